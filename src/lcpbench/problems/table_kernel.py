"""A round of the refinement of a function profile's table, compiled.

:func:`lcpbench.problems.profile_table.hermite_pieces` tabulates a wall given as a
function in rounds: it asks the function for h and h' at the midpoints of the pieces to
check, and :func:`refine` does the rest of the round in one call: each piece's
coefficients, its check at the midpoint, and the split of the pieces that fail. The
arithmetic is numpy's elementwise arithmetic written as loops, the same operations in
the same order (no fused multiply-adds: numba does not contract without ``fastmath``),
so the table is the same, bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["refine"]


@njit(cache=True, error_model="numpy")  # (a piece of zero width: inf/NaN, as numpy)
def refine(ends, mids, h_mid, m_mid, tol_h, tol_m, narrowest):
    """One round of :func:`~lcpbench.problems.profile_table.hermite_pieces` on the
    pieces ``ends`` (rows: a, b, h(a), h(b), h'(a), h'(b)), their midpoints ``mids``
    and the function's h and h' there. A piece fails where its cubic Hermite piece is
    off the function at the midpoint by more than ``tol_h`` in h or ``tol_m`` in h',
    and it is wider than ``narrowest``.

    Returns ``(passed, split, next_mids, top_h, top_m)``: the pieces that passed, in
    order (rows: a and the PPoly coefficients c0, c1, c2, c3); the halves of the failed
    ones, each split at its midpoint c (rows as ``ends``: first every [a, c], then every
    [c, b]) and their midpoints; max|h| and max|h'| at the new breakpoints c (−1: none
    failed). ``passed`` is empty where some h or h' at a midpoint is not finite
    (``top_h`` is then NaN)."""
    k = ends.shape[1]
    for i in range(k):
        if not (np.isfinite(h_mid[i]) and np.isfinite(m_mid[i])):
            return np.empty((5, 0)), np.empty((6, 0)), np.empty(0), np.nan, np.nan
    fail = np.empty(k, np.bool_)
    coef = np.empty((2, k))
    nbad = 0
    for i in range(k):
        a, b, ha, hb, ma, mb = ends[0, i], ends[1, i], ends[2, i], ends[3, i], ends[4, i], \
            ends[5, i]
        dx = b - a
        secant = (hb - ha) / dx
        c1 = (3.0 * secant - 2.0 * ma - mb) / dx
        c0 = (ma + mb - 2.0 * secant) / (dx * dx)
        d = mids[i] - a  # (the table at the midpoint: its own piece's cubic)
        t_h = ((c0 * d + c1) * d + ma) * d + ha
        t_m = (3.0 * c0 * d + 2.0 * c1) * d + ma
        bad = (abs(t_h - h_mid[i]) > tol_h or abs(t_m - m_mid[i]) > tol_m) and dx > narrowest
        fail[i] = bad
        coef[0, i], coef[1, i] = c0, c1
        nbad += bad
    passed = np.empty((5, k - nbad))
    split = np.empty((6, 2 * nbad))
    next_mids = np.empty(2 * nbad)
    top_h = top_m = -1.0
    p = q = 0
    for i in range(k):
        a, b = ends[0, i], ends[1, i]
        if not fail[i]:
            passed[0, p], passed[1, p], passed[2, p] = a, coef[0, i], coef[1, i]
            passed[3, p], passed[4, p] = ends[4, i], ends[2, i]
            p += 1
            continue
        c, hc, mc = mids[i], h_mid[i], m_mid[i]
        top_h, top_m = max(top_h, abs(hc)), max(top_m, abs(mc))
        r = nbad + q
        split[0, q], split[1, q], split[2, q] = a, c, ends[2, i]
        split[3, q], split[4, q], split[5, q] = hc, ends[4, i], mc
        split[0, r], split[1, r], split[2, r] = c, b, hc
        split[3, r], split[4, r], split[5, r] = ends[3, i], mc, ends[5, i]
        q += 1
    for j in range(2 * nbad):
        next_mids[j] = 0.5 * (split[0, j] + split[1, j])
    return passed, split, next_mids, top_h, top_m
