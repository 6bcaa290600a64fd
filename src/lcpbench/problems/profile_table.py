"""A wall profile as piecewise cubic pieces: the form the compiled kernels evaluate.

A profile y = h(x) (:class:`lcpbench.problems.walls.WallProfile`) reaches the
compiled solve as a table of breakpoints x_0 < … < x_m and, per piece i, the
coefficients of

    h(x) = c0_i d³ + c1_i d² + c2_i d + c3_i,   d = x − x_i,   x_i <= x <= x_(i+1)

(scipy's ``PPoly`` layout: ``coef[:, i]`` = (c0, c1, c2, c3)). Outside
[x_0, x_m] the wall is continued flat: h the end value, h' = h'' = 0, as
:class:`~lcpbench.problems.walls.WallProfile` defines it.

* A table profile (``linear``, ``pchip``, ``cubic``) *is* such pieces: its
  table is exact (:func:`exact_pieces`).
* A profile given as a function is tabulated once, over the x range the
  chain can reach, as cubic Hermite pieces through h and h' at the
  breakpoints (:func:`hermite_pieces`). The breakpoints are refined, piece
  by piece, until every piece's midpoint agrees with the function to
  :data:`HEIGHT_TOL` (relative to 1 + max|h|) in h and :data:`SLOPE_TOL` in
  h'. A kink or a jump stops the refinement at pieces of
  :data:`MIN_WIDTH` ℓ: the table then differs from the function only
  inside those pieces. Where more than :data:`MAX_PIECES` would be needed,
  there is no table (None), and the plan refuses the scene with a ProblemError
  naming ``wall_profile`` or ``lower_profile`` (every route reads the table).
"""

from __future__ import annotations

import numpy as np

#: a function profile's table: largest |h_table − h| at a piece's midpoint, relative
#: to 1 + max|h| (mm): 1e-13 is ~100 ulps of a wall 5 mm high; a node's force moves
#: by ~6 EI/a³ times a wall error (1e-8 N·relative at the paper's N = 140)
HEIGHT_TOL = 1e-13
#: …and the largest |h'_table − h'| at a piece's midpoint, relative to 1 + max|h'|
SLOPE_TOL = 1e-9
#: the narrowest piece the refinement makes, relative to the range tabulated
MIN_WIDTH = 1e-10
#: the most pieces a function profile's table may have
MAX_PIECES = 1 << 18
#: the first, uniform, breakpoints of a function profile's table
START_PIECES = 64


def exact_pieces(knots, coef) -> tuple[np.ndarray, np.ndarray]:
    """A table from breakpoints and a (k+1, m) PPoly coefficient array of degree k <= 3
    (scipy's ``PPoly.x``, ``PPoly.c``), as contiguous float arrays of degree 3."""
    c = np.asarray(coef, dtype=float)
    full = np.zeros((4, c.shape[1]))
    full[4 - c.shape[0]:] = c
    return np.ascontiguousarray(knots, dtype=float), np.ascontiguousarray(full)


def linear_pieces(xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The table of the piecewise-linear interpolant through (xs, ys)."""
    steps = np.diff(ys) / np.diff(xs)
    return exact_pieces(xs, np.vstack([steps, ys[:-1]]))


def evaluate(knots: np.ndarray, coef: np.ndarray, x) -> tuple[np.ndarray, np.ndarray]:
    """h and h' of a table at x (vectorised; the pieces' own continuation outside is
    not applied here: for checking a table inside its range)."""
    x = np.asarray(x, dtype=float)
    i = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, coef.shape[1] - 1)
    d = x - knots[i]
    c0, c1, c2, c3 = coef[:, i]
    return ((c0 * d + c1) * d + c2) * d + c3, (3.0 * c0 * d + 2.0 * c1) * d + c2


def hermite_pieces(height, slope, x_low: float, x_high: float
                   ) -> tuple[np.ndarray, np.ndarray] | None:
    """Cubic Hermite pieces of ``height`` (h, vectorised) and ``slope`` (h') over
    [x_low, x_high], refined until each piece meets :data:`HEIGHT_TOL` and
    :data:`SLOPE_TOL` at its midpoint or is :data:`MIN_WIDTH` narrow; None where that
    takes more than :data:`MAX_PIECES` pieces.

    Refined in rounds: each round checks the pieces made in the round before (at first
    the START_PIECES uniform ones) at their midpoints, against the scales 1 + max|h| and
    1 + max|h'| over every breakpoint so far, and splits the ones that fail at their
    midpoint (h and h' there become the new breakpoint's). A piece that passed stays as
    it is: its coefficients and midpoint depend on its two ends alone, and the scales
    only grow, so it passes every later round's check too; h and h' are asked only at
    the new midpoints."""
    if not x_low < x_high:
        return None
    from ..numba_cache import kernel_module  # numba at the first table, not at import

    refine = kernel_module("lcpbench.problems.table_kernel", "refine").refine
    knots = np.linspace(x_low, x_high, START_PIECES + 1)
    narrowest = MIN_WIDTH * (x_high - x_low)
    h, m = height(knots), slope(knots)
    scale_h = 1.0 + float(np.max(np.abs(h)))
    scale_m = 1.0 + float(np.max(np.abs(m)))
    # the pieces to check, a row each: their ends a, b, h at both, h' at both
    ends = np.stack([knots[:-1], knots[1:], h[:-1], h[1:], m[:-1], m[1:]]).astype(float)
    mids = 0.5 * (ends[0] + ends[1])
    done: list[np.ndarray] = []  # the pieces that passed: rows a, c0, c1, c2, c3
    total = START_PIECES  # pieces in the table
    while True:
        h_mid = np.ascontiguousarray(height(mids), dtype=float)
        m_mid = np.ascontiguousarray(slope(mids), dtype=float)
        passed, ends, mids, top_h, top_m = refine(ends, mids, h_mid, m_mid,
                                                  HEIGHT_TOL * scale_h, SLOPE_TOL * scale_m,
                                                  narrowest)
        if np.isnan(top_h):  # h or h' not finite at a midpoint
            return None
        done.append(passed)
        nbad = mids.size
        if nbad == 0:
            table = np.concatenate(done, axis=1)
            order = np.argsort(table[0])
            return (np.ascontiguousarray(np.append(table[0, order], x_high)),
                    np.ascontiguousarray(table[1:, order]))
        if total + nbad > MAX_PIECES:
            return None
        total += nbad
        scale_h = max(scale_h, 1.0 + top_h)
        scale_m = max(scale_m, 1.0 + top_m)
