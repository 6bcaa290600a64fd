"""The joint fit of the chain of arcs on exact and noisy curves: it recovers the
shape the curve was drawn from (the renderer's arc_sections, or arcs of chosen
unequal θ and ℓ), its standard errors cover the truth at the stated rate, and a
centerline the chain cannot explain raises a warning."""

import math

import numpy as np
import pytest

from lcpbench.vision.errors import VisionError
from lcpbench.vision.jointfit import chain, check, fit_chain, signed_distance
from lcpbench.vision.measure import analyse
from lcpbench.vision.render import arc_sections


def _visible(c, clear=4.5):
    """The centerline without the parts the bearings hide (as the pipeline sees it)."""
    keep = (np.hypot(*c.T) > clear) & (np.hypot(*(c - c[-1]).T) > clear)
    return c[keep]


def test_chain_ends_on_the_pins_with_the_lengths_and_angles_asked():
    arcs = chain([0.3, 1.2, 0.7], [1.0, 2.0, 1.5], +1, (1.0, 2.0), (31.0, -3.0))
    np.testing.assert_allclose(arcs[0].start, [1.0, 2.0], atol=1e-12)
    np.testing.assert_allclose(arcs[-1].end, [31.0, -3.0], atol=1e-12)
    np.testing.assert_allclose([a.theta for a in arcs], [0.3, 1.2, 0.7], rtol=1e-12)
    lens = np.array([a.length for a in arcs])
    np.testing.assert_allclose(lens / lens[-1], [1 / 1.5, 2 / 1.5, 1.0], rtol=1e-12)
    # tangent-continuous, alternating in sense
    for a, b in zip(arcs, arcs[1:]):
        np.testing.assert_allclose(a.end, b.start, atol=1e-12)
        assert a.phi + a.kappa * a.length == pytest.approx(b.phi, abs=1e-12)
        assert a.kappa * b.kappa < 0


def test_signed_distance_is_the_offset_along_the_normal():
    arcs = chain([0.8, 0.8, 0.8], [1.0, 1.0, 1.0], -1, (0.0, 0.0), (60.0, 0.0))
    for a in arcs:
        s = np.linspace(0.1, 0.9, 7) * a.length
        p = a.point(s)
        ang = a.phi + a.kappa * s
        left = np.column_stack([-np.sin(ang), np.cos(ang)])
        np.testing.assert_allclose(signed_distance(p, arcs), 0, atol=1e-9)
        np.testing.assert_allclose(signed_distance(p + 0.2 * left, arcs), 0.2, atol=1e-9)
        np.testing.assert_allclose(signed_distance(p - 0.3 * left, arcs), -0.3, atol=1e-9)


@pytest.mark.parametrize("theta", [10.0, 34.0, 90.0, 175.0, 180.0])
@pytest.mark.parametrize("equal", [False, True])
def test_exact_renderer_curves_round_trip(theta, equal):
    c, knots = arc_sections(theta, 25.15, 3)
    fit = fit_chain(_visible(c)[::3], c[-1, 0], 3, equal_sections=equal, px_per_mm=15.0)
    np.testing.assert_allclose(fit.theta_deg, theta, rtol=1e-5)
    np.testing.assert_allclose(fit.arc_length_mm, 25.15, rtol=1e-5)
    np.testing.assert_allclose(fit.inflection_points, knots, atol=1e-4)
    assert fit.confidence.rms_mm < 1e-5 and fit.confidence.outliers == 0


def test_unequal_sections_and_five_of_them():
    # started from the per-section circle fits, as measure() does
    th, ln = np.radians([25.0, 60.0, 40.0, 80.0, 30.0]), np.array([22.0, 26.0, 25.0, 28.0, 23.0])
    arcs = chain(th, ln, -1, (0.0, 0.0), (1.0, 0.0))            # shape only: rescale below
    span = 1.0 / arcs[0].length * ln[0]
    arcs = chain(th, ln, -1, (0.0, 0.0), (span, 0.0))
    np.testing.assert_allclose([a.length for a in arcs], ln, rtol=1e-12)
    pts = np.vstack([a.point(np.linspace(0, a.length, 300)) for a in arcs])
    fit, _, _ = analyse(_visible(pts), span, 5)
    np.testing.assert_allclose(np.radians(fit.theta_deg), th, rtol=1e-6)
    np.testing.assert_allclose(fit.arc_length_mm, ln, rtol=1e-6)
    assert fit.confidence.length_spread == pytest.approx(np.ptp(ln) / ln.mean(), rel=1e-5)


