"""The nonlinear driver: re-linearise and solve contact steps until α stops moving.

Three schemes (the first two are Fig. 3 of the paper):

``method="undamped"`` — the paper's: α ← α̂ of eq. (21) after every step,
until max|α̂ − α| < tol. Each step is a Gauss–Newton step on the energy; taken
in full it can leave the region where the linearisation is valid (links
passing vertical, 1/cos α blowing up), which is why it is kept: benchmarks
show where it breaks.

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

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..errors import ProblemError
from ..problems.scenes import Chain
from ..solvers.base import Status, StepSolution
from .chain import alpha_from_heights, energy, heights
from .elastic import penalty_gradient
from .judge import split_reactions
from .newton import newton_step
from .step import ContactStep, assemble_step
from .step_solver import step_residuals

StepSolver = Callable[[ContactStep, "StepSolution | None"], StepSolution]

METHODS = ("globalised", "undamped", "newton")
#: the Newton scheme takes Gauss–Newton steps until the last step moved α by less
#: than this (rad): far from the answer the exact curvature of the energy only
#: lengthens the steps the line search then cuts (6 outer iterations instead of 4
#: on the default scene at 1e-3 with Newton from the start)
NEWTON_SWITCH = 0.05


@dataclass
class StepRecord:
    """What one outer iteration did."""

    iterations: int
    status: str
    solve_time: float
    assemble_time: float
    step_length: float
    max_dalpha: float
    energy: float
    setup_time: float = 0.0  # the back-end's setup and lcpbench's building of its form (s)


@dataclass
class DriverOutput:
    """What the driver hands to the result: link angles α (rad), the wall
    reactions R (eq. 30) of the last step per free node (N, upper and lower
    wall), whether max|α̂ − α| < tol was reached and why not."""

    alpha: np.ndarray
    forces_upper: np.ndarray
    forces_lower: np.ndarray
    converged: bool
    reason: str
    steps: list[StepRecord] = field(default_factory=list)
    last_step: StepSolution | None = None  # for a continuation start of the next scene
    # the back-end's own multipliers of the last step, kept beside R for comparison
    multipliers_upper: np.ndarray | None = None
    multipliers_lower: np.ndarray | None = None


@dataclass
class DriverStart:
    """Where a continuation starts: a neighbouring scene's answer (same chain size).

    ``alpha`` are its link angles; ``warm`` its last contact step, handed to
    back-ends that accept a warm start.
    """

    alpha: np.ndarray
    warm: StepSolution | None = None


def _fail(alpha, n, steps, reason) -> DriverOutput:
    zero = np.zeros(n)
    return DriverOutput(alpha, zero, zero.copy(), False, reason, steps)


#: Outer iterations without a new low of max|Δα| (halving the best before them) after
#: which a run out of iterations is reported as stalled. A linear contraction as slow
#: as 0.93 per step still halves it in 10.
STALL_STEPS = 10
#: A stall at or below this max|Δα| (rad) is the accuracy of the contact steps (their
#: round-off, or a back-end's own tolerance): the nodes then move by less than 1e-10 of
#: the chain's length per step, far below any physical meaning of the answer.
STEP_ACCURACY_DALPHA = 1e-10


def stall(steps: list[StepRecord]) -> tuple[float, int] | None:
    """``(level, since)`` when the outer iteration stalled: the smallest max|Δα| of the
    last :data:`STALL_STEPS` steps, ``level``, is not below half the smallest before
    them (no new low: a contraction even as slow as 0.93 per step makes one); ``since``
    is the first outer iteration (from 1) at or below twice ``level``. None when it was
    still falling, or the run is shorter than twice :data:`STALL_STEPS`."""
    d = [s.max_dalpha for s in steps]
    if len(d) < 2 * STALL_STEPS or not all(map(math.isfinite, d)):
        return None
    level = min(d[-STALL_STEPS:])
    if level < 0.5 * min(d[:-STALL_STEPS]):
        return None
    return level, next(i for i, v in enumerate(d) if v <= 2.0 * level) + 1


def out_of_iterations(alpha, n: int, steps: list[StepRecord], max_outer: int,
                      tol: float | None) -> DriverOutput:
    """The answer of a driver that ran its ``max_outer`` outer iterations. Its reason
    says when max|Δα| had stalled (:func:`stall`); at or below
    :data:`STEP_ACCURACY_DALPHA`, that this is the accuracy of the contact steps, and
    whether the requested ``tol`` is below it (the driver cannot reach it)."""
    reason = (f"no convergence in {max_outer} outer iterations "
              f"(last max|Δα| = {steps[-1].max_dalpha:.2e} rad)")
    stalled = stall(steps)
    if stalled is not None:
        level, since = stalled
        reason += (f": max|Δα| stalled, no lower than {level:.2e} rad over the last "
                   f"{STALL_STEPS} steps and within a factor 2 of that since outer "
                   f"iteration {since}")
        if level <= STEP_ACCURACY_DALPHA:
            reason += ", the accuracy of the contact steps"
            if tol is not None and tol < level:
                reason += f"; tol = {tol:.3g} rad is below it, out of the driver's reach"
    return _fail(alpha, n, steps, reason)


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
    if method == "undamped":
        if start is not None:
            raise ProblemError("a continuation start needs method='globalised'")
        return _undamped(chain, solver, tol, max_outer)
    if method not in ("globalised", "newton"):
        raise ProblemError(f"method must be one of {METHODS}, got {method!r}")
    return _globalised(chain, solver, tol, max_outer, start, newton=method == "newton")


def _step_failed(alpha, n, steps, sol: StepSolution, t_asm: float, E: float) -> DriverOutput:
    steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm, 0.0,
                            np.nan, E, _setup(sol)))
    return _fail(alpha, n, steps, f"contact step not solved ({sol.status.value}: {sol.message})")


def _converged(chain: Chain, alpha, sol: StepSolution, steps,
               step: ContactStep | None = None) -> DriverOutput:
    """The driver's criterion is met: R = K g + z from the last step's primal (its
    ``forces_net``, or computed from ``step``), the back-end's multipliers beside it.
    Round-off in R is the judge's to clean (:mod:`lcpbench.model.judge`)."""
    net = sol.forces_net
    if net is None or not np.all(np.isfinite(net)):
        if step is None:
            raise ValueError("a converged step needs its forces_net or its ContactStep")
        net = step_residuals(step, sol.u)[1]
    upper, lower = split_reactions(chain, net, sol.u)
    reason = "converged" if sol.solved else "converged (last step inaccurate)"
    return DriverOutput(alpha, upper, lower, True, reason, steps, last_step=sol,
                        multipliers_upper=sol.forces_upper, multipliers_lower=sol.forces_lower)


