"""End to end on rendered photographs with every nuisance on (the paper's Fig. 19
experiment on 3-D printed ground truth): the issue's accuracy targets."""

import numpy as np
import pytest

from lcpbench.vision.measure import measure

# a subset of the 10-180 degree sweep in the default run, at resolutions across
# 10-25 px/mm; the full sweep is the slow test below and benchmarks/vision_accuracy.py
SUBSET = [(10, 12.0), (45, 10.0), (100, 14.0), (150, 11.0), (180, 12.0)]


def _errors(rendered, theta, ppm, seed):
    img, truth = rendered(theta, ppm, seed=seed, nuisances=True)
    m = measure(img, calibration=truth["calibration"])
    mid = m.sections[m.middle]
    e_theta = abs(mid.theta_deg - truth["theta_deg"]) / truth["theta_deg"]
    e_len = abs(mid.arc_length_mm - truth["arc_length_mm"]) / truth["arc_length_mm"]
    return m, truth, e_theta, e_len


def _check(errs):
    et, el = np.array(errs).T
    assert et.mean() <= 0.005 and el.mean() <= 0.005, (et, el)
    assert et.max() <= 0.015 and el.max() <= 0.015, (et, el)


def test_middle_section_accuracy_on_a_subset(rendered):
    errs = []
    for theta, ppm in SUBSET:
        m, truth, et, el = _errors(rendered, theta, ppm, seed=theta)
        errs.append((et, el))
        # the intermediate results against the truth too
        assert m.px_per_mm == pytest.approx(ppm, rel=1e-3)
        assert m.level_deg == pytest.approx(truth["rotation_deg"], abs=0.05)
        np.testing.assert_allclose(m.inflection_points_mm, truth["inflection_points_mm"],
                                   atol=0.15)
        assert m.sections[m.middle].radius_mm == pytest.approx(truth["radius_mm"], rel=0.015)
    _check(errs)


def test_measurement_json_has_the_issues_keys(rendered):
    img, truth = rendered(100, 14.0, seed=100, nuisances=True)
    d = measure(img, calibration=truth["calibration"]).to_dict()
    for key in ("px_per_mm", "level_deg", "centerline_mm", "inflection_points_mm", "sections",
                "middle"):
        assert key in d
    assert len(d["sections"]) == 3 and len(d["inflection_points_mm"]) == 2
    for s in d["sections"]:
        assert {"theta_deg", "arc_length_mm", "radius_mm", "center_mm"} <= set(s)
    assert set(d["middle"]) >= {"theta_deg", "arc_length_mm"}
    c = np.array(d["centerline_mm"])
    assert c.ndim == 2 and c.shape[1] == 2
    # origin at the left pin, x along the pin line: the centerline runs 0 -> pin span
    assert 0 < c[0, 0] < 10 and d["pin_span_mm"] - 10 < c[-1, 0] < d["pin_span_mm"]


@pytest.mark.slow
def test_middle_section_accuracy_full_sweep(rendered):
    errs = []
    for theta in range(10, 181, 10):
        ppm = 10.0 + (theta * 7) % 16  # resolutions over 10-25 px/mm
        errs.append(_errors(rendered, theta, ppm, seed=theta)[2:])
    _check(errs)


# -- the joint fit and its confidence (issue 41) ------------------------------------
def _render(theta, length, ppm, seed, hue=None, noise=None):
    from lcpbench.vision.render import Nuisances, render_unconstrained, tube_colour

    nz = Nuisances.all_on(seed)
    if noise is not None:
        nz.noise = noise
    kw = {} if hue is None else {"tube_bgr": tube_colour(hue)}
    return render_unconstrained(theta, length=length, px_per_mm=ppm, nuisances=nz, **kw)


