"""Back-ends for the contact step.

For now two built-in exact solvers behind one seam: ``active-set`` (primal
active set on the banded Hessian, O(N) per change; the default) and ``lemke``
(complementary pivoting on the dense LCP form). A step solver is a callable
``(step, warm) -> StepSolution``; the full registry of back-ends plugs in here.
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import SolverNotFound
from .base import LCPSolution, Status, StepSolution
from .banded import solve_banded_qp, step_certificate


def _active_set(step, warm):
    if warm is None:
        return solve_banded_qp(step)
    return solve_banded_qp(step, start=warm.u, active_upper=warm.active_upper,
                           active_lower=warm.active_lower)


def _lemke(step, warm):
    from .lemke import lemke

    t0 = time.perf_counter()
    form = step.lcp("contact")
    setup = time.perf_counter() - t0
    res = lemke(form.M, form.q)
    n = step.size
    if res.status not in (Status.SOLVED, Status.INACCURATE):
        return StepSolution(np.zeros(n), np.zeros(n), np.zeros(n), res.status, res.iterations,
                            res.solve_time, setup, res.message)
    u = step.from_lcp(form, res.z)
    r_up = np.zeros(n)
    r_lo = np.zeros(n)
    m = form.n_gap
    r_up[form.rows] = np.maximum(res.w[:m], 0.0)
    if form.q.size > m:
        r_lo[form.rows] = np.maximum(res.z[m:], 0.0)
    upper = np.zeros(n, bool)
    upper[form.rows] = res.z[:m] <= 0.0
    sol = StepSolution(u, r_up, r_lo, res.status, res.iterations, res.solve_time, setup,
                       res.message, active_upper=upper)
    if sol.solved and step_certificate(step, sol) > 1e-7:
        sol.status = Status.INACCURATE
        sol.message = "Lemke's answer fails the KKT certificate of the step"
    return sol


STEP_SOLVERS = {"active-set": _active_set, "lemke": _lemke}


def step_solver(name: str):
    """The step solver called ``name`` ("auto" picks the default, active-set)."""
    if name == "auto":
        name = "active-set"
    try:
        return STEP_SOLVERS[name]
    except KeyError:
        raise SolverNotFound(
            f"unknown solver {name!r}; available: auto, {', '.join(STEP_SOLVERS)}"
        ) from None


__all__ = ["LCPSolution", "Status", "StepSolution", "step_solver", "STEP_SOLVERS"]
