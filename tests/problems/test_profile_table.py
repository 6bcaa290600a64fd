"""The cubic pieces the compiled kernels evaluate a wall profile by
(lcpbench.problems.profile_table), checked against the profile itself: a table's
pieces are its own interpolant (scipy's), a function's stay within the documented
tolerances of the function, and the kernel's evaluation continues them flat."""

import numpy as np
import pytest

from lcpbench.numba_cache import kernel_module
from lcpbench.problems import profile_table as pt
from lcpbench.problems.walls import WallProfile

XS, YS = [0.0, 5.0, 11.0, 20.0, 30.0], [3.0, 2.5, 3.6, 3.1, 3.0]


def _gauss(x):
    return 3.0 - 0.8 * np.exp(-0.5 * ((np.asarray(x, float) - 14.0) / 1.5) ** 2)


def _gauss_slope(x):
    x = np.asarray(x, float)
    return 0.8 * (x - 14.0) / 1.5**2 * np.exp(-0.5 * ((x - 14.0) / 1.5) ** 2)


def _kernel_eval(table, x):
    k = kernel_module("lcpbench.model.wall_kernel", "wall_height")
    out = np.array([k.wall_height(*table, float(t)) for t in x])
    return out[:, 0], out[:, 1], out[:, 2]


@pytest.mark.parametrize("kind", ["linear", "pchip", "cubic"])
def test_a_tables_pieces_are_its_interpolant_continued_flat(kind):
    prof = WallProfile.from_table(XS, YS, kind)
    table = prof.pieces(-30.0, 30.0)
    x = np.concatenate([np.linspace(-5, 35, 401), XS])
    h, h1, h2 = _kernel_eval(table, x)
    np.testing.assert_allclose(h, prof(x), rtol=0, atol=1e-14)
    inside = (x > XS[0]) & (x < XS[-1]) & ~np.isin(x, XS)  # (a kink of "linear" at a knot)
    np.testing.assert_allclose(h1[inside], prof.slope(x[inside]), rtol=0, atol=1e-13)
    np.testing.assert_allclose(h2[inside], prof.curvature(x[inside]), rtol=0, atol=1e-12)
    outside = (x < XS[0]) | (x > XS[-1])
    assert np.all(h1[outside] == 0) and np.all(h2[outside] == 0)


def test_a_functions_pieces_meet_the_documented_tolerances():
    prof = WallProfile.from_function(_gauss, _gauss_slope)
    knots, coef = prof.pieces(-30.0, 30.0)
    x = np.random.default_rng(3).uniform(-30, 30, 20000)
    h, h1 = pt.evaluate(knots, coef, x)
    # the refinement checks midpoints; the Hermite error of a smooth h peaks there
    assert np.max(np.abs(h - _gauss(x))) <= 2 * pt.HEIGHT_TOL * (1 + 3.0)
    assert np.max(np.abs(h1 - _gauss_slope(x))) <= 2 * pt.SLOPE_TOL * (1 + 0.33)
    assert knots.size - 1 <= pt.MAX_PIECES


def test_a_function_that_writes_its_answers_into_one_buffer_has_a_true_table():
    """A profile function may hand back its own array and write it again on the next
    call (here h and h' share one buffer): the table must still be h's, within the
    documented tolerances against the calculus h and h' (theory: _gauss, _gauss_slope)."""
    buf = np.empty(0)

    def into(values):
        nonlocal buf
        if buf.shape != values.shape:
            buf = np.empty(values.shape)
        buf[...] = values
        return buf

    prof = WallProfile.from_function(lambda t: into(_gauss(t)), lambda t: into(_gauss_slope(t)))
    knots, coef = prof.pieces(-30.0, 30.0)
    xs = np.random.default_rng(5).uniform(-30, 30, 20000)
    h, h1 = pt.evaluate(knots, coef, xs)
    assert np.max(np.abs(h - _gauss(xs))) <= 2 * pt.HEIGHT_TOL * (1 + 3.0)
    assert np.max(np.abs(h1 - _gauss_slope(xs))) <= 2 * pt.SLOPE_TOL * (1 + 0.33)


def test_a_function_given_without_its_slope_has_a_table_as_tight():
    """The slope by Richardson-extrapolated central differences is close enough to the
    calculus slope (theory: _gauss_slope) for the table to meet the same tolerances;
    with plain central differences (error ~4e-9 > SLOPE_TOL) no table could."""
    prof = WallProfile.from_function(_gauss)
    x = np.linspace(-30.0, 30.0, 2001)
    assert np.max(np.abs(prof.slope(x) - _gauss_slope(x))) <= 1e-11
    knots, coef = prof.pieces(-30.0, 30.0)
    h, h1 = pt.evaluate(knots, coef, np.random.default_rng(4).uniform(-30, 30, 20000))
    xs = np.random.default_rng(4).uniform(-30, 30, 20000)
    assert np.max(np.abs(h - _gauss(xs))) <= 2 * pt.HEIGHT_TOL * (1 + 3.0)
    assert np.max(np.abs(h1 - _gauss_slope(xs))) <= 2 * pt.SLOPE_TOL * (1 + 0.33)


def test_the_mirror_negates_the_pieces_and_the_table_is_made_once():
    prof = WallProfile.from_function(_gauss, _gauss_slope)
    a = prof.pieces(-30.0, 30.0)
    assert prof.pieces(-30.0, 30.0) is a
    mirror = WallProfile.from_table(XS, YS).mirrored()
    x = np.linspace(-2, 32, 101)
    np.testing.assert_allclose(_kernel_eval(mirror.pieces(-30, 30), x)[0], mirror(x), atol=1e-14)


def test_a_kink_is_tabulated_within_a_narrow_piece():
    """|x − 12.3| has no cubic interpolant across the kink: the refinement narrows the
    piece holding it, and elsewhere the table is the function."""
    prof = WallProfile.from_function(lambda x: 3.0 + 0.1 * np.abs(np.asarray(x) - 12.3),
                                     lambda x: 0.1 * np.sign(np.asarray(x) - 12.3))
    knots, coef = prof.pieces(-30.0, 30.0)
    x = np.random.default_rng(4).uniform(-30, 30, 20000)
    h, _ = pt.evaluate(knots, coef, x)
    err = np.abs(h - prof(x))
    i = np.searchsorted(knots, 12.3)
    width = knots[i] - knots[i - 1]
    assert width <= 1e-6  # the piece across the kink
    assert np.max(err) <= max(0.1 * width, pt.HEIGHT_TOL * 5)


def test_a_function_that_needs_too_many_pieces_has_no_table():
    prof = WallProfile.from_function(lambda x: 3.0 + 1e-3 * np.sin(1e5 * np.asarray(x)),
                                     lambda x: 1e2 * np.cos(1e5 * np.asarray(x)))
    assert prof.pieces(-30.0, 30.0) is None
