"""The dual walks' pick rule, compiled: which nodes a walk adds to its working set at a
face minimiser u.

A node's violation v_i is u_i − upper wall_i (or lower wall_i − u_i), −∞ where the node
is held. The walk adds, on each wall, the nodes whose v_i exceeds the slack: first the
warm contact set's (:func:`warm_picks`, once per walk), then in every run of consecutive
violated nodes its local maxima (v_i ≥ v_{i−1}, v_i > v_{i+1}), or with ``reach`` > 0
the galloping picks next to the held nodes (:func:`picks_in`;
:mod:`lcpbench.solvers.compiled_walk`). A pick is node + 1, signed: + the upper wall,
− the lower one.

Both walks call it, with a slack per node: the walk in node heights
(:func:`lcpbench.solvers.dual_kernel.dual_active_set`, the same for every node) and the
walk on a twisted factor at large N (:func:`lcpbench.linalg.twisted_walk_kernel.walk`).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def violation(u, wall, S, side, i):
    """The violation of node i's wall (``side`` +1: u − upper, −1: lower − u); −inf on
    held nodes."""
    if S[i]:
        return -np.inf
    return u[i] - wall[i] if side > 0 else wall[i] - u[i]


@njit(cache=True)
def warm_picks(u, hi, lo, has_lo, S, slack, warm_up, warm_lo, picks):
    """The warm contact set's nodes (``warm_up``, ``warm_lo``) whose wall is violated
    beyond the slack written to ``picks``, in node order; their count."""
    npick = 0
    for i in range(u.size):
        if warm_up[i] and violation(u, hi, S, 1, i) > slack[i]:
            picks[npick] = i + 1
            npick += 1
        elif has_lo and warm_lo[i] and violation(u, lo, S, -1, i) > slack[i]:
            picks[npick] = -(i + 1)
            npick += 1
    return npick


@njit(cache=True)
def picks_in(u, wall, side, slack, S, reach, picks, npick, start, stop):
    """Append to ``picks`` (node + 1; ``side`` in the sign) the nodes a walk adds on this
    wall, scanning nodes ``start`` .. ``stop`` (every violated node lies there): every
    run's local maxima of v, or with ``reach`` > 0 the galloping picks. Returns the new
    count."""
    n = u.size
    if reach <= 0:  # every local maximum beyond the slack, v in a sliding window
        if start > stop:
            return npick
        left = violation(u, wall, S, side, start - 1) if start >= 1 else -np.inf
        v = violation(u, wall, S, side, start)
        for i in range(start, stop + 1):
            right = violation(u, wall, S, side, i + 1) if i + 1 < n else -np.inf
            if v > slack[i] and v >= left and v > right:
                picks[npick] = side * (i + 1)
                npick += 1
            left, v = v, right
        return npick
    i = start
    while i <= stop:
        if not violation(u, wall, S, side, i) > slack[i]:
            i += 1
            continue
        a = i
        while i + 1 < n and violation(u, wall, S, side, i + 1) > slack[i + 1]:
            i += 1
        b = i
        left = a >= 1 and S[a - 1]
        right = b + 1 < n and S[b + 1]
        if (left or right) and b - a + 1 > reach:
            if left:
                picks[npick] = side * (a + reach - 1 + 1)
                npick += 1
            if right and not (left and b - reach + 1 == a + reach - 1):
                picks[npick] = side * (b - reach + 1 + 1)
                npick += 1
            i += 1
            continue
        best = a  # the run's deepest node (the first of equal ones)
        for k in range(a + 1, b + 1):
            if violation(u, wall, S, side, k) > violation(u, wall, S, side, best):
                best = k
        picks[npick] = side * (best + 1)
        npick += 1
        i += 1
    return npick