def test_standard_errors_cover_the_truth_on_noisy_curves():
    """White noise of 0.3 px on the centerline and 0.08 px on each pin (the stated
    pin uncertainty): |error| < 2 s.e. in about 95 % of the trials, < 1 s.e. in 68 %."""
    rng = np.random.default_rng(41)
    ppm, z = 12.0, []
    for trial in range(40):
        theta = [12.0, 34.0, 90.0, 160.0][trial % 4]
        c, _ = arc_sections(theta, 25.15, 3, spacing=1 / ppm)
        pins = rng.normal(0, 0.08 / ppm, (2, 2))
        # the pipeline's frame is the measured pins': move the curve by the pin error
        a, b = c[0] - pins[0], c[-1] - pins[1]
        ang = math.atan2(b[1] - a[1], b[0] - a[0])
        rot = np.array([[math.cos(ang), math.sin(ang)], [-math.sin(ang), math.cos(ang)]])
        pts = (_visible(c) - a) @ rot.T + rng.normal(0, 0.3 / ppm, (len(_visible(c)), 2))
        fit = fit_chain(pts, float(np.hypot(*(b - a))), 3, px_per_mm=ppm)
        se = fit.confidence
        z.append([(fit.theta_deg[1] - theta) / se.theta_se_deg[1],
                  (fit.arc_length_mm[1] - 25.15) / se.arc_length_se_mm[1]])
    z = np.abs(np.array(z))
    cover2, cover1 = (z < 2).mean(axis=0), (z < 1).mean(axis=0)
    assert np.all(cover2 >= 0.85), cover2
    assert np.all((cover1 >= 0.5) & (cover1 <= 0.9)), cover1


def test_a_centerline_that_is_not_a_chain_of_arcs_warns():
    # the middle third flattened against a wall at y = 3 mm (a constrained actuator)
    c, _ = arc_sections(120.0, 30.0, 3)
    c = c.copy()
    c[:, 1] = np.minimum(c[:, 1], 3.0)
    fit, circles, _ = analyse(_visible(c)[::4], c[-1, 0], 3, px_per_mm=12.0)
    assert any("fit the centerline poorly" in w for w in fit.confidence.warnings)


def test_a_bent_centerline_is_within_one_percent_or_warns():
    """A local defect (a 0.3 mm bump over 4 mm of the middle section, as a shadow or
    a wrinkle would make): never more than 1 % off in silence."""
    for theta in (15.0, 34.0, 90.0):
        for where in (0.35, 0.5, 0.62):
            c, _ = arc_sections(theta, 25.15, 3)
            s = np.linspace(0, 1, len(c))
            c = c + 0.3 * np.exp(-((s - where) * len(c) * 0.01 / 2.0) ** 2)[:, None] * [0, 1]
            fit, circles, _ = analyse(_visible(c)[::4], c[-1, 0], 3, px_per_mm=15.0)
            err = max(abs(fit.theta_deg[1] / theta - 1), abs(fit.arc_length_mm[1] / 25.15 - 1))
            assert err <= 0.01 or fit.confidence.warnings, (theta, where, err)


def test_check_names_each_threshold():
    c, _ = arc_sections(34.0, 25.15, 3)
    fit = fit_chain(_visible(c)[::3], c[-1, 0], 3, px_per_mm=12.0)
    assert check(fit, 1, 3.0, 12.0, (34.0, 25.15)) == []
    assert "differ on the middle section" in check(fit, 1, 3.0, 12.0, (32.13, 23.81))[0]
    fit.confidence.length_spread = 0.092  # the 25.72, 23.81, 26.03 mm
    assert any("section lengths differ by 9.2 %" in w for w in check(fit, 1, 3.0, 12.0))


def test_too_few_points_is_an_error():
    with pytest.raises(VisionError, match="too few"):
        fit_chain(np.zeros((5, 2)), 10.0, 3)


def test_a_section_the_centerline_does_not_show_has_no_standard_error():
    c, _ = arc_sections(34.0, 25.15, 3)
    v = _visible(c)[::3]
    v = v[v[:, 0] > 0.45 * c[-1, 0]]          # the first section and a half hidden
    fit, _, _ = analyse(v, c[-1, 0], 3, px_per_mm=12.0)
    assert fit.confidence.section_points[0] == 0
    assert np.isinf(fit.confidence.theta_se_deg[0])
    assert any("section 1 has 0 centerline points" in w for w in fit.confidence.warnings)
