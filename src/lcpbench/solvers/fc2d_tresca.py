"""2-D Coulomb friction by a fixed point of Tresca problems, each a box QP.

The problem is Siconos' fc2d form (:mod:`.siconos_fc2d`): u = W r + q per contact
u_c = (u_n, u_t), r_c = (r_n, r_t), W symmetric positive semidefinite. With the slip
bounds b_c fixed (Tresca friction: |r_t| <= b_c in place of |r_t| <= μ_c r_n), the
conditions 0 <= r_n ⟂ u_n >= 0, |r_t| <= b_c, r_t = −b_c sign(u_t) where u_t ≠ 0 are
the optimality conditions of the box QP

    minimise ½ rᵀ W r + qᵀ r   subject to   r_n >= 0,  −b_c <= r_t <= b_c

(its gradient W r + q is u; a bound that holds r_t at +b_c needs u_t <= 0, the force
opposing the slip). Any QP back-end of the registry solves it. The classical fixed
point (Panagiotopoulos; Haslinger's method of successive approximations): start from
b = 0, solve, set b = μ r_n, repeat until the answer satisfies Coulomb's law (a Tresca
answer whose bounds are μ r_n of its own r_n is a Coulomb answer), or b no longer
moves (:data:`FIXED_TOL`). It is not always reached (the map is a
contraction for small μ only): the loop has a limit and reports MAX_ITER there.
SOLVED only where the Signorini–Coulomb residual
(:func:`.siconos_fc2d.coulomb_residual`, lcpbench's own) is below
:data:`.siconos_fc2d.ACCEPT_TOL`.
"""

from __future__ import annotations

import time

import numpy as np

from .base import BoxQP, QPWarm, Settings, Status
from .siconos_fc2d import ACCEPT_TOL, FC2DSolution, coulomb_residual, fc2d_arrays

#: the fixed point stops, SOLVED or not, when max|b_new − b| <= FIXED_TOL · max(1, max b)
FIXED_TOL = 1e-13
#: the default limit on Tresca problems per solve
MAX_FIXED = 60


def next_bounds(W, q, mu, r, bound) -> tuple[np.ndarray, bool, bool, float]:
    """One update of the fixed point from a Tresca answer ``r`` (bounds ``bound``):
    ``(b = μ r_n, solved, fixed, residual)``: solved where ``r`` satisfies Coulomb's law
    (lcpbench's residual below ACCEPT_TOL: a Tresca answer whose bounds are μ r_n of its
    own r_n is a Coulomb answer), fixed where the bounds no longer move
    (:data:`FIXED_TOL`). The loop around it is the caller's: a QP back-end's here, the
    active set's pivoting in :func:`lcpbench.solvers.fc2d_active.tresca_fixed_point`."""
    new = mu * np.maximum(r[0::2], 0.0)
    moved = float(np.max(np.abs(new - bound), initial=0.0))
    residual = coulomb_residual(W, q, mu, r)
    return (new, residual <= ACCEPT_TOL,
            moved <= FIXED_TOL * max(1.0, float(np.max(new, initial=0.0))), residual)


def tresca_qp(W: np.ndarray, q: np.ndarray, bound: np.ndarray) -> BoxQP:
    """The Tresca problem with slip bounds ``bound`` (one per contact) as a box QP."""
    import scipy.sparse as sp  # at the first QP, not at start-up

    nc = bound.size
    lower = np.zeros(2 * nc)
    upper = np.full(2 * nc, np.inf)
    lower[1::2], upper[1::2] = -bound, bound
    P = sp.csc_matrix(0.5 * (W + W.T))
    return BoxQP(P, np.asarray(q, float).copy(), lower, upper)


def solve_fc2d_tresca(W, q, mu, solve_qp, settings: Settings, *, options: dict | None = None,
                      max_fixed: int = MAX_FIXED, warm: bool = True) -> FC2DSolution:
    """Coulomb friction as a fixed point of Tresca box QPs, each solved by
    ``solve_qp(qp, settings, warm, **options)`` (a QP back-end's function). ``warm``:
    hand each QP the last answer (back-ends without a warm start ignore it). Never
    raises for a solver failure: the QP's status (not SOLVED) or MAX_ITER with a message.
    """
    W, q, mu = fc2d_arrays(W, q, mu)
    nc = mu.size
    t0 = time.perf_counter()
    bound = np.zeros(nc)
    r = np.full(2 * nc, np.nan)
    last = None
    qps = 0
    fixed = solved = False
    residual = np.inf
    for qps in range(1, max_fixed + 1):
        res = solve_qp(tresca_qp(W, q, bound), settings, last if warm else None,
                       **(options or {}))
        if res.status is not Status.SOLVED or not np.all(np.isfinite(res.x)):
            nan = np.full(2 * nc, np.nan)
            status = res.status if res.status is not Status.SOLVED else Status.FAILED
            return FC2DSolution(r if np.all(np.isfinite(r)) else nan, nan, status, qps,
                                message=f"Tresca problem {qps}: {res.status.name} "
                                        f"({res.message})",
                                extra={"qps": qps, "solve_time": time.perf_counter() - t0})
        r = res.x.copy()
        last = QPWarm(res.x, res.y)
        bound, solved, fixed, residual = next_bounds(W, q, mu, r, bound)
        if solved or fixed:
            break
    u = W @ r + q
    extra = {"qps": qps, "solve_time": time.perf_counter() - t0}
    if solved:
        return FC2DSolution(r, u, Status.SOLVED, qps, residual, "", extra)
    if fixed:
        return FC2DSolution(r, u, Status.INACCURATE, qps, residual,
                            f"fixed point reached, Coulomb residual {residual:.3g}", extra)
    return FC2DSolution(r, u, Status.MAX_ITER, qps, residual,
                        f"no fixed point in {max_fixed} Tresca problems (Coulomb residual "
                        f"{residual:.3g})", extra)
