"""The globalised driver in increments, for large N (:mod:`.large_n`).

The same scheme as :func:`lcpbench.model.compiled_driver.run` with
``method="globalised"``: start from the unconstrained arc clipped to the walls,
solve the contact step, search along it with Armijo on the exact energy,
stop when max|α̂ − α| < tol and the driver's prediction of the judge's
per-node force bound holds (:data:`NODE_SETTLED`). The differences, both for
round-off at large N:
the step is :func:`~.large_n.increments_at` (unknowns d = u − u₀, face solves
on the tridiagonal factor of H) and the iterate moves by
:func:`~.large_n.trial_of`, so the state is α, never heights
rounded to doubles. The step is solved by the caller's step solver (the
default back-end's active set, judged by lcpbench's step residuals; with elastic
walls Newton on the springs, :mod:`lcpbench.solvers.spring_newton`); the
answer is judged by :mod:`.judge` as every other.

The walls are parameters of the same loop (:class:`WallTerms`), not a second
driver: elastic walls add their springs' energy to the merit and start from a
nested start unclipped (a node may indent the wall); a wall profile gives each
step the walls at the nodes' x and the slope load of the lagged reactions, and
the merit and the stop of the profile kernel (:mod:`.profile_kernel`: the l1 penalty on the exact
walls, a full step near the answer, the chain on the exact walls).
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ..problems.scenes import Chain
from ..solvers.base import Status
from ..thresholds import GEOMETRY_SLACK, NEWTON_SWITCH, NODE_GROSS, PENALTY
from .chain import energy, heights
from .elastic import penalty, penalty_gradient
from .judge import contraction_estimate, split_reactions
from .large_n import StepWork, increments_at, trial_of
from .outer import (
    DriverOutput,
    DriverStart,
    StepRecord,
    StepSolver,
    armijo,
    converged_output,
    energy_noise,
    failed_output,
    feasible_start,
    line_search_failed,
    out_of_iterations,
    step_failed,
    step_setup_time,
)
from .profile import slope_load, wall_rows, wall_tables

#: past max|Δα| < tol the driver goes on while its prediction of the judge's per-node
#: force error bound (:func:`_node_change`) exceeds this share of NODE_GROSS, for at
#: most EXTRA_STEPS steps: a point contact's split between its two neighbouring nodes
#: moves by ~4 EI δφ / a² per joint-angle error δφ, so at N ≥ 10⁴ and tol 1e-3 the
#: answer's nodes were 0.1–1 F₀ off (the total force within τ); each further step
#: divides that by ~100 (docs/performance.md)
NODE_SETTLED = 0.5
EXTRA_STEPS = 4
#: the next step's walk gallops from its warm contacts (:mod:`lcpbench.solvers.compiled_walk`)
#: from 1/REACH_SHARE of the nodes the contacts moved in this step on (the outer
#: iteration contracts the moves by ~10-20 a step)
REACH_SHARE = 16


def run_large(chain: Chain, solver: StepSolver, *, tol: float = 1e-3, max_outer: int = 200,
              start: DriverStart | None = None) -> DriverOutput:
    """Iterate increment steps to the equilibrium of ``chain`` (never raises on
    non-convergence). The last step's ``u`` is returned in heights (mm), as the
    other drivers do, for a continuation of the next scene. The walls are parameters
    of the step and the merit (:class:`WallTerms`): elastic walls add their springs'
    energy, a wall profile its walls at the nodes' x, the lagged slope load and the
    l1 penalty on the exact walls (the profile kernel's scheme)."""
    n = chain.free_nodes.size
    steps: list[StepRecord] = []
    warm = None
    alpha = None
    walls = WallTerms(chain)
    fit = walls.start if chain.profiled_walls else feasible_start
    if start is not None and chain.elastic_walls:  # its nodes may indent the walls
        alpha = np.array(start.alpha, dtype=float)
    elif start is not None:
        _, alpha = fit(chain, np.asarray(start.alpha, float))
    if alpha is None:
        _, alpha = fit(chain, chain.rest_alpha)
    elif start is not None and start.warm is not None:  # its contact set, no heights
        warm = replace(start.warm, u=np.full(n, np.nan))
    if alpha is None:
        return failed_output(chain.rest_alpha.copy(), n, steps, "cannot fit the chain between the walls")
    noise = energy_noise(chain, energy(chain, alpha, walls=False))
    last_net, extra = None, 0
    last_contacts = None
    # one set of step arrays for every outer step: the next step's assembly writes them
    # again when nothing reads this step any more (its answer, reactions, warm start
    # and trial α are arrays of their own); at N = 10⁵ fresh arrays cost ~5,000 page
    # faults a step, two sets ~15 MiB more peak RSS
    work = StepWork(chain.links)
    for _ in range(max_outer):
        t0 = time.perf_counter()
        step = walls.step(alpha, work)
        t_asm = time.perf_counter() - t0
        sol = solver(step, warm)
        if sol.status not in (Status.SOLVED, Status.INACCURATE):
            return step_failed(alpha, n, steps, sol, t_asm, energy(chain, alpha, walls=False))
        d = sol.u  # the increment to the step's answer
        dalpha = float(np.max(np.abs(step.predict_alpha(d) - alpha), initial=0.0))
        E, slope = walls.merit_at(alpha, step, sol, d)
        local = dalpha < NEWTON_SWITCH and chain.profiled_walls
        t, trial, E_t = armijo(walls.trial(alpha, d, step), E, slope, noise, local)
        if trial is None:
            return line_search_failed(alpha, n, steps, sol, t_asm, dalpha, E)
        steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm,
                                t, dalpha, E_t, step_setup_time(sol)))
        node_change, last_net = _node_change(chain, sol.forces_net, last_net, steps)
        walls.lag(sol.forces_net, step.heights + d)
        if (dalpha < tol and walls.on_walls(trial) and extra >= walls.first_extra
                and (node_change <= NODE_SETTLED * NODE_GROSS or extra >= EXTRA_STEPS)):
            final = replace(sol, u=step.heights + d)  # in heights, as every driver reports
            return converged_output(walls.at, trial, final, steps)
        extra += dalpha < tol
        # the warm start of the next step: this answer, in the next step's increments
        warm = replace(sol, u=(1.0 - t) * d)
        move, last_contacts = _contact_move(sol, last_contacts)
        if move is not None:
            warm.reach = max(1, move // REACH_SHARE)  # read by the dual walk's solve_step
        alpha = trial
    return out_of_iterations(alpha, n, steps, max_outer, tol)


# -- walls of any profile in increments: the start, merit and stop of the profile kernel
# (:mod:`.profile_kernel`: compiled, once) on this driver's Python loop
def _driver_kernel():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.model.driver_kernel", "assemble")


def _profile_kernel():
    from ..numba_cache import kernel_module

    return kernel_module("lcpbench.model.profile_kernel", "merit_at")


class WallTerms:
    """What the walls add to the increment driver: the step's walls and load, and the
    merit's terms beyond the chain's energy (:func:`.chain.energy` without walls).

    - rigid flat walls: nothing (the merit is the energy);
    - elastic walls: the springs' energy Σ ½ k (y − h)₊² (:func:`.elastic.penalty`)
      at the nodes' heights, its gradient in the slope;
    - a wall profile: the walls at the nodes' x (:func:`.profile.wall_rows`), the slope
      load of the lagged reactions μ̄, ν̄ (:func:`.profile.slope_load`) in the step's
      load, and the merit Φ = E − Σ μ̄ h(x) + Σ ν̄ l(x) + σ·Σ(penetration of the exact
      walls) (:func:`~.profile_kernel.merit_at`); the start and the stop of the profile
      kernel (:func:`~.driver_kernel.profile_start`,
      :func:`~.driver_kernel.profile_on_walls`). All compiled, on the walls' tables."""

    def __init__(self, chain: Chain):
        self.chain = chain
        self.at = chain  # the chain with its walls at the nodes' x of the last step
        n = chain.free_nodes.size
        self.mu_up, self.mu_lo = np.zeros(n), np.zeros(n)
        self.sigma = 0.0
        #: steps past max|Δα| < tol before the driver may stop: a profile's contact split
        #: between two nodes at a curved wall moves with the lagged slopes (12 % of F₀ in
        #: the judge's step after the first such step, the stenosis at N = 3·10⁴), so its
        #: per-node prediction compares two steps below tol
        self.first_extra = 1 if chain.profiled_walls else 0
        if chain.profiled_walls:  # the kernels' walls: (upper rows, lower rows, tables)
            f64 = np.ascontiguousarray
            self.walls = (f64(chain.upper, dtype=float), f64(chain.lower, dtype=float),
                          *wall_tables(chain))
            self.a, self.fs = float(chain.link_length), int(chain.free_nodes[0]) + 1

    def start(self, chain: Chain, alpha0: np.ndarray):
        """``(u, α)``: the clipped shape of ``alpha0``, else the arc flattened by halves
        until its clipped shape is a chain (:func:`~.profile_kernel.clipped_start`); α
        None where nothing fits."""
        ok, _, alpha, u = _driver_kernel().profile_start(
            np.ascontiguousarray(alpha0, dtype=float),
            np.ascontiguousarray(chain.rest_alpha, dtype=float), self.a, self.fs, self.walls)
        return u, (alpha if ok else None)

    def step(self, alpha: np.ndarray, work: StepWork):
        chain = self.chain
        if not chain.profiled_walls:
            return increments_at(chain, alpha, work)
        rows = wall_rows(chain, alpha)
        self.at = replace(chain, upper=rows[2], lower=rows[3])
        # the lagged reactions as the last step gave them, round-off of either sign kept
        # (clipped at 0, as the profile kernel does, the stenosis at θ 150°, tol 1e-3
        # needed the escalations at N = 8·10⁴ and 10⁵, 9–10 s; kept: none of 12 solves,
        # N = 10⁴…10⁵, θ 120° and 150°)
        s = slope_load(chain, alpha, self.mu_up, self.mu_lo, rows)
        return increments_at(chain, alpha, work, walls=(rows[3], rows[2]),
                             load=chain.nodal_load + s)

    def merit_parts(self, alpha: np.ndarray) -> tuple[float, float]:
        """A profile's (−Σ μ̄ h(x) + Σ ν̄ l(x), the penetration of the exact walls summed)
        at α (:func:`~.profile_kernel.merit_at` with E = 0: this driver adds its
        compensated E itself)."""
        _, y, hi, lo, *_ = wall_rows(self.chain, alpha)
        part, pen = _profile_kernel().merit_at(0.0, self.walls, self.mu_up, self.mu_lo, y,
                                               hi, lo)
        return float(part), float(pen)

    def extra(self, alpha: np.ndarray) -> float:
        """The merit's terms beyond the energy at α."""
        chain = self.chain
        if chain.elastic_walls:
            return penalty(chain, heights(chain, alpha))
        if chain.profiled_walls:
            part, pen = self.merit_parts(alpha)
            return part + self.sigma * pen
        return 0.0

    def merit_at(self, alpha, step, sol, d) -> tuple[float, float]:
        """(merit at α, its slope along the step's increment d)."""
        chain = self.chain
        slope = float(step.linear @ d)  # the gradient at u₀ along d
        if chain.elastic_walls:
            slope += float(penalty_gradient(chain, step.heights) @ d)
        elif chain.profiled_walls:  # σ above every reaction (the profile kernel's)
            net = sol.forces_net
            self.sigma = PENALTY * max(
                float(np.max(np.abs(net), initial=0.0)) if net is not None else 0.0,
                float(np.max(self.mu_up, initial=0.0)), float(np.max(self.mu_lo, initial=0.0)),
                chain.force_scale)
            slope -= self.sigma * self.merit_parts(alpha)[1]
        return energy(chain, alpha, walls=False) + self.extra(alpha), slope

    def trial(self, alpha, d, step):
        """``t -> (α', merit(α'))`` (:func:`~.large_n.trial_of` plus :meth:`extra`)."""
        at = trial_of(self.chain, alpha, d, step)
        if not (self.chain.elastic_walls or self.chain.profiled_walls):
            return at

        def moved(t: float):
            trial, E = at(t)
            return (None, E) if trial is None else (trial, E + self.extra(trial))

        return moved

    def lag(self, net, u: np.ndarray) -> None:
        """The step's reactions as the next step's lagged multipliers (a profile)."""
        if self.chain.profiled_walls and net is not None and np.all(np.isfinite(net)):
            self.mu_up, self.mu_lo = (np.ascontiguousarray(m, dtype=float) for m in
                                      split_reactions(self.at, net, u))

    def on_walls(self, alpha: np.ndarray) -> bool:
        """A profile: the chain on the right side of the exact walls at α to
        GEOMETRY_SLACK·ℓ (the walls move under the nodes with x,
        :func:`~.profile_kernel.penetration`); else True."""
        if not self.chain.profiled_walls:
            return True
        worst, _, _ = _driver_kernel().profile_on_walls(
            np.ascontiguousarray(alpha, dtype=float), self.a, self.fs, self.walls)
        return worst <= GEOMETRY_SLACK * self.chain.length


def _node_change(chain: Chain, net, last_net, steps: list[StepRecord]):
    """``(bound, net)``: the judge's per-node force error bound as this driver can predict
    it, ρ κ max_i |R_i − R_i^prev| / F₀ (the judge takes κ max_i |R_i − R'_i| one step
    later, so ρ smaller), with ρ and κ = 1/(1 − ρ) as the judge estimates them; inf
    before two steps' reactions are known."""
    if net is None or not np.all(np.isfinite(net)):
        return np.inf, None
    net = np.asarray(net, dtype=float)
    if last_net is None:
        return np.inf, net
    F0 = max(float(np.sum(np.maximum(net, 0.0))), float(np.sum(np.maximum(-net, 0.0))),
             chain.force_scale)
    rho = contraction_estimate([s.max_dalpha for s in steps[:-1]], steps[-1].max_dalpha)
    change = float(np.max(np.abs(net - last_net), initial=0.0))
    return rho / (1.0 - rho) * change / F0, net


def _contact_move(sol, last):
    """``(move, contacts)``: how many nodes the contacts moved against the ``last`` step's
    (the largest distance of a contact node to the nearest last one; None when either
    set is empty or unknown) and this step's contact nodes."""
    up, lo = getattr(sol, "active_upper", None), getattr(sol, "active_lower", None)
    if up is None or lo is None:
        return None, None
    now = np.flatnonzero(np.asarray(up, bool) | np.asarray(lo, bool))
    if last is None or last.size == 0 or now.size == 0:
        return None, now
    k = np.clip(np.searchsorted(last, now), 1, last.size - 1) if last.size > 1 else None
    if k is None:
        dist = np.abs(now - last[0])
    else:
        dist = np.minimum(np.abs(now - last[k - 1]), np.abs(now - last[k]))
    return int(dist.max()), now

