"""The plane-geometry stages on exact curves: circle fit, eq. (38), eq. (39),
inflection points, ICP on a known rigid motion."""

import math

import numpy as np
import pytest

from lcpbench.vision.geometry import (
    arc_length,
    bend_angle,
    bend_angle_printed,
    fit_circle,
    icp,
    inflection_indices,
    offset_curve,
    resample,
    rigid_fit,
    tangent_point,
)
from lcpbench.vision.render import arc_sections


def _arc(center, r, a0, sweep, n=400):
    t = a0 + np.linspace(0, sweep, n)
    return np.column_stack([center[0] + r * np.cos(t), center[1] + r * np.sin(t)])


@pytest.mark.parametrize("sweep_deg", [5, 10, 45, 120, 180, 270])
def test_circle_fit_recovers_exact_arcs(sweep_deg):
    c, r = np.array([3.0, -7.5]), 12.345
    pts = _arc(c, r, 0.3, math.radians(sweep_deg))
    fit = fit_circle(pts)
    assert fit.radius == pytest.approx(r, rel=1e-9)
    np.testing.assert_allclose(fit.center, c, atol=1e-7)
    assert fit.rms < 1e-8


def test_circle_fit_on_noisy_shallow_arc_is_unbiased():
    # the 10-degree section of a 30 mm actuator, 0.01 mm noise: radius within 1 %
    rng = np.random.default_rng(1)
    r = 30 / math.radians(10)
    pts = _arc((0, -r), r, math.radians(85), math.radians(10), 600)
    pts += rng.normal(0, 0.01, pts.shape)
    assert fit_circle(pts).radius == pytest.approx(r, rel=0.01)


def test_circle_fit_rejects_a_line():
    with pytest.raises(ValueError):
        fit_circle(np.column_stack([np.arange(10.0), 2 * np.arange(10.0)]))


@pytest.mark.parametrize("deg", [10, 60, 89, 91, 120, 150, 180])
def test_eq38_with_atan2_on_known_angles(deg):
    c = np.array([1.0, 2.0])
    a0 = 0.7
    p1 = c + 5 * np.array([math.cos(a0), math.sin(a0)])
    p2 = c + 5 * np.array([math.cos(a0 + math.radians(deg)), math.sin(a0 + math.radians(deg))])
    assert math.degrees(bend_angle(p1, p2, c)) == pytest.approx(deg, abs=1e-9)


@pytest.mark.parametrize("deg", [200, 250, 330])
def test_eq38_beyond_half_a_circle_with_a_point_on_the_arc(deg):
    c = np.zeros(2)
    t = math.radians(deg)
    p1, p2 = np.array([1.0, 0.0]), np.array([math.cos(t), math.sin(t)])
    mid = np.array([math.cos(t / 2), math.sin(t / 2)])
    assert math.degrees(bend_angle(p1, p2, c, through=mid)) == pytest.approx(deg, abs=1e-9)


@pytest.mark.parametrize("deg, printed", [(30, 30), (60, 60), (120, 60), (150, 30), (180, 0)])
def test_eq38_as_printed_folds_angles_above_90_degrees(deg, printed):
    # arctan|cross/dot| is arctan|tan θ|: the erratum of docs/errata.md
    c = np.zeros(2)
    t = math.radians(deg)
    p1, p2 = np.array([2.0, 0.0]), 2 * np.array([math.cos(t), math.sin(t)])
    assert math.degrees(bend_angle_printed(p1, p2, c)) == pytest.approx(printed, abs=1e-7)
    assert math.degrees(bend_angle(p1, p2, c)) == pytest.approx(deg, abs=1e-9)


def test_eq39_arc_length():
    assert arc_length(30 / math.pi, math.pi) == pytest.approx(30.0)


@pytest.mark.parametrize("theta", [10, 90, 180])
def test_inflection_points_of_exact_sections(theta):
    c, knots = arc_sections(theta, 30.0, 3)
    dense = resample(c, step=0.05)
    idx = inflection_indices(dense, 3, 10)
    np.testing.assert_allclose(dense[idx], knots, atol=0.06)


def test_neighbouring_circles_touch_at_the_inflection_point():
    c, knots = arc_sections(70, 30.0, 3)
    n = len(c) // 3
    c1, c2 = fit_circle(c[10:n - 10]), fit_circle(c[n + 10:2 * n - 10])
    np.testing.assert_allclose(tangent_point(c1, c2), knots[0], atol=1e-7)


def test_offset_of_a_clockwise_arc_moves_towards_its_centre():
    pts = _arc((0, 0), 10.0, math.pi, -math.pi)  # left to right over the top: clockwise
    off = offset_curve(pts, 1.5)
    np.testing.assert_allclose(np.hypot(off[5:-5, 0], off[5:-5, 1]), 8.5, atol=1e-3)


def _rot(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


def test_rigid_fit_recovers_a_known_motion():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(30, 2))
    r, t = _rot(23.0), np.array([1.5, -2.0])
    r_fit, t_fit = rigid_fit(a, a @ r.T + t)
    np.testing.assert_allclose(r_fit, r, atol=1e-12)
    np.testing.assert_allclose(t_fit, t, atol=1e-12)


def test_icp_undoes_a_known_rigid_motion():
    # an S-shaped 3-section centerline (a single arc would slide along itself); the
    # model's 201 points cover its inner 90 %, the "photographed" curve all of it
    c, _ = arc_sections(120, 30.0, 3)
    dense = resample(c, step=0.005)
    fixed = resample(dense[len(dense) // 20: -len(dense) // 20], n=201)
    r, t = _rot(6.0), np.array([0.8, -0.5])
    moved = dense @ r.T + t
    reg = icp(fixed, moved)
    assert reg.distances.mean() < 2e-3          # spacing 0.005 mm: nearest point within 0.0025
    assert reg.angle_deg == pytest.approx(-6.0, abs=0.01)
    # the registration maps the moved curve back: R_reg (R x + t) + t_reg = x
    np.testing.assert_allclose(reg.rotation @ r, np.eye(2), atol=2e-4)
    np.testing.assert_allclose(reg.rotation @ t + reg.translation, 0, atol=5e-3)
