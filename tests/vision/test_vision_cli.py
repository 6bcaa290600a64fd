"""``lcpbench vision ...``: bad input is exit 2 and one line on stderr; the
measure JSON, the calibrate --fit string that ``solve`` accepts, render and compare."""

import json
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest

from lcpbench.cli import main
from lcpbench.vision.render import BACKGROUND


@pytest.fixture(scope="module")
def photo(tmp_path_factory, rendered):
    d = tmp_path_factory.mktemp("vision-cli")
    img, truth = rendered(100, 14.0, seed=100, nuisances=True)
    path = d / "u100.png"
    cv2.imwrite(str(path), img)
    cal = d / "u100.calib.json"
    cal.write_text(json.dumps(truth["calibration"]))
    return d, path, cal, img, truth


def _one_line_error(capsys, argv, match):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("lcpbench: error:"), err
    assert "Traceback" not in err and match in err, err


def test_missing_marker(photo, capsys):
    d, _, cal, img, truth = photo
    q = np.array(truth["marker_corners_px"])  # corners in the undistorted image: cover wide
    blank = img.copy()
    cv2.fillConvexPoly(blank, np.round(q.mean(0) + 1.5 * (q - q.mean(0))).astype(np.int32),
                       (BACKGROUND,) * 3)
    cv2.imwrite(str(d / "nomarker.png"), blank)
    _one_line_error(capsys, ["vision", "measure", str(d / "nomarker.png")], "ArUco")


def test_no_bearings(photo, capsys):
    d, _, _, img, truth = photo
    blank = img.copy()
    for p in truth["pins_px"]:  # the lens moves them by < 20 px: paint 5 mm around
        cv2.circle(blank, tuple(int(v) for v in np.round(p)), 5 * 14, (BACKGROUND,) * 3, -1)
    cv2.imwrite(str(d / "nobearings.png"), blank)
    _one_line_error(capsys, ["vision", "measure", str(d / "nobearings.png")], "bearings")


def test_empty_segmentation(photo, capsys):
    d, _, _, img, _ = photo
    grey = cv2.cvtColor(cv2.cvtColor(img, cv2.COLOR_BGR2GRAY), cv2.COLOR_GRAY2BGR)
    cv2.imwrite(str(d / "grey.png"), grey)
    _one_line_error(capsys, ["vision", "measure", str(d / "grey.png")], "segmentation is empty")


def test_not_an_image(tmp_path, capsys):
    f = tmp_path / "photo.jpg"
    f.write_text("hello")
    _one_line_error(capsys, ["vision", "measure", str(f)], "not an image")


def test_calibration_of_the_wrong_shape(photo, tmp_path, capsys):
    _, path, _, _, _ = photo
    cal = tmp_path / "cal.json"
    cal.write_text(json.dumps({"camera_matrix": [[1, 2, 3, 4]], "dist_coeffs": [0, 0, 0, 0, 0]}))
    _one_line_error(capsys, ["vision", "measure", str(path), "--calib", str(cal)], "3x3")


def test_missing_subcommand_and_bad_options(photo, capsys):
    _, path, _, _, _ = photo
    _one_line_error(capsys, ["vision"], "SUBCOMMAND")
    _one_line_error(capsys, ["vision", "measure", str(path), "--hsv-lower", "1,2",
                             "--hsv-upper", "20,255,255"], "H,S,V")
    _one_line_error(capsys, ["vision", "compare", str(path), "--wall-face", "5"], "--theta")
    _one_line_error(capsys, ["vision", "compare", str(path), "--theta", "120"], "--wall-face")
    _one_line_error(capsys, ["vision", "compare", str(path), "--theta", "120", "--wall-face",
                             "5", "--height", "3.5"], "--height")


