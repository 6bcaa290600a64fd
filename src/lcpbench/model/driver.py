"""The nonlinear driver: re-linearise and solve contact steps until α stops moving.

Two schemes here; the paper's undamped one (α ← α̂ of eq. (21) after every step, Fig. 3)
runs in the compiled driver (:func:`lcpbench.model.compiled_driver.undamped`), and for
walls of any profile in :mod:`lcpbench.model.profile_driver`:

``method="globalised"`` (default) — the same steps, made safe. The iterate is
kept exactly feasible: a chain given by its node heights u (inverse kinematics
per link, the pins exactly on y = 0), starting from the unconstrained arc
clipped to the walls. The step û − u of the contact QP is a descent direction
of the true nonlinear energy on the convex set {walls respected}, so a
backtracking (Armijo) line search on that energy along u + t(û − u) converges
to a KKT point of the exact problem. Near the solution full steps are taken
and the scheme is the paper's.

``method="newton"`` — the globalised scheme with the exact Hessian of the
energy, H + T (:mod:`lcpbench.model.newton`), wherever it is positive
definite: quadratic instead of linear convergence near the answer.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from ..errors import ProblemError
from ..problems.scenes import Chain
from ..solvers.base import Status, StepSolution
from ..thresholds import NEWTON_SWITCH
from .chain import alpha_from_heights, energy
from .elastic import penalty_gradient
from .newton import newton_step
from .outer import (
    DriverOutput,
    DriverStart,
    StepRecord,
    armijo,
    converged_output,
    energy_noise,
    failed_output,
    feasible_start,
    line_search_failed,
    out_of_iterations,
    starting_point,
    step_failed,
    step_setup_time,
)
from .step import ContactStep, assemble_step

StepSolver = Callable[[ContactStep, "StepSolution | None"], StepSolution]

METHODS = ("globalised", "undamped", "newton")


def run_driver(
    chain: Chain,
    solver: StepSolver,
    *,
    tol: float = 1e-3,
    max_outer: int = 200,
    method: str = "globalised",
    start: DriverStart | None = None,
) -> DriverOutput:
    """Iterate contact steps to the equilibrium of ``chain``.

    Returns the final link angles and the reactions of the last step, with
    ``converged`` and a reason; never raises on non-convergence. A chain with
    a wall profile runs :mod:`lcpbench.model.profile_driver`. ``start``
    (globalised and Newton schemes) begins from a neighbouring scene's answer instead
    of the clipped unconstrained arc.
    """
    if chain.profiled_walls:
        if method not in METHODS:
            raise ProblemError(f"method must be one of {METHODS}, got {method!r}")
        from .profile_driver import run_profile_driver  # it imports this module

        return run_profile_driver(chain, solver, tol=tol, max_outer=max_outer,
                                  method=method, start=start)
    if method == "undamped":  # (flat walls: model.compiled.drive runs it compiled)
        raise ProblemError("method='undamped' on flat walls runs in the compiled driver "
                           "(lcpbench.model.compiled_driver.run), which takes a chain of "
                           "consecutive joints and contiguous free nodes from node 1")
    if method not in ("globalised", "newton"):
        raise ProblemError(f"method must be one of {METHODS}, got {method!r}")
    return _globalised(chain, solver, tol, max_outer, start, newton=method == "newton")


def _solve_step(chain, alpha, solver, warm, newton=False):
    t0 = time.perf_counter()
    step = assemble_step(chain, alpha)
    if newton:
        step, _ = newton_step(step, chain)
    t_asm = time.perf_counter() - t0
    sol = solver(step, warm)
    return step, sol, t_asm


def _globalised(chain: Chain, solver: StepSolver, tol: float, max_outer: int,
                start: DriverStart | None = None, newton: bool = False) -> DriverOutput:
    n = chain.free_nodes.size
    steps: list[StepRecord] = []
    u, alpha, warm = starting_point(chain, start, feasible_start)
    if alpha is None:
        return failed_output(chain.rest_alpha.copy(), n, steps, "cannot fit the chain between the walls")
    E = energy(chain, alpha)
    warm_start = start is not None and warm is not None  # a neighbour's answer: near already
    for _ in range(max_outer):
        near = newton and (steps[-1].max_dalpha < NEWTON_SWITCH if steps else warm_start)
        step, sol, t_asm = _solve_step(chain, alpha, solver, warm, near)
        if sol.status not in (Status.SOLVED, Status.INACCURATE):
            return step_failed(alpha, n, steps, sol, t_asm, E)
        dalpha = float(np.max(np.abs(step.predict_alpha(sol.u) - alpha), initial=0.0))
        d = sol.u - u
        grad = step.gradient(u)
        if step.elastic:  # the walls' springs are part of the energy searched on
            grad += penalty_gradient(step, u)
        slope = float(grad @ d)
        t, trial, E_t = armijo(lambda t, u=u, d=d, a=alpha: _trial(chain, u + t * d, a),
                               E, slope, energy_noise(chain, E))
        if trial is None:
            return line_search_failed(alpha, n, steps, sol, t_asm, dalpha, E)
        u, alpha, E = u + t * d, trial, E_t
        steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm,
                                t, dalpha, E, step_setup_time(sol)))
        warm = sol
        if dalpha < tol:
            return converged_output(chain, alpha, sol, steps, step)
    return out_of_iterations(alpha, n, steps, max_outer, tol)


def _trial(chain: Chain, u: np.ndarray, reference: np.ndarray):
    """(α, E(α)) of the chain at heights ``u``; (None, nan) where none fits."""
    alpha = alpha_from_heights(chain, u, reference)
    return (None, np.nan) if alpha is None else (alpha, energy(chain, alpha))

