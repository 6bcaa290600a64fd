"""Primal active-set method for the contact step on its banded Hessian.

Solves ``min ½ uᵀHu + cᵀu  s.t.  lower <= u <= upper`` with H symmetric
positive definite and pentadiagonal (a :class:`~lcpbench.model.step.ContactStep`).
Every iterate is feasible; each iteration minimises over the current face
with one banded Cholesky solve (O(N)), then either moves to a blocking wall or
releases the wall with the most negative reaction (Nocedal & Wright, Alg.
16.3). It terminates in finitely many steps on a strictly convex QP; a warm
start with the previous step's contact set usually needs one or two.

The answer is certified before it is called solved: primal feasibility,
stationarity on the free nodes and non-negative reactions, each against a
round-off scale computed from the size of the terms that cancel.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.linalg import LinAlgError, solveh_banded

from .base import Status, StepSolution

EPS = np.finfo(float).eps


def _sub_bands(bands: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Lower banded storage of the principal submatrix H[idx, idx] (idx sorted).

    A principal submatrix of a matrix of bandwidth b has bandwidth at most b:
    its entry (p + k, p) is H[idx[p + k], idx[p]], read from the bands when
    the two indices are at most b apart.
    """
    b = bands.shape[0] - 1
    m = idx.size
    sub = np.zeros((max(min(b, m - 1), 0) + 1, m))
    sub[0] = bands[0, idx]
    for k in range(1, sub.shape[0]):
        gap = idx[k:] - idx[:-k]
        ok = gap <= b
        vals = np.zeros(m - k)
        vals[ok] = bands[gap[ok], idx[:-k][ok]]
        sub[k, : m - k] = vals
    return sub


def solve_banded_qp(
    step,
    *,
    start: np.ndarray | None = None,
    active_upper: np.ndarray | None = None,
    active_lower: np.ndarray | None = None,
    max_iter: int | None = None,
    rtol: float = 1e-9,
) -> StepSolution:
    """Solve a contact step exactly by the primal active-set method.

    Parameters
    ----------
    step : ContactStep
    start : feasible (or to-be-clipped) starting heights; default: the
        unconstrained minimiser clipped to the walls.
    active_upper, active_lower : boolean masks of walls to start in contact
        (a warm start, e.g. the previous step's contact set).
    max_iter : active-set changes allowed (default 20 n + 50).
    rtol : relative tolerance of the final certificate.
    """
    t0 = time.perf_counter()
    lo, hi = step.lower, step.upper
    n = step.size
    max_iter = 20 * n + 50 if max_iter is None else max_iter
    try:
        if start is None:
            start = step.unconstrained_minimiser()
        u = np.clip(np.asarray(start, dtype=float), lo, hi)
        W_up = np.isfinite(hi) & (u >= hi)
        W_lo = np.isfinite(lo) & (u <= lo) & ~W_up
        if active_upper is not None:
            W_up |= active_upper & np.isfinite(hi)
        if active_lower is not None:
            W_lo |= active_lower & np.isfinite(lo) & ~W_up
        u[W_up] = hi[W_up]
        u[W_lo] = lo[W_lo]
        at_minimiser = False  # True after a full step: u minimises H on the current face
        for it in range(1, max_iter + 1):
            free = ~(W_up | W_lo)
            if at_minimiser or not free.any():
                grad = step.gradient(u)
                noise = 64 * EPS * step.gradient_scale(u)
                lam_up = np.where(W_up, -grad, np.inf) / noise  # upper-wall reactions
                lam_lo = np.where(W_lo, grad, np.inf) / noise
                worst_up, worst_lo = int(np.argmin(lam_up)), int(np.argmin(lam_lo))
                if min(lam_up[worst_up], lam_lo[worst_lo]) >= -1.0:
                    return _finish(step, u, W_up, W_lo, it, t0, rtol)
                if lam_up[worst_up] <= lam_lo[worst_lo]:
                    W_up[worst_up] = False
                else:
                    W_lo[worst_lo] = False
                at_minimiser = False
                continue
            # Newton step on the current face, as an increment (accurate near the answer)
            idx = np.flatnonzero(free)
            p = np.zeros(n)
            p[idx] = solveh_banded(
                _sub_bands(step.bands, idx), -step.gradient(u)[idx], lower=True,
                check_finite=False,
            )
            if not np.all(np.isfinite(p)):
                return _fail(step, u, it, t0, "non-finite face minimiser")
            # ratio test: the first wall met along p (smallest index on ties)
            with np.errstate(divide="ignore", invalid="ignore"):
                t_up = np.where(free & (p > 0) & np.isfinite(hi), (hi - u) / p, np.inf)
                t_lo = np.where(free & (p < 0) & np.isfinite(lo), (lo - u) / p, np.inf)
            j_up, j_lo = int(np.argmin(t_up)), int(np.argmin(t_lo))
            t = min(1.0, t_up[j_up], t_lo[j_lo])
            u = u + max(t, 0.0) * p
            if t < 1.0:
                if t_up[j_up] <= t_lo[j_lo]:
                    W_up[j_up] = True
                    u[j_up] = hi[j_up]
                else:
                    W_lo[j_lo] = True
                    u[j_lo] = lo[j_lo]
            else:
                at_minimiser = True
        sol = _finish(step, u, W_up, W_lo, max_iter, t0, rtol)
        sol.status = Status.MAX_ITER
        sol.message = f"active-set limit of {max_iter} changes reached"
        return sol
    except (LinAlgError, ValueError) as exc:
        return _fail(step, np.zeros(n), 0, t0, f"{type(exc).__name__}: {exc}")


