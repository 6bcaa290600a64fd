"""The result judge's exact step at large N: a primal active set from the answer's contacts.

At N >= LARGE_N the judge's step is in increments on the tridiagonal factor
(:mod:`.large_n`). Block principal pivoting (:func:`lcpbench.model.judge._pivot_step`)
does not settle there: the answer's contacts are pairs of neighbouring nodes,
and at the final α a pair has moved by one node. Releasing the outer node of a
pair frees the chain's slope there, the span between the contacts passes
through the wall (3,640 nodes at N = 10⁵) and the exchanges that follow cycle
until the round cap.

Here the same step is solved by the primal active-set method (Nocedal &
Wright, Alg. 16.3), one change at a time from the answer's contact set:
every iterate is feasible, a wall that pulls by more than the slack releases
its node (the most negative, scaled by its slack), and a move towards the
face minimiser stops at the first wall it meets, which joins the set. A pair
that moved by one node costs a release and a join on each side. The face
minimisers are solved as in the block pivoting (solve, then one refinement
with the factored gradient), and it stops with the same test: no wall pulls
by more than its slack and no node is through a wall by more than its reach.
It is the judge's own code, independent of the solver's dual walk
(:mod:`lcpbench.solvers.banded`).
"""

from __future__ import annotations

import numpy as np


def primal_step(step, up: np.ndarray, lo: np.ndarray, *, slack_of, reach_of, cap: int):
    """``(u, up, lo, rounds)`` at the settled face, or None within ``cap`` face solves.

    ``slack_of(u)``: per node, the pull that releases a wall; ``reach_of(u)``: per
    node, the depth through a wall that joins it (both as the block pivoting uses).
    Rigid walls only (elastic walls at large N take the block pivoting of
    :func:`lcpbench.model.judge._pivot_step`, its springs in the twisted factor).
    """
    up, lo = up.copy(), lo.copy()
    hi_w, lo_w = step.upper, step.lower
    u = _face_minimiser(step, up, lo)
    if u is None:
        return None
    # a feasible start: nodes through a wall join it (then the face's minimiser again)
    for _ in range(cap):
        reach = reach_of(u)
        join_up = ~up & ~lo & (u > hi_w + reach)
        join_lo = ~up & ~lo & (u < lo_w - reach)
        if not (join_up.any() or join_lo.any()):
            break
        up |= join_up
        lo |= join_lo
        u = _face_minimiser(step, up, lo)
        if u is None:
            return None
    else:
        return None
    at_minimiser = True
    for rounds in range(1, cap + 1):
        if at_minimiser:
            net = -step.gradient(u)
            slack = slack_of(u)
            # net = −gradient: the upper wall's reaction (it pushes down), minus the lower's
            pull_up = np.where(up, net / slack, np.inf)  # < −1: it pulls
            pull_lo = np.where(lo, -net / slack, np.inf)
            i_up, i_lo = int(np.argmin(pull_up)), int(np.argmin(pull_lo))
            if min(pull_up[i_up], pull_lo[i_lo]) >= -1.0:
                return u, up, lo, rounds
            if pull_up[i_up] <= pull_lo[i_lo]:
                up[i_up] = False
            else:
                lo[i_lo] = False
        v = _face_minimiser(step, up, lo)
        if v is None:
            return None
        d = v - u
        free = ~(up | lo)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_up = np.where(free & (d > 0) & np.isfinite(hi_w), (hi_w - u) / d, np.inf)
            t_lo = np.where(free & (d < 0) & np.isfinite(lo_w), (lo_w - u) / d, np.inf)
        j_up, j_lo = int(np.argmin(t_up)), int(np.argmin(t_lo))
        t = min(t_up[j_up], t_lo[j_lo])
        if t < 1.0:
            u = u + max(t, 0.0) * d
            if t_up[j_up] <= t_lo[j_lo]:
                up[j_up] = True
                u[j_up] = hi_w[j_up]
            else:
                lo[j_lo] = True
                u[j_lo] = lo_w[j_lo]
            at_minimiser = False
        else:
            u = v
            at_minimiser = True
    return None


def _face_minimiser(step, up, lo):
    """The step's minimiser with ``up`` / ``lo`` on their walls: a face solve, refined once
    with the factored gradient (as the block pivoting does)."""
    u = step.origin.copy()
    u[up] = step.upper[up]
    u[lo] = step.lower[lo]
    free = np.flatnonzero(~(up | lo))
    if free.size:
        try:
            for _ in range(2):
                u[free] -= step.solve_on(free, step.gradient(u)[free])
        except (np.linalg.LinAlgError, ValueError):
            return None
    return u