@pytest.mark.parametrize("ppm, seed", [(10.0, 500), (13.0, 501), (22.0, 502)])
def test_the_issues_hard_case_green_tube(ppm, seed):
    """θ = 34.0°, ℓ = 25.15 mm, a green tube: 5.5 % off in silence on main 308f03e
    (held-out render). Now within 1 % or a warning, and here within 0.2 %."""
    img, truth = _render(34.0, 25.15, ppm, seed, hue=120)
    m = measure(img, calibration=truth["calibration"])
    mid = m.sections[m.middle]
    err = max(abs(mid.theta_deg / 34.0 - 1), abs(mid.arc_length_mm / 25.15 - 1))
    assert err <= 0.01 or m.warnings
    assert err <= 0.002 and not m.warnings, (err, m.warnings)
    np.testing.assert_allclose(m.inflection_points_mm, truth["inflection_points_mm"], atol=0.05)
    assert m.confidence.length_spread < 0.01


def test_standard_errors_cover_the_truth_on_noisy_renders():
    """Renders with three times the default sensor noise (σ = 12 grey levels): the
    middle section's θ and ℓ within 2 s.e. of the truth in at least 7 of 8 images."""
    inside = []
    for i, theta in enumerate((10.0, 20.0, 34.0, 60.0, 90.0, 120.0, 150.0, 175.0)):
        img, truth = _render(theta, 30.0, (10.0, 13.0, 17.0, 22.0)[i % 4], 70 + i, noise=12.0)
        mid = measure(img, calibration=truth["calibration"]).sections[1]
        inside.append((abs(mid.theta_deg - theta) < 2 * mid.theta_se_deg,
                       abs(mid.arc_length_mm - 30.0) < 2 * mid.arc_length_se_mm))
    assert np.sum(inside, axis=0).min() >= 7, inside


def test_a_hidden_stretch_of_tube_is_within_one_percent_or_warns(tmp_path):
    """A band of background painted across the middle section (a shadow or a
    finger): the centerline has a gap; the measurement stays within 1 % or warns."""
    import math

    import cv2

    from lcpbench.vision.render import BACKGROUND, arc_sections

    img, truth = _render(34.0, 25.15, 14.0, 7, noise=4.0)
    img = img.copy()
    c, _ = arc_sections(34.0, 25.15, 3)
    a = math.radians(truth["rotation_deg"])
    for frac in (0.4, 0.55):  # two discs of 2.5 mm radius on the middle section
        x, y = c[int(frac * len(c))]
        p = np.array(truth["pins_px"][0]) + 14.0 * np.array(
            [x * math.cos(a) + y * math.sin(a), x * math.sin(a) - y * math.cos(a)])
        cv2.circle(img, tuple(int(v) for v in p), 35, (BACKGROUND,) * 3, -1)
    m = measure(img, calibration=truth["calibration"])
    mid = m.sections[m.middle]
    err = max(abs(mid.theta_deg / 34.0 - 1), abs(mid.arc_length_mm / 25.15 - 1))
    assert err <= 0.01 or m.warnings, err
    if m.warnings:  # the overlay draws them too
        pytest.importorskip("matplotlib")
        from lcpbench.vision.plots import plot_measurement

        plot_measurement(m, tmp_path / "warned.png")
        assert (tmp_path / "warned.png").stat().st_size > 0


def test_json_has_the_confidence_and_the_circle_fits(rendered):
    img, truth = rendered(100, 14.0, seed=100, nuisances=True)
    d = measure(img, calibration=truth["calibration"], equal_sections=True).to_dict()
    assert d["method"] == "joint fit (equal sections)"
    assert len({round(s["theta_deg"], 9) for s in d["sections"]}) == 1
    conf = d["confidence"]
    for key in ("rms_px", "rms_mm", "theta_se_deg", "arc_length_se_mm", "length_spread",
                "warnings"):
        assert key in conf
    assert conf["rms_px"] == pytest.approx(conf["rms_mm"] * d["px_per_mm"])
    assert d["warnings"] == conf["warnings"] == []
    assert d["middle"]["theta_se_deg"] > 0 and d["middle"]["arc_length_se_mm"] > 0
    cf = d["circle_fits"]
    assert len(cf["sections"]) == 3 and len(cf["inflection_points_mm"]) == 2
    assert cf["middle"]["theta_deg"] == pytest.approx(100, rel=0.01)
