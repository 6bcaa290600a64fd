"""The driver for walls of any profile: contact steps with lagged wall slopes.

The globalised scheme of :mod:`lcpbench.model.compiled_driver`, in Python, with the step of
:func:`lcpbench.model.profile.profile_step`: at each outer iteration the box
is the profile at the nodes' current x and the slope of the wall enters the
linear term through the last step's reactions (lagged multipliers). The
globalised and Newton schemes line-search the merit

    Φ(u) = E(u) − Σ μ̄_k h(x_k(u)) + Σ ν̄_k l(x_k(u))

(the energy plus the work of the lagged reactions along the wall), whose
Gauss–Newton model the step minimises, plus an l1 penalty σ·Σ(penetration of
the exact walls), σ = PENALTY × the largest reaction: the walls move under the
nodes as x moves, and the step that puts a node back on its wall costs energy
that only the penalty repays (as in SQP's exact-penalty merit). Near the
answer a step the merit would cut below LOCAL_CUT is taken in full (the
undamped fixed point, which converges locally). The undamped scheme takes
full steps throughout.
It stops when max|Δα| < tol and the chain is on the right side of the exact
walls (h(x) at the new x) to GEOMETRY_SLACK·ℓ: one more step is taken when
the walls moved under the nodes by more. The answer is judged like every
other (:mod:`lcpbench.model.judge`), on the exact KKT conditions of the
profile problem.
"""

from __future__ import annotations

import time

import numpy as np

from ..problems.scenes import Chain
from ..solvers.base import Status
from ..thresholds import GEOMETRY_SLACK, NEWTON_SWITCH, PENALTY, START_PASSES
from .chain import alpha_from_heights, heights, node_positions
from .chain import energy as chain_energy
from .judge import split_reactions
from .newton import newton_step
from .outer import (
    DriverOutput,
    DriverStart,
    StepRecord,
    armijo,
    converged_output,
    energy_noise,
    failed_output,
    out_of_iterations,
    starting_point,
    step_failed,
    step_setup_time,
)
from .profile import profile_gaps, profile_step, walls_at


def penetration(chain: Chain, alpha: np.ndarray) -> float:
    up, lo = profile_gaps(chain, alpha)
    rows_up = np.isfinite(chain.upper)
    worst = max(0.0, -float(np.min(up[rows_up], initial=np.inf)))
    if lo is not None:
        rows_lo = np.isfinite(chain.lower)
        worst = max(worst, -float(np.min(lo[rows_lo], initial=np.inf)))
    return worst


def merit(chain: Chain, alpha: np.ndarray, mu_up: np.ndarray, mu_lo: np.ndarray,
          sigma: float, energy: float | None = None) -> float:
    """P = E − Σ μ̄ h(x_k) + Σ ν̄ l(x_k) + σ·Σ(penetration of the exact walls) (N·mm):
    one forward kinematics and one evaluation of each profile. ``energy``: E given
    (the large-N driver adds its compensated E itself, 0 here); None: computed."""
    x, y = node_positions(chain, alpha)
    xf, yf = x[chain.free_nodes], y[chain.free_nodes]
    total = chain_energy(chain, alpha) if energy is None else energy
    for prof, mu, limit, sign in ((chain.upper_profile, mu_up, chain.upper, 1.0),
                                  (chain.lower_profile, mu_lo, chain.lower, -1.0)):
        rows = np.isfinite(limit)
        wall = prof(xf) if prof is not None else limit
        if prof is not None:
            total -= sign * float(np.sum(np.where(mu > 0, mu, 0.0) * wall))
        if sigma:
            total += sigma * float(np.sum(np.maximum(sign * (yf - wall), 0.0)[rows]))
    return total


def _clipped(chain: Chain, alpha0: np.ndarray):
    """Heights clipped to the walls at the nodes' x, a few times (x moves with them)."""
    alpha = alpha0
    u = heights(chain, alpha0)
    for _ in range(START_PASSES):
        at = walls_at(chain, alpha)
        u = np.clip(heights(chain, alpha), at.lower, at.upper)
        trial = alpha_from_heights(chain, u, alpha)
        if trial is None:
            return u, None
        alpha = trial
    return u, alpha


