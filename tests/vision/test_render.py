"""The renderer's ground truth is the geometry it was given (checked independently),
and every image is reproducible from its seed."""

import math

import numpy as np
import pytest

from lcpbench.vision.render import Nuisances, arc_sections, render, with_end_sections


@pytest.mark.parametrize("theta", [10, 90, 180])
def test_sections_are_tangent_arcs_with_pins_and_inflections_on_one_line(theta):
    c, knots = arc_sections(theta, 30.0, 3)
    r = 30 / math.radians(theta)
    chord = 2 * r * math.sin(math.radians(theta) / 2)
    np.testing.assert_allclose(knots, [[chord, 0], [2 * chord, 0]], atol=1e-9)
    np.testing.assert_allclose(c[-1], [3 * chord, 0], atol=1e-9)
    # total length 3 l, and the middle section bulges up by its sagitta
    assert np.hypot(*np.diff(c, axis=0).T).sum() == pytest.approx(90.0, rel=1e-6)
    assert c[:, 1].max() == pytest.approx(r * (1 - math.cos(math.radians(theta) / 2)), rel=1e-6)


def test_end_sections_continue_a_constrained_middle_tangentially():
    t = np.linspace(0, 1, 401)
    mid = np.column_stack([20 * t, 3 * np.sin(np.pi * t)])   # any pinned shape
    c, knots = with_end_sections(mid, 30.0, 3)
    np.testing.assert_allclose(knots, [mid[0], mid[-1]])
    assert abs(c[0, 1]) < 1e-9 and abs(c[-1, 1]) < 1e-9     # outer pins on the pin line
    d = np.diff(c, axis=0)
    turn = np.abs(np.diff(np.unwrap(np.arctan2(d[:, 1], d[:, 0]))))
    assert turn.max() < 0.02                                  # no kink at the joins


def test_same_seed_same_image_and_nuisances_change_it():
    c, _ = arc_sections(60, 30.0, 3)
    a, ta = render(c, px_per_mm=10.0, nuisances=Nuisances.all_on(3))
    b, _ = render(c, px_per_mm=10.0, nuisances=Nuisances.all_on(3))
    assert np.array_equal(a, b)
    assert -10 <= ta["rotation_deg"] <= 10 and "calibration" in ta
    clean, tc = render(c, px_per_mm=10.0)
    assert tc["rotation_deg"] == 0 and "calibration" not in tc
    assert a.shape != clean.shape or np.abs(a.astype(int) - clean).mean() > 1
