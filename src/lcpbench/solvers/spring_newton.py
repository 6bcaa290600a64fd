"""The contact step with elastic walls at large N: Newton on its springs (semismooth).

With elastic walls (:mod:`lcpbench.model.elastic`) of stiffness k_i the step is
no longer a box QP: it is the unconstrained, convex, piecewise quadratic

    minimise  f(d) = Q(d) + Σ ½ k_i (d_i − h_i)₊² + Σ ½ k'_i (l_i − d_i)₊²

(Q the step's quadratic in increments d, h and l the walls about u₀). Its
gradient r = ∇Q + k (d − h)₊ − k' (l − d)₊ is piecewise linear, and the
reactions are R = −∇Q(d) = k (d − h)₊ − k' (l − d)₊: the compliance law
0 <= R ⟂ g + R/k >= 0 holds by construction. Each Newton step solves

    (H + diag(k on the nodes past a wall)) Δ = −r

on the step's twisted factor, the springs rotated in as rows √k e_i
(:meth:`lcpbench.linalg.twisted.TwistedFactor.face_solve`): k never forms a sum
with H's entries, and r is a residual (bounded as k grows), so the rigid wall is
the limit k → ∞, not a special case. The step length is the exact line search
of the convex f along Δ (the root of f'(t), monotone, by safeguarded secant);
a full step whose springs are those it was computed with lands on the minimiser
of that piece, the answer (one refinement on the same face follows). It takes
steps in increments with their own factor only (large N,
:mod:`lcpbench.model.large_n`), every wall row elastic.
"""

from __future__ import annotations

import time

import numpy as np

from ..thresholds import EPS, ROUNDOFF_ULPS
from .base import Status, StepSolution

#: Newton steps before the step is handed back unsolved
MAX_NEWTON = 200
#: secant steps of the line search on f'(t)
LINE_STEPS = 30


def springs(step) -> tuple[np.ndarray, np.ndarray] | None:
    """(k upper, k lower) per node (N/mm; 0 where the node has no such wall), or None
    where some wall row is rigid (not taken here)."""
    out = []
    for k, wall in ((step.upper_stiffness, step.upper), (step.lower_stiffness, step.lower)):
        rows = np.isfinite(wall)
        if not rows.any():
            out.append(np.zeros(step.size))
            continue
        if k is None:
            return None
        k = np.asarray(k, dtype=float)
        if not np.all(np.isfinite(k[rows]) & (k[rows] > 0)):
            return None
        out.append(np.where(rows, k, 0.0))
    return out[0], out[1]


def takes(step) -> bool:
    """Whether :func:`solve_step` takes the step: increments with their own factor and
    every wall row elastic."""
    return getattr(step, "factor", None) is not None and step.elastic and \
        springs(step) is not None


def _residual(step, d, ku, kl):
    """(r, past upper, past lower, ∇Q): the gradient of f at d and its springs."""
    g = step.gradient(d)
    with np.errstate(invalid="ignore"):
        pu = (ku > 0) & (d > step.upper)
        pl = (kl > 0) & (d < step.lower)
    r = g.copy()
    r[pu] += ku[pu] * (d[pu] - step.upper[pu])
    r[pl] -= kl[pl] * (step.lower[pl] - d[pl])
    return r, pu, pl, g


def _line(step, d, delta, ku, kl, slope1):
    """t in (0, 1] with f'(t) = r(d + t Δ)·Δ ≈ 0 (f'(0) < 0 < f'(1) = ``slope1``)."""
    a, fa = 0.0, float(_residual(step, d, ku, kl)[0] @ delta)
    b, fb = 1.0, slope1
    t = 1.0
    for _ in range(LINE_STEPS):
        t = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
        if not (a < t < b):
            t = 0.5 * (a + b)
        ft = float(_residual(step, d + t * delta, ku, kl)[0] @ delta)
        if ft > 0.0:
            b, fb = t, ft
            fa *= 0.5  # Illinois: the end that stays is halved
        else:
            a, fa = t, ft
        if b - a <= 1e-3 * b:
            break
    return a if a > 0.0 else t


def _warm_sets(warm, n: int):
    """The warm start's contact sets (upper, lower), or None."""
    up = getattr(warm, "active_upper", None)
    lo = getattr(warm, "active_lower", None)
    if up is None or np.size(up) != n or not np.any(up):
        return None
    lo = np.zeros(n, bool) if lo is None or np.size(lo) != n else np.asarray(lo, bool)
    return np.asarray(up, bool), lo


def solve_step(step, warm: StepSolution | None = None) -> StepSolution:
    """The elastic step's minimiser by Newton on its springs (see the module)."""
    if not takes(step):
        raise ValueError("spring_newton.solve_step takes a step in increments (its own "
                         "factor) whose every wall row is elastic (finite k > 0)")
    t0 = time.perf_counter()
    n = step.size
    ku, kl = springs(step)
    d = np.zeros(n)
    if warm is not None and warm.u is not None and np.size(warm.u) == n and \
            np.all(np.isfinite(warm.u)):
        d = np.array(warm.u, dtype=float)
    free = np.zeros(n, bool)
    last = None
    hold = _warm_sets(warm, n)  # the first step's springs: the warm contact set's
    wall_size = np.where(np.isfinite(step.upper), np.abs(step.upper), 0.0) + \
        np.where(np.isfinite(step.lower), np.abs(step.lower), 0.0)
    it = 0
    while it < MAX_NEWTON:
        it += 1
        r, pu, pl, g = _residual(step, d, ku, kl)
        if last is not None and np.array_equal(pu, last[0]) and np.array_equal(pl, last[1]):
            break  # the springs of the full step are those it was computed with
        spring = np.where(pu, ku, 0.0) + np.where(pl, kl, 0.0)
        # at round-off (ROUNDOFF_ULPS ε of the terms of r): the minimiser
        scale = step.gradient_scale(d) + spring * (np.abs(d) + wall_size)
        if np.all(np.abs(r) <= ROUNDOFF_ULPS * EPS * scale):
            break
        if hold is not None:
            pu, pl = hold[0] & (ku > 0), hold[1] & (kl > 0) & ~hold[0]
            spring = np.where(pu, ku, 0.0) + np.where(pl, kl, 0.0)
            r = g.copy()
            r[pu] += ku[pu] * (d[pu] - step.upper[pu])
            r[pl] -= kl[pl] * (step.lower[pl] - d[pl])
            hold = None
        delta = -step.factor.face_solve(free, r, spring)
        slope1 = float(_residual(step, d + delta, ku, kl)[0] @ delta)
        if slope1 <= 0.0:  # f' still falls at the full step: take it
            d = d + delta
            last = (pu, pl)
        else:
            d = d + _line(step, d, delta, ku, kl, slope1) * delta
            last = None
    else:
        return StepSolution(d, np.zeros(n), np.zeros(n), Status.MAX_ITER, MAX_NEWTON,
                            time.perf_counter() - t0,
                            message=f"no settled spring set in {MAX_NEWTON} Newton steps")
    # one refinement on the same face (its factor is held: no rows are refactored)
    spring = np.where(pu, ku, 0.0) + np.where(pl, kl, 0.0)
    d = d - step.factor.face_solve(free, r, spring)
    R = -step.gradient(d)
    return StepSolution(d, np.maximum(R, 0.0), np.maximum(-R, 0.0), Status.SOLVED, it,
                        time.perf_counter() - t0, active_upper=pu, active_lower=pl,
                        time_source="wall")


__all__ = ["MAX_NEWTON", "solve_step", "springs", "takes"]