def profile_start(chain: Chain, alpha0: np.ndarray):
    """The clipped shape of ``alpha0``; where a steep wall makes clipping tear the
    chain (neighbours more than a apart), the unconstrained arc flattened by
    halves until its clipped shape is a chain (the arc's angles scaled by 2^-k: a
    symmetric arc stays closed on the right pin)."""
    u, alpha = _clipped(chain, alpha0)
    scale = 0.5
    while alpha is None and scale > 1e-6:
        u, alpha = _clipped(chain, scale * chain.rest_alpha)
        scale *= 0.5
    return u, alpha


def run_profile_driver(chain: Chain, solver, *, tol: float, max_outer: int, method: str,
                       start: DriverStart | None = None) -> DriverOutput:
    """Iterate profile contact steps to the equilibrium (never raises on failure)."""
    n = chain.free_nodes.size
    steps: list[StepRecord] = []
    undamped = method == "undamped"
    u, alpha, warm = starting_point(chain, start, profile_start)
    if alpha is None:
        return failed_output(chain.rest_alpha.copy(), n, steps, "cannot fit the chain between the walls")
    mu_up, mu_lo = np.zeros(n), np.zeros(n)
    if warm is not None and warm.forces_net is not None and np.all(np.isfinite(warm.forces_net)):
        mu_up, mu_lo = split_reactions(walls_at(chain, alpha), warm.forces_net, u)
    ell = chain.length
    for _ in range(max_outer):
        E = chain_energy(chain, alpha)
        step, at = profile_step(chain, alpha, mu_up, mu_lo)
        near = method == "newton" and bool(steps) and steps[-1].max_dalpha < NEWTON_SWITCH
        t0 = time.perf_counter()
        if near:
            step, _ = newton_step(step, at)
        t_asm = time.perf_counter() - t0
        sol = solver(step, warm)
        if sol.status not in (Status.SOLVED, Status.INACCURATE):
            return step_failed(alpha, n, steps, sol, t_asm, E)
        dalpha = float(np.max(np.abs(step.predict_alpha(sol.u) - alpha), initial=0.0))
        d = sol.u - u
        t = 1.0
        if undamped:
            trial = step.predict_alpha(sol.u)
            if not np.all(np.isfinite(trial)) or np.any(np.sign(np.cos(trial))
                                                         != np.sign(np.cos(alpha))):
                steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time,
                                        t_asm, 1.0, dalpha, E, step_setup_time(sol)))
                return failed_output(alpha, n, steps, "diverged: a link passed the vertical, where "
                                              "the linearisation of eq. (20) is singular")
            new_u = heights(chain, trial)
        else:
            # the l1 merit P = Φ + σ·(violation of the exact walls), σ above every
            # reaction: the walls move under the nodes with x, and the step that puts
            # a node back on its wall costs energy that only the penalty repays
            sigma = PENALTY * max(float(np.max(np.abs(sol.forces_net), initial=0.0))
                                  if sol.forces_net is not None else 0.0,
                                  float(np.max(mu_up, initial=0.0)),
                                  float(np.max(mu_lo, initial=0.0)), chain.force_scale)
            phi = merit(chain, alpha, mu_up, mu_lo, sigma)
            violation = (phi - merit(chain, alpha, mu_up, mu_lo, 0.0)) / sigma
            slope = float(step.gradient(u) @ d) - sigma * violation

            def moved(t, u=u, d=d, a=alpha, up=mu_up, lo=mu_lo, sigma=sigma):
                trial = alpha_from_heights(chain, u + t * d, a)
                return (None, np.nan) if trial is None else (
                    trial, merit(chain, trial, up, lo, sigma))

            # near the answer a step cut below LOCAL_CUT is taken in full (undamped)
            t, trial, _ = armijo(moved, phi, slope, energy_noise(chain, phi),
                                 dalpha < NEWTON_SWITCH)
            if trial is None:
                steps.append(StepRecord(sol.iterations, sol.status.value,
                                        sol.solve_time, t_asm, 0.0, dalpha, E,
                                        step_setup_time(sol)))
                return failed_output(alpha, n, steps, "line search failed: no decrease of the "
                                              "merit along the step")
            new_u = u + t * d
        u, alpha = new_u, trial
        steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm,
                                t, dalpha, chain_energy(chain, alpha), step_setup_time(sol)))
        warm = sol
        net = sol.forces_net
        if net is not None and np.all(np.isfinite(net)):
            mu_up, mu_lo = split_reactions(at, net, sol.u)
        if dalpha < tol and penetration(chain, alpha) <= GEOMETRY_SLACK * ell:
            return converged_output(walls_at(chain, alpha), alpha, sol, steps, step)
    return out_of_iterations(alpha, n, steps, max_outer, tol)