def _setup(sol) -> float:
    """A step's setup time: the back-end's own setup and lcpbench's building of its form."""
    return float(getattr(sol, "setup_time", 0.0) or 0.0) + float(
        getattr(sol, "build_time", 0.0) or 0.0)


def _solve_step(chain, alpha, solver, warm, newton=False):
    t0 = time.perf_counter()
    step = assemble_step(chain, alpha)
    if newton:
        step, _ = newton_step(step, chain)
    t_asm = time.perf_counter() - t0
    sol = solver(step, warm)
    return step, sol, t_asm


def _feasible_start(chain: Chain, alpha0: np.ndarray):
    """Node heights clipped to the walls, and the chain through them (None if none fits)."""
    u = np.clip(heights(chain, alpha0), chain.lower, chain.upper)
    return u, alpha_from_heights(chain, u, alpha0)


def starting_point(chain: Chain, start: DriverStart | None, fit: Callable):
    """(u, α, warm) to begin from: a neighbour's answer ``start`` fitted to this
    scene's walls by ``fit(chain, α) -> (u, α or None)``, else the unconstrained arc
    (α None where neither fits)."""
    if start is not None:
        u, alpha = fit(chain, np.asarray(start.alpha, float))
        if alpha is not None:
            return u, alpha, start.warm
    u, alpha = fit(chain, chain.rest_alpha)
    return u, alpha, None


