"""Walls of any profile, compiled: a wall's height, slope and curvature at x, the walls
at the nodes' x, and the slope load of the wall reactions.

A wall is a table of cubic pieces (:mod:`lcpbench.problems.profile_table`):
breakpoints ``knots`` and coefficients ``coef`` (4 × pieces, scipy's PPoly layout),
continued flat outside the breakpoints. The solve's profile kernel
(:func:`lcpbench.model.compiled_kernel.outer_loop`) and the judge kernel
(:mod:`lcpbench.model.judge_kernel`) both read the walls through these functions: the
wall is the scene's data, as the chain's arrays are.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["lagged_load", "slope_load", "split_by_wall", "wall_height", "walls_at"]


@njit(cache=True)
def wall_height(knots, coef, x):
    """(h, h', h'') of a table of cubic pieces at x: the piece holding x (binary
    search), continued flat outside the breakpoints (the end value, h' = h'' = 0)."""
    m = coef.shape[1]
    if x <= knots[0]:
        return coef[3, 0], 0.0, 0.0
    if x >= knots[m]:
        d = knots[m] - knots[m - 1]
        return ((coef[0, m - 1] * d + coef[1, m - 1]) * d + coef[2, m - 1]) * d + coef[3, m - 1], \
            0.0, 0.0
    lo, hi = 0, m  # knots[lo] <= x < knots[hi]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if knots[mid] <= x:
            lo = mid
        else:
            hi = mid
    d = x - knots[lo]
    c0, c1, c2, c3 = coef[0, lo], coef[1, lo], coef[2, lo], coef[3, lo]
    return ((c0 * d + c1) * d + c2) * d + c3, (3.0 * c0 * d + 2.0 * c1) * d + c2, \
        6.0 * c0 * d + 2.0 * c1


@njit(cache=True)
def walls_at(sines, cosines, a, fs, hi_rows, lo_rows, ku, cu_, kl, cl_, xf, yf, hi, lo, h1, l1,
             h2, l2):
    """The free nodes' x, y (``xf``, ``yf``; plain running sums, as
    model.chain.node_positions) and the walls at their x: ``hi``, ``lo`` the profile
    heights where a node has a row (its flat row where that wall has no table), ``h1``,
    ``l1`` the slopes, ``h2``, ``l2`` the curvatures (0 where a wall has no table; from
    Python: model.profile.wall_rows). ``sines``, ``cosines``: of the link angles α."""
    n = hi_rows.size
    x = y = 0.0
    first = fs - 1
    if first == 0:
        xf[0] = yf[0] = 0.0
    for i in range(sines.size):
        x += a * cosines[i]
        y += a * sines[i]
        node = i + 1 - first
        if 0 <= node < n:
            xf[node], yf[node] = x, y
    for i in range(n):
        hi[i], lo[i], h1[i], l1[i], h2[i], l2[i] = hi_rows[i], lo_rows[i], 0.0, 0.0, 0.0, 0.0
        if ku.size:
            hh, h1[i], h2[i] = wall_height(ku, cu_, xf[i])
            if np.isfinite(hi_rows[i]):
                hi[i] = hh
        if kl.size:
            hh, l1[i], l2[i] = wall_height(kl, cl_, xf[i])
            if np.isfinite(lo_rows[i]):
                lo[i] = hh


@njit(cache=True)
def slope_load(alpha, cosines, sines, fs, w, out):
    """s = J_xᵀ w on the free nodes (from Python: model.profile.slope_load): with W_j the
    sum of w over the nodes past link j and p_j = −tan α_j W_j, node m gets
    p_(m−1) − p_m."""
    n, first, links = w.size, fs - 1, alpha.size
    W, p_next = 0.0, 0.0
    for i in range(n):
        out[i] = 0.0
    for j in range(links - 1, -1, -1):  # link j joins nodes j, j + 1
        node = j + 1 - first
        if 0 <= node < n:
            W += w[node]
        p = -(sines[j] / cosines[j]) * W
        if 0 <= node < n:
            out[node] += p - p_next if j + 1 < links else p
        p_next = p
    node = -first  # node 0 (free only without a left pin)
    if 0 <= node < n:
        out[node] -= p_next


@njit(cache=True)
def lagged_load(alpha, cosines, sines, fs, mu_up, mu_lo, h1, l1, nodal_load, w, s, out):
    """The nodal load of a step against walls of any profile into ``out``: ``nodal_load``
    plus the slope load s = J_xᵀ w (:func:`slope_load`) of the lagged reactions, w =
    μ̄ h'(x) − ν̄ l'(x) with μ̄, ν̄ (``mu_up``, ``mu_lo``) clipped at 0; ``w``, ``s``
    scratch. The profile kernel's step, the compiled driver's and the judge's."""
    for i in range(w.size):
        w[i] = max(mu_up[i], 0.0) * h1[i] - max(mu_lo[i], 0.0) * l1[i]
    slope_load(alpha, cosines, sines, fs, w, s)
    for i in range(w.size):
        out[i] = nodal_load[i] + s[i]


@njit(cache=True)
def split_by_wall(net, u, hi, lo, channel, upper, lower):
    """The net reactions ``net`` (N, + pushes down) of the free nodes at heights ``u``, split
    by wall into ``upper`` and ``lower``: against one wall all of it is the upper wall's (a
    negative value is that wall pulling); in a channel each node's belongs to the wall it
    is nearer to, of those at its x (``hi``, ``lo``), with its sign kept, so a pulling wall
    stays visible (a node whose walls' midpoint is not finite: the upper wall's where it has
    one). The one split of the solve (the profile kernel's lagged reactions), the judge and
    the results (:func:`lcpbench.model.profile.split_reactions`)."""
    for i in range(net.size):
        near_up = True
        if channel:  # (both walls finite first: inf − inf warns as plain Python)
            near_up = np.isfinite(hi[i])
            if near_up and np.isfinite(lo[i]):
                mid = 0.5 * (hi[i] + lo[i])
                near_up = u[i] >= mid if np.isfinite(mid) else True
        upper[i], lower[i] = (net[i], 0.0) if near_up else (0.0, -net[i])