def _finish(step, u, W_up, W_lo, iterations, t0, rtol) -> StepSolution:
    grad = step.gradient(u)
    r_up = np.where(W_up, np.maximum(-grad, 0.0), 0.0)
    r_lo = np.where(W_lo, np.maximum(grad, 0.0), 0.0)
    elapsed = time.perf_counter() - t0
    sol = StepSolution(
        u=u, reaction_upper=r_up, reaction_lower=r_lo, status=Status.SOLVED,
        iterations=iterations, solve_time=elapsed,
        active_upper=W_up.copy(), active_lower=W_lo.copy(),
    )
    err = step_certificate(step, sol)
    if err > rtol:
        sol.status = Status.INACCURATE
        sol.message = f"certificate residual {err:.2e} > {rtol:.1e}"
    return sol


def _fail(step, u, iterations, t0, message) -> StepSolution:
    n = step.size
    return StepSolution(
        u=u, reaction_upper=np.zeros(n), reaction_lower=np.zeros(n), status=Status.FAILED,
        iterations=iterations, solve_time=time.perf_counter() - t0, message=message,
    )


def step_certificate(step, sol: StepSolution) -> float:
    """Scaled KKT residual of a step solution, the same for every back-end.

    max over rows of |H u + c − R_lower + R_upper| (stationarity), bound
    violations and |gap·R| (complementarity), each divided by the size of the
    terms that make it up, so 1e-12 means "round-off" whatever the units.
    """
    u, ru, rl = sol.u, sol.reaction_upper, sol.reaction_lower
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(ru)) and np.all(np.isfinite(rl))):
        return np.inf
    grad = step.gradient(u)
    size = step.gradient_scale(u) + ru + rl
    force = max(float(np.max(size, initial=0.0)), np.finfo(float).tiny)
    stat = np.max(np.abs(grad + ru - rl), initial=0.0) / force
    span = 1.0 + np.max(np.abs(u), initial=0.0)
    g_up = np.where(np.isfinite(step.upper), step.upper - u, np.inf)
    g_lo = np.where(np.isfinite(step.lower), u - step.lower, np.inf)
    feas = max(-np.min(g_up, initial=0.0), -np.min(g_lo, initial=0.0), 0.0) / span
    neg = max(-np.min(ru, initial=0.0), -np.min(rl, initial=0.0), 0.0) / force
    comp_up = np.abs(np.where(np.isfinite(g_up), g_up, 0.0) * ru)
    comp_lo = np.abs(np.where(np.isfinite(g_lo), g_lo, 0.0) * rl)
    comp = max(np.max(comp_up, initial=0.0), np.max(comp_lo, initial=0.0)) / (force * span)
    return float(max(stat, feas, neg, comp))


# -- the back-end interface ---------------------------------------------------
class _BandedBoxQP:
    """A general :class:`~lcpbench.solvers.base.BoxQP` in the shape the active
    set needs (bands, gradient, a round-off scale of the gradient)."""

    def __init__(self, qp):
        self.P = qp.P
        self.linear = np.asarray(qp.c, dtype=float)
        self.lower = np.asarray(qp.lower, dtype=float)
        self.upper = np.asarray(qp.upper, dtype=float)
        self.bands = qp.bands if qp.bands is not None else dense_to_bands(qp.dense())
        self.absP = abs(self.P)

    @property
    def size(self) -> int:
        return self.linear.size

    def gradient(self, u):
        return self.P @ u + self.linear

    def gradient_scale(self, u):
        return self.absP @ np.abs(u) + np.abs(self.linear) + np.finfo(float).tiny

    def unconstrained_minimiser(self):
        return solveh_banded(self.bands, -self.linear, lower=True, check_finite=False)


def dense_to_bands(P: np.ndarray) -> np.ndarray:
    """Lower banded storage of a symmetric matrix, at its actual bandwidth."""
    n = P.shape[0]
    rows, cols = np.nonzero(np.tril(P))
    b = int(np.max(rows - cols, initial=0))
    bands = np.zeros((b + 1, n))
    for k in range(b + 1):
        bands[k, : n - k] = np.diagonal(P, -k)
    return bands


def _warm_sets(warm, n):
    if warm is None:
        return None, None, None
    x = getattr(warm, "u", None)
    if x is None:
        x = warm.x
    up = getattr(warm, "active_upper", None)
    lo = getattr(warm, "active_lower", None)
    return x, up, lo


def solve_step(step, settings, warm=None, **options) -> StepSolution:
    """The contact step by the active set on its own banded, factored form.

    The method is scale-invariant (its tests are relative to the size of the
    terms that cancel), so it always works on the step in physical units.
    """
    x, up, lo = _warm_sets(warm, step.size)
    max_iter = settings.max_iter if settings.max_iter else None
    return solve_banded_qp(step, start=x, active_upper=up, active_lower=lo, max_iter=max_iter)


def solve_qp(qp, settings, warm=None, **options):
    """Any bound-constrained QP with positive-definite P (banded or not)."""
    from .base import QPResult

    t0 = time.perf_counter()
    try:
        prob = _BandedBoxQP(qp)
    except (LinAlgError, ValueError) as exc:
        return QPResult.failure(qp.size, Status.FAILED, f"{type(exc).__name__}: {exc}")
    setup = time.perf_counter() - t0
    x, _, _ = _warm_sets(warm, qp.size)
    max_iter = settings.max_iter if settings.max_iter else None
    sol = solve_banded_qp(prob, start=x, max_iter=max_iter)
    y = sol.reaction_upper - sol.reaction_lower
    return QPResult(sol.u, y, sol.status, sol.iterations, sol.solve_time, setup, sol.message,
                    time_source="solver")
