"""The parts every outer loop shares: what it records, returns and starts from.

One step's record (:class:`StepRecord`), the answer a driver hands to the result
(:class:`DriverOutput`), a continuation's start (:class:`DriverStart`), the ways a
run ends (:func:`converged_output`, :func:`failed_output`, :func:`step_failed`,
:func:`line_search_failed`, :func:`out_of_iterations` with its stall test) and the
start from the unconstrained arc clipped to the walls (:func:`feasible_start`,
:func:`starting_point`), and the Armijo search on the exact energy around the one
compiled rule (:func:`armijo`, :func:`energy_noise`). The profile, large-N
and compiled drivers and the solve kernel's Python side all build their answers
here, so one answer reads the same whichever loop ran.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..problems.scenes import Chain
from ..solvers.base import StepSolution
from ..thresholds import ARMIJO_SHORTEST, LOCAL_CUT
from .chain import alpha_from_heights, heights
from .profile import split_reactions
from .step import ContactStep
from .step_solver import step_residuals

#: the outer loop's schemes (``method``): "globalised" (the Armijo search on the exact
#: energy), "undamped" (the paper's Fig. 3: α ← α̂ after every step), "newton" (the
#: globalised scheme with the exact Hessian H + T near the answer)
METHODS = ("globalised", "undamped", "newton")

#: a step solver: ``(step, warm) -> StepSolution`` (:func:`.step_solver.make_step_solver`)
StepSolver = Callable[[ContactStep, "StepSolution | None"], StepSolution]


def _rule():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.model.chain_kernel", "armijo")


def energy_noise(chain: Chain, E: float) -> float:
    """The round-off an energy comparison at ``E`` allows
    (:func:`lcpbench.model.chain_kernel.energy_noise`)."""
    return float(_rule().energy_noise(E, float(np.sum(np.abs(chain.joint_stiffness)))))


def armijo(at: Callable, E: float, slope: float, noise: float, local: bool = False):
    """Backtracking on the exact energy (or a merit): the first t in 1, ½, ¼, … whose
    trial ``at(t)`` = (α, E(α)) (α None where no chain fits) passes
    :func:`lcpbench.model.chain_kernel.armijo`, as (t, α, E(α)); (0, None, E) where
    none down to ARMIJO_SHORTEST does. ``local`` (a wall profile near the answer): a
    step cut below LOCAL_CUT is taken in full (the undamped fixed point,
    the large-N driver's wall profiles, :mod:`.large_driver`)."""
    rule = _rule().armijo
    t = 1.0
    while True:
        trial, E_t = at(t)
        step = rule(t, math.nan if trial is None else float(E_t), E, slope, noise,
                    ARMIJO_SHORTEST)
        if step == t:
            return t, trial, E_t
        if step == 0.0:
            return 0.0, None, E
        t = step
        if local and t < LOCAL_CUT:
            trial, E_t = at(1.0)
            if trial is not None:
                return 1.0, trial, E_t
            local = False


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
    # λ, the closure's multiplier, where the SQP in the link angles found the answer
    closure_multiplier: float | None = None


@dataclass
class DriverStart:
    """Where a continuation starts: a neighbouring scene's answer (same chain size).

    ``alpha`` are its link angles; ``warm`` its last contact step, handed to
    back-ends that accept a warm start; ``multipliers`` its (λ, R upper, R lower per
    free node), the first multipliers and active set of the SQP in the link angles
    (:func:`lcpbench.model.angle_step.solve_in_angles`), λ = 0 where unknown.
    """

    alpha: np.ndarray
    warm: StepSolution | None = None
    multipliers: tuple | None = None


def failed_output(alpha, n, steps, reason) -> DriverOutput:
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
    return failed_output(alpha, n, steps, reason)


def step_failed(alpha, n, steps, sol: StepSolution, t_asm: float, E: float) -> DriverOutput:
    steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm, 0.0,
                            np.nan, E, step_setup_time(sol)))
    return failed_output(alpha, n, steps, f"contact step not solved ({sol.status.value}: {sol.message})")


def converged_output(chain: Chain, alpha, sol: StepSolution, steps,
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


def step_setup_time(sol) -> float:
    """A step's setup time: the back-end's own setup and lcpbench's building of its form."""
    return float(getattr(sol, "setup_time", 0.0) or 0.0) + float(
        getattr(sol, "build_time", 0.0) or 0.0)


def feasible_start(chain: Chain, alpha0: np.ndarray):
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


def line_search_failed(alpha, n: int, steps: list[StepRecord], sol: StepSolution,
                       t_asm: float, dalpha: float, E: float) -> DriverOutput:
    """The answer of a line search that found no decrease (the step recorded, t = 0)."""
    steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm, 0.0,
                            dalpha, E, step_setup_time(sol)))
    return failed_output(alpha, n, steps, "line search failed: no decrease of the energy along "
                                  "the step")