def test_measure_json(photo, capsys):
    _, path, cal, _, truth = photo
    assert main(["vision", "measure", str(path), "--calib", str(cal), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["middle"]["theta_deg"] == pytest.approx(truth["theta_deg"], rel=0.015)
    assert out["px_per_mm"] == pytest.approx(truth["px_per_mm"], rel=1e-3)


def test_measure_plot(photo, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    _, path, cal, _, _ = photo
    out = tmp_path / "overlay.png"
    assert main(["vision", "measure", str(path), "--calib", str(cal), "--plot", str(out)]) == 0
    assert cv2.imread(str(out)) is not None


def test_calibrate_writes_a_fit_that_solve_accepts(tmp_path, capsys):
    from lcpbench.vision.render import Nuisances, render_unconstrained

    # three photographs of a known calibration theta = 0.8 P + 10 (P = 50, 100, 150 kPa),
    # every nuisance but the lens (each rendered camera would need its own --calib)
    files, ps = [], [50.0, 100.0, 150.0]
    for p in ps:
        nz = Nuisances.all_on(int(p))
        nz.distort = False
        img, _ = render_unconstrained(0.8 * p + 10, px_per_mm=10.0, nuisances=nz)
        f = tmp_path / f"p{int(p)}.png"
        cv2.imwrite(str(f), img)
        files.append(str(f))
    fit_json, plot = tmp_path / "fit.json", tmp_path / "fit.png"
    csv = tmp_path / "pressures.csv"
    csv.write_text("file,pressure\n" + "".join(f"{os.path.basename(f)},{p}\n"
                                               for f, p in zip(files, ps)))
    assert main(["vision", "calibrate", "--csv", str(csv), "--out", str(fit_json),
                 "--plot", str(plot)]) == 0
    out = capsys.readouterr().out
    fit = json.loads(fit_json.read_text())
    assert fit["slope"] == pytest.approx(0.8, rel=0.01)
    assert fit["intercept"] == pytest.approx(10.0, abs=1.0)
    assert fit["slope_ci95"][0] <= fit["slope"] <= fit["slope_ci95"][1]
    assert f"--fit {fit['fit']}" in out
    assert main(["solve", "--pressure", "120", "--fit", fit["fit"], "--height", "5",
                 "--links", "40"]) in (0, 1)
    err = capsys.readouterr().err
    assert "error" not in err


def test_render_then_compare(tmp_path, capsys):
    img = tmp_path / "c.png"
    assert main(["vision", "render", "--theta", "120", "--wall-face", "5", "--px-per-mm", "11",
                 "--out", str(img)]) == 0
    capsys.readouterr()
    assert main(["vision", "compare", str(img), "--calib", str(tmp_path / "c.calib.json"),
                 "--wall-face", "5", "--theta", "120", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["mean_distance_mm"] < 0.05 and d["contact_force_n"] > 0
    truth = json.loads((tmp_path / "c.json").read_text())
    assert d["contact_force_n"] == pytest.approx(truth["contact_force_n"], rel=1e-9)
    # height is the centre-line height, as in solve: the wall face less the radius 1.5 mm
    assert (d["wall_face_mm"], d["height_mm"]) == (5.0, 3.5)
    assert main(["vision", "compare", str(img), "--calib", str(tmp_path / "c.calib.json"),
                 "--height", "3.5", "--theta", "120", "--json"]) == 0
    same = json.loads(capsys.readouterr().out)
    assert same["contact_force_n"] == d["contact_force_n"]
    pytest.importorskip("matplotlib")
    picture = tmp_path / "compare.png"  # the figure draws the wall faces it was given
    assert main(["vision", "compare", str(img), "--calib", str(tmp_path / "c.calib.json"),
                 "--wall-face", "5", "--theta", "120", "--plot", str(picture)]) == 0
    assert picture.stat().st_size > 10_000
    capsys.readouterr()
    assert main(["solve", "--theta", "120", "--height", "3.5", "--links", "200", "--channel",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["total_force"] == pytest.approx(
        d["contact_force_n"], rel=1e-9)


def test_import_lcpbench_does_not_load_opencv():
    code = ("import sys, lcpbench, lcpbench.cli; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('cv2', 'skimage') or m.startswith('lcpbench.vision.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=os.environ | {"PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.stdout.strip() in ("[]", "['lcpbench.vision.commands', 'lcpbench.vision.errors']")


def test_measure_with_a_user_hsv_range(photo, capsys):
    _, path, cal, _, truth = photo
    # the tube is orange (OpenCV hue ~ 11): a hand-set range around it
    assert main(["vision", "measure", str(path), "--calib", str(cal), "--json",
                 "--hsv-lower", "0,70,50", "--hsv-upper", "30,255,255"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["hsv_range"] == [[0, 70, 50], [30, 255, 255]]
    assert out["middle"]["theta_deg"] == pytest.approx(truth["theta_deg"], rel=0.015)


def test_measure_text_gives_the_joint_fit_and_its_confidence(photo, capsys):
    _, path, cal, _, truth = photo
    assert main(["vision", "measure", str(path), "--calib", str(cal)]) == 0
    out, err = capsys.readouterr()
    assert "joint fit" in out and "+-" in out and "residual" in out and "circle fits" in out
    assert "no warning" in out and err == ""
    assert main(["vision", "measure", str(path), "--calib", str(cal), "--equal-sections",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["method"] == "joint fit (equal sections)"
    assert d["middle"]["theta_deg"] == pytest.approx(truth["theta_deg"], rel=0.002)


def test_a_doubtful_measurement_says_so_on_stderr(photo, tmp_path, capsys):
    d, _, cal, img, truth = photo
    # a second, differently bent tube of the same colour over the first one's end:
    # the chain of three arcs cannot explain the centerline
    from lcpbench.vision.render import TUBE_BGR

    bad = img.copy()
    p = np.array(truth["pins_px"])
    mid = (p[0] + p[1]) / 2
    cv2.ellipse(bad, tuple(int(v) for v in mid), (140, 60), 0, 200, 340, TUBE_BGR, 14)
    f = tmp_path / "bad.png"
    cv2.imwrite(str(f), bad)
    assert main(["vision", "measure", str(f), "--calib", str(cal), "--json"]) == 0
    out, err = capsys.readouterr()
    res = json.loads(out)
    assert res["warnings"] and err.count("lcpbench: warning:") == len(res["warnings"])


def test_render_tube_hue(tmp_path, capsys):
    img = tmp_path / "g.png"
    assert main(["vision", "render", "--theta", "34", "--length", "25.15", "--tube-hue", "120",
                 "--nuisances", "none", "--out", str(img)]) == 0
    truth = json.loads((tmp_path / "g.json").read_text())
    b, g, r = truth["tube_bgr"]
    assert g > 2 * max(b, r)  # green
