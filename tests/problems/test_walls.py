"""WallProfile: tables, functions, CSV files, and one clear error per bad input."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lcpbench.errors import ProblemError
from lcpbench.problems.scenes import ActuatorScene
from lcpbench.problems.walls import WallProfile, load_profile_csv

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples" / "profiles"


def test_linear_table_interpolates_and_has_its_segment_slopes():
    p = WallProfile.from_table([0, 10, 30], [3, 2, 4], "linear")
    assert p(5.0) == pytest.approx(2.5)
    assert p.slope(5.0) == pytest.approx(-0.1)
    assert p.slope(20.0) == pytest.approx(0.1)
    assert p(40.0) == pytest.approx(4.0) and p.slope(40.0) == 0.0  # continued flat


def test_a_table_is_fixed_once_built_and_a_wall_moved_under_the_pin_is_refused():
    # the profile copies the caller's points: editing them afterwards moves no wall, and
    # a profile built from the edited points (through the pin line) is refused, although
    # a scene with the first one passed its check before
    x, y = np.array([-40.0, 0.0, 40.0]), np.full(3, 3.0)
    p = WallProfile.from_table(x, y, "linear")
    ActuatorScene(150, 3.0, wall_profile=p).chain()
    y[:] = -1.0
    assert p(0.0) == pytest.approx(3.0) and p(20.0) == pytest.approx(3.0)
    ActuatorScene(150, 3.0, wall_profile=p).chain()
    with pytest.raises(ProblemError, match="pin"):
        ActuatorScene(150, 3.0, wall_profile=WallProfile.from_table(x, y, "linear")).chain()


@pytest.mark.parametrize("kind", ["pchip", "cubic"])
def test_smooth_tables_reproduce_a_straight_line(kind):
    x = np.linspace(0, 30, 7)
    p = WallProfile.from_table(x, 2 + 0.05 * x, kind)
    t = np.linspace(0, 30, 101)
    np.testing.assert_allclose(p(t), 2 + 0.05 * t, atol=1e-12)
    np.testing.assert_allclose(p.slope(t), 0.05, atol=1e-12)
    np.testing.assert_allclose(p.curvature(t), 0.0, atol=1e-10)


def test_function_slope_by_central_differences_matches_the_derivative():
    p = WallProfile.from_function(lambda x: 3 - 0.8 * np.exp(-((x - 14) / 3) ** 2))
    t = np.linspace(0, 30, 61)
    exact = 0.8 * 2 * (t - 14) / 9 * np.exp(-((t - 14) / 3) ** 2)
    np.testing.assert_allclose(p.slope(t), exact, atol=1e-9)


def test_flat_and_mirror():
    p = WallProfile.flat(3.0)
    assert p(12.0) == 3.0 and p.slope(12.0) == 0.0
    assert p.mirrored()(12.0) == -3.0


@pytest.mark.parametrize("x, y, kind, match", [
    ([0, 10, 30], [3, np.nan, 3], "pchip", "not finite"),
    ([0, 10, np.inf], [3, 3, 3], "pchip", "not finite"),
    ([0, 10, 10, 30], [3, 3, 3, 3], "pchip", "strictly increasing"),
    ([0, 20, 10], [3, 3, 3], "linear", "strictly increasing"),
    ([0], [3], "pchip", "at least 2 points"),
    ([0, 30], [3, 3, 3], "pchip", "same length"),
    ([0, 30], [3, 3], "spline", "kind must be"),
])
def test_bad_tables_give_one_problem_error(x, y, kind, match):
    with pytest.raises(ProblemError, match=match):
        WallProfile.from_table(x, y, kind)


def test_a_profile_crossing_the_pin_line_is_refused():
    with pytest.raises(ProblemError, match="wall_profile.*pin line"):
        ActuatorScene(wall_profile=WallProfile.from_table([0, 30], [3, -1], "linear"))
    with pytest.raises(ProblemError, match="wall_profile.*pin line"):
        ActuatorScene(wall_profile=WallProfile.from_table([0, 15, 30], [3, 0, 3], "linear"))
    with pytest.raises(ProblemError, match="lower_profile.*pin line"):
        ActuatorScene(channel=True, wall_profile=WallProfile.flat(3.0),
                      lower_profile=WallProfile.from_table([0, 30], [-1, 0.5], "linear"))


def test_scenes_sharing_a_profile_sample_it_once_and_a_bad_one_is_refused_each_time():
    """The pin-line check of a profile samples it once per chain range and side; scenes
    that share the profile do not sample it again, and a profile that fails is refused
    by every scene that uses it."""
    calls = []

    def h(x):
        calls.append(np.size(x))
        return 3.0 + 0.0 * np.asarray(x, float)

    good = WallProfile.from_function(h, lambda x: 0.0 * np.asarray(x, float))
    first = ActuatorScene(theta=120, wall_profile=good)
    sampled = len(calls)
    assert sampled >= 1
    for theta in (130, 140, 150):
        ActuatorScene(theta=theta, wall_profile=good)
    assert len(calls) == sampled
    ActuatorScene(theta=120, length=first.length / 2, wall_profile=good)  # another range
    assert len(calls) > sampled
    bad = WallProfile.from_table([0, 15, 30], [3, 0, 3], "linear")
    for theta in (120, 130):
        with pytest.raises(ProblemError, match="wall_profile.*pin line"):
            ActuatorScene(theta=theta, wall_profile=bad)


def test_a_profile_must_cover_the_chain():
    with pytest.raises(ProblemError, match="cover the chain's x range"):
        ActuatorScene(wall_profile=WallProfile.from_table([0, 20], [3, 3]))
    with pytest.raises(ProblemError, match="cover"):  # theta > 180: the arc reaches x < 0
        ActuatorScene(theta=250, wall_profile=WallProfile.from_table([0, 30], [9, 9]))


def test_scene_field_types():
    with pytest.raises(ProblemError, match="wall_profile must be a WallProfile"):
        ActuatorScene(wall_profile="stenosis.csv")
    with pytest.raises(ProblemError, match="lower_profile needs channel"):
        ActuatorScene(wall_profile=WallProfile.flat(3.0),
                      lower_profile=WallProfile.flat(-3.0))


def test_csv_loader(tmp_path):
    p = load_profile_csv(EXAMPLES / "stenosis.csv")
    assert p(14.0) == pytest.approx(2.2) and p(0.0) == pytest.approx(3.0, abs=1e-6)
    f = tmp_path / "w.csv"
    f.write_text("x,y\n# comment\n0,3\n\n30,4\n")
    assert load_profile_csv(f, "linear")(15.0) == pytest.approx(3.5)


@pytest.mark.parametrize("text, match", [
    ("x,y\n0,3\n10,nan\n30,3\n", "not finite"),
    ("x,y\n0,3\n10,inf\n30,3\n", "not finite"),
    ("0,3\n10,3\n30,3\n", "header"),
    ("x,y\n0,3\n", "at least 2 points"),
    ("x,y\n0,3\n10,a\n", "not two numbers"),
    ("x,y\n0,3,1\n30,3\n", "must be x,y"),
    ("", "empty"),
    ("x,y\n30,3\n0,3\n", "strictly increasing"),
])
def test_bad_csv_files(tmp_path, text, match):
    f = tmp_path / "bad.csv"
    f.write_text(text)
    with pytest.raises(ProblemError, match=match):
        load_profile_csv(f)


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "lcpbench.cli", *args], capture_output=True,
                          text=True, timeout=300)


def test_cli_solves_a_profile_and_refuses_a_bad_file(tmp_path):
    out = _cli("solve", "--links", "40", "--wall-profile", str(EXAMPLES / "stenosis.csv"))
    assert out.returncode == 0, out.stderr
    assert "wall profile stenosis.csv" in out.stdout
    bad = tmp_path / "nan.csv"
    bad.write_text("x,y\n0,3\n10,nan\n30,3\n")
    out = _cli("solve", "--wall-profile", str(bad))
    assert out.returncode == 2
    assert out.stderr.count("\n") == 1 and "--wall-profile" in out.stderr
    assert "Traceback" not in out.stderr
    cross = tmp_path / "cross.csv"
    cross.write_text("x,y\n0,3\n30,-1\n")
    out = _cli("solve", "--wall-profile", str(cross))
    assert out.returncode == 2 and "pin line" in out.stderr
    out = _cli("solve", "--lower-profile", str(EXAMPLES / "ramp.csv"))
    assert out.returncode == 2 and "--lower-profile needs" in out.stderr


def test_flat_scenes_keep_their_store_key_and_json():
    from lcpbench.bench.grid import scene_key

    key = scene_key(ActuatorScene(theta=120, height=2.5, links=30))
    assert "profile" not in key
    with pytest.raises(ProblemError, match="wall_profile"):
        scene_key(ActuatorScene(wall_profile=WallProfile.flat(3.0)))


# -- bounded input, one clear error (issue 36) ---------------------------------------------
def _cli_main(capsys, *args):
    """The CLI in this process: its status and stderr (a refusal is one line, status 2)."""
    from lcpbench.cli import main

    code = main(list(args))
    return code, capsys.readouterr().err


def _refused(capsys, *args) -> str:
    code, err = _cli_main(capsys, *args)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith("lcpbench: error: ")
    return err


def test_a_device_profile_is_refused_unread(tmp_path, capsys):
    with pytest.raises(ProblemError, match="wall_profile: '/dev/zero': is a device"):
        load_profile_csv("/dev/zero")
    err = _refused(capsys, "solve", "--wall-profile", "/dev/zero")
    assert "--wall-profile: '/dev/zero': is a device, not a regular file" in err
    folder = tmp_path / "dir.csv"
    folder.mkdir()
    with pytest.raises(ProblemError, match="is a directory, not a regular file"):
        load_profile_csv(folder)


def test_a_profile_csv_over_the_cap_is_refused_unread(tmp_path, capsys):
    from lcpbench.problems import walls

    big = tmp_path / "big.csv"
    with open(big, "wb") as fh:  # sparse: 2 GB of NUL bytes cost no disk
        fh.write(b"x,y\n0,3\n30,3\n")
        fh.truncate(2 * 10**9)
    with pytest.raises(ProblemError) as info:
        load_profile_csv(big)
    msg = str(info.value)
    assert f"takes {2 * 10**9} bytes" in msg
    assert f"at most {walls.MAX_PROFILE_BYTES} bytes (16 MiB" in msg and "\n" not in msg
    assert walls.MAX_PROFILE_BYTES == 16 * 2**20
    err = _refused(capsys, "solve", "--wall-profile", str(big))
    assert "--wall-profile" in err and "at most 16777216 bytes" in err


def test_a_profile_csv_that_is_not_utf8_is_one_line(tmp_path, capsys):
    bad = tmp_path / "latin1.csv"
    bad.write_bytes("x (mm),höhe\n0,3\n30,3\n".encode("latin-1"))
    with pytest.raises(ProblemError, match="wall_profile: latin1.csv is not UTF-8 text"):
        load_profile_csv(bad)
    err = _refused(capsys, "solve", "--wall-profile", str(bad))
    assert "--wall-profile: latin1.csv is not UTF-8 text" in err


def test_a_profile_csv_with_a_utf8_bom_and_a_huge_field(tmp_path):
    bom = tmp_path / "bom.csv"
    bom.write_bytes("x,y\n0,3\n30,3\n".encode("utf-8-sig"))  # as spreadsheets write it
    assert load_profile_csv(bom, "linear")(15.0) == pytest.approx(3.0)
    huge = tmp_path / "huge.csv"
    huge.write_text("x,y\n0,3\n" + "1" * 200_000 + ",3\n")  # past csv's field limit
    with pytest.raises(ProblemError, match="huge.csv is not a CSV of x,y rows"):
        load_profile_csv(huge)


def _bump(x):
    return 3 - 0.8 * np.exp(-((x - 14) / 3) ** 2)


def _raises(x):
    raise RuntimeError("lookup\ntable missing")


@pytest.mark.parametrize("height, match", [
    (_raises, "the height function raised RuntimeError: lookup table missing"),
    (lambda x: 1 / 0, "the height function raised ZeroDivisionError"),
    (lambda x: "3 mm", "the height function must return numbers .* returned '3 mm'"),
    (lambda x: None, "the height function must return numbers .* returned None"),
    (lambda x: [3.0, 3.0], "the height function must return one number per x"),
])
def test_a_user_function_that_raises_or_returns_no_numbers_is_one_error(height, match):
    profile = WallProfile.from_function(height, name="mine")
    with pytest.raises(ProblemError, match=f"wall_profile 'mine': {match}") as info:
        ActuatorScene(theta=150, wall_profile=profile, links=20)
    assert "\n" not in str(info.value)


def test_a_user_slope_that_raises_is_one_error_from_solve():
    import lcpbench

    profile = WallProfile.from_function(_bump, slope=_raises, name="bump")
    scene = ActuatorScene(theta=150, wall_profile=profile, links=20)  # h itself is fine
    with pytest.raises(ProblemError, match="wall_profile 'bump': the slope function raised"):
        lcpbench.solve(scene)


def test_extremes_are_the_walls_lowest_and_highest_point_on_the_grid_kept_per_range():
    # theory: h = 3 - 0.5 sin(pi x / 30) on [0, 30] is lowest (2.5 mm) at x = 15, a point
    # of the 2001-point grid, and highest (3 mm) at the ends
    calls = []

    def h(x):
        calls.append(1)
        return 3.0 - 0.5 * np.sin(np.pi * np.asarray(x, float) / 30.0)

    p = WallProfile.from_function(h)
    low, high = p.extremes(0.0, 30.0)
    assert low == pytest.approx(2.5, abs=1e-15) and high == pytest.approx(3.0, abs=1e-15)
    seen = len(calls)
    assert p.extremes(0.0, 30.0) == (low, high) and len(calls) == seen  # kept
    assert p.extremes(0.0, 15.0)[1] == pytest.approx(3.0) and len(calls) > seen  # per range