def _globalised(chain: Chain, solver: StepSolver, tol: float, max_outer: int,
                start: DriverStart | None = None, newton: bool = False) -> DriverOutput:
    n = chain.free_nodes.size
    steps: list[StepRecord] = []
    u, alpha, warm = starting_point(chain, start, _feasible_start)
    if alpha is None:
        return _fail(chain.rest_alpha.copy(), n, steps, "cannot fit the chain between the walls")
    E = energy(chain, alpha)
    warm_start = start is not None and warm is not None  # a neighbour's answer: near already
    for _ in range(max_outer):
        near = newton and (steps[-1].max_dalpha < NEWTON_SWITCH if steps else warm_start)
        step, sol, t_asm = _solve_step(chain, alpha, solver, warm, near)
        if sol.status not in (Status.SOLVED, Status.INACCURATE):
            return _step_failed(alpha, n, steps, sol, t_asm, E)
        dalpha = float(np.max(np.abs(step.predict_alpha(sol.u) - alpha), initial=0.0))
        d = sol.u - u
        grad = step.gradient(u)
        if step.elastic:  # the walls' springs are part of the energy searched on
            grad += penalty_gradient(step, u)
        slope = float(grad @ d)
        noise = 1e-12 * (abs(E) + float(np.sum(np.abs(chain.joint_stiffness))) * 1e-6)
        t, trial, E_t = armijo(chain, lambda t, u=u, d=d, a=alpha: alpha_from_heights(chain, u + t * d, a),
                               E, slope, noise)
        if trial is None:
            return line_search_failed(alpha, n, steps, sol, t_asm, dalpha, E)
        u, alpha, E = u + t * d, trial, E_t
        steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm,
                                t, dalpha, E, _setup(sol)))
        warm = sol
        if dalpha < tol:
            return _converged(chain, alpha, sol, steps, step)
    return out_of_iterations(alpha, n, steps, max_outer, tol)


def armijo(chain: Chain, trial_of, E: float, slope: float, noise: float):
    """Backtracking on the exact energy: the first t in 1, ½, ¼, … with
    E(trial_of(t)) ≤ E + 1e-4 t min(slope, 0) + noise, as (t, α, E(α));
    (0, None, E) below t = 1e-12. ``trial_of(t)`` is the chain at t (None where
    none fits)."""
    t = 1.0
    while t >= 1e-12:
        trial = trial_of(t)
        if trial is not None:
            E_t = energy(chain, trial)
            if E_t <= E + 1e-4 * t * min(slope, 0.0) + noise:
                return t, trial, E_t
        t *= 0.5
    return 0.0, None, E


def line_search_failed(alpha, n: int, steps: list[StepRecord], sol: StepSolution,
                       t_asm: float, dalpha: float, E: float) -> DriverOutput:
    """The answer of a line search that found no decrease (the step recorded, t = 0)."""
    steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm, 0.0,
                            dalpha, E, _setup(sol)))
    return _fail(alpha, n, steps, "line search failed: no decrease of the energy along "
                                  "the step")


def _undamped(chain: Chain, solver: StepSolver, tol: float, max_outer: int) -> DriverOutput:
    n = chain.free_nodes.size
    steps: list[StepRecord] = []
    alpha = chain.rest_alpha.copy()
    branch = np.sign(np.cos(alpha))
    warm: StepSolution | None = None
    for _ in range(max_outer):
        step, sol, t_asm = _solve_step(chain, alpha, solver, warm)
        if sol.status not in (Status.SOLVED, Status.INACCURATE):
            return _step_failed(alpha, n, steps, sol, t_asm, np.nan)
        new = step.predict_alpha(sol.u)
        dalpha = float(np.max(np.abs(new - alpha), initial=0.0))
        steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm, 1.0,
                                dalpha, np.nan, _setup(sol)))
        if not np.all(np.isfinite(new)):
            return _fail(alpha, n, steps, "diverged: non-finite link angles")
        if np.any(np.sign(np.cos(new)) != branch):
            return _fail(new, n, steps, "diverged: a link passed the vertical, where the "
                                        "linearisation of eq. (20) is singular")
        alpha = new
        warm = sol
        if dalpha < tol:
            return _converged(chain, alpha, sol, steps, step)
    return out_of_iterations(alpha, n, steps, max_outer, tol)
