"""The globalised driver around any back-end, with lcpbench's own parts compiled.

The default back-end runs its whole solve in one kernel (:mod:`.compiled`); every
other back-end is a Python call per contact step. Around that call the numpy driver
(``model/driver.py``, removed) spent several milliseconds per solve of
lcpbench's own Python (assembly, the back-end's form, the judge, the line search), so a
table of full-solve times would compare that more than the back-ends. Here those parts
are the kernels of :mod:`.driver_kernel`; per outer iteration:

1. :func:`~.driver_kernel.assemble`: the banded step at α (a :class:`KernelStep`);
2. the step solver of :mod:`.step_solver`, unchanged (fallback, verdict, timings), which
   asks the step for its form (:func:`~.driver_kernel.qp_form` or
   :func:`~.driver_kernel.lcp_form`, timed as the form's ``build_time`` as before), the
   back-end's call in Python, and lcpbench's residuals (:func:`~.driver_kernel.judge`);
3. :func:`~.driver_kernel.advance`: max|α̂ − α| and the Armijo search on the exact energy.

Its answers are checked against the energy minimisation
(``tests/model/test_compiled_driver.py``). Elastic walls are a parameter of the same
loop: the back-end gets the step's elastic forms (:mod:`.elastic_step`), the judge the
compliant gaps, the line search the springs' energy. Walls of any profile are a
parameter too (:class:`Profile`): the step is the profile kernel's
(:func:`~.driver_kernel.profile_assemble`: the walls at the nodes' x, the lagged
reactions' slope load), the search on its merit and its stop
(:func:`~.driver_kernel.profile_advance`, :func:`~.driver_kernel.profile_on_walls`,
calling :mod:`.profile_kernel`'s functions), checked against the energy minimisation
(``tests/model/test_profile.py``). The paper's undamped scheme is an option of the same
loop (:func:`undamped`, any back-end). Where the solve kernel or the profile kernel
stops (:func:`lcpbench.model.compiled.reference`) this driver takes over with the
default back-end's step solver.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from ..errors import ProblemError
from ..problems.scenes import Chain
from ..solvers.base import Status
from ..solvers.registry import DEFAULT
from ..thresholds import GEOMETRY_SLACK, NEWTON_SWITCH
from .chain import energy
from .kernel_call import applies, consecutive, profile_args, profile_layout
from .newton import newton_step
from .outer import (
    STALL_STEPS,
    DriverOutput,
    DriverStart,
    StepRecord,
    converged_output,
    failed_output,
    feasible_start,
    line_search_failed,
    out_of_iterations,
    stall,
    starting_point,
    step_failed,
    step_setup_time,
)
from .profile import split_reactions
from .step import ContactStep, residuals_of, step_kernels

ENGINE = "compiled driver"


def takes(chain: Chain, step_solver, method: str) -> bool:
    """Whether this driver runs the solve: the globalised scheme or its Newton steps with
    a step solver of a back-end that takes a QP or an LCP or a contact step itself (a
    plug-in's ``solve_step``; not the default back-end, whose solve the kernel runs), or
    the undamped scheme with any back-end; a
    chain of consecutive joints and contiguous free nodes with flat walls, rigid or
    elastic (the back-end gets :mod:`.elastic`'s forms, the springs' energy is in the
    line search's). A step solver that is not ``scaled`` gets the step's forms in the
    problem's units (:func:`~.formulations.step_qp`, :func:`~.formulations.step_lcp`)."""
    backend = getattr(step_solver, "backend", None)
    return backend is not None and takes_backend(chain, backend,
                                                 getattr(step_solver, "scaled", False), method)


def takes_backend(chain: Chain, backend, scaled: bool, method: str) -> bool:
    """:func:`takes` from the registry's data on the back-end (a
    :class:`~lcpbench.solvers.registry.Backend`) and whether its step is ``scaled``
    (what :func:`lcpbench.plan.make_plan` knows before the step solver is made)."""
    if method in ("globalised", "newton"):
        if backend.form not in ("qp", "lcp"):
            return False
        if backend.name == DEFAULT and (method == "globalised" or not chain.profiled_walls):
            return False  # the kernels' (the solve kernel, the profile kernel)
    elif method != "undamped":
        return False
    if chain.profiled_walls:
        return profile_layout(chain)
    return applies("auto", "globalised", chain)


class KernelStep(ContactStep):
    """A contact step assembled by :mod:`.driver_kernel`, whose residuals the kernels
    compute (the hook of :mod:`.step_solver`; its forms are every step's,
    :meth:`ContactStep.lcp_form`, :meth:`ContactStep.qp_form`)."""

    cu = cl = np.empty(0)  # the elastic walls' compliances 1/k (empty: rigid walls)

    def springs(self) -> tuple[np.ndarray, np.ndarray]:
        """(cu, cl), the elastic walls' compliances (computed again where a copy of the
        step lost them, :func:`_compliances`)."""
        return (self.cu, self.cl) if self.cu.size else _compliances(self, self.elastic)

    def compiled_residuals(self, u: np.ndarray):
        """step_residuals' ``(residuals, R)``, or None (the numpy reference decides: a
        Newton step, whose gradient holds T (u − u₀))."""
        if self.geometric is not None:
            return None
        cu, cl = self.springs()
        ok, res, R = self.kernels().judge(
            np.ascontiguousarray(u, dtype=float), self.bands, self.linear, self.lower,
            self.upper, cu, cl, self.coef, int(self.base[0]), int(self.free_nodes[0]) + 1,
            self.links, self.origin, self.phi_origin, self.stiffness, self.rest_joint,
            self.nodal_load, float(self.length_scale), float(self.force_scale))
        if not ok:
            return None
        return residuals_of(res), R


def _compliances(obj, elastic: bool) -> tuple[np.ndarray, np.ndarray]:
    """The walls' compliances 1/k per free node of a chain or a step
    (:func:`.elastic.compliances`; empty arrays where no wall yields, ``elastic`` False:
    the kernels' form)."""
    if not elastic:
        return np.empty(0), np.empty(0)
    from .elastic import compliances

    return compliances(obj)


def _arrays(chain: Chain) -> tuple:
    f64 = np.ascontiguousarray
    return (float(chain.link_length), f64(chain.joint_links[:, 0], dtype=np.int64),
            f64(chain.joint_links[:, 1], dtype=np.int64),
            f64(chain.joint_stiffness, dtype=float), f64(chain.rest_joint, dtype=float),
            int(chain.free_nodes[0]) + 1, f64(chain.nodal_load, dtype=float),
            f64(chain.link_load, dtype=float), f64(chain.lower, dtype=float),
            f64(chain.upper, dtype=float))


def _assemble(kd, chain: Chain, c: tuple, alpha: np.ndarray,
              wall: Profile | None = None) -> KernelStep:
    a, jl, jr, k, rest, fs, load, _, lo, hi = c
    if wall is None:
        bands, linear, inv, v, phi0, coef, origin, alpha0, phi_origin = kd.assemble(
            alpha, a, jl, jr, k, rest, fs, lo.size, load)
    else:  # the walls at the nodes' x, the lagged reactions' slope load in the load
        (bands, linear, inv, v, phi0, coef, origin, alpha0, phi_origin, lo, hi,
         load) = kd.profile_assemble(alpha, a, jl, jr, k, rest, fs, load, wall.walls,
                                     wall.mu_up, wall.mu_lo)
    step = KernelStep(bands, linear, lo, hi, alpha, inv, v, chain.free_nodes, chain.links,
                      jr, coef, phi0, origin, alpha0, phi_origin, k, rest, load,
                      length_scale=chain.length, force_scale=chain.force_scale,
                      upper_stiffness=chain.upper_stiffness,
                      lower_stiffness=chain.lower_stiffness)
    step.kernel = kd
    if chain.elastic_walls:
        step.cu, step.cl = _compliances(chain, True)
    return step


def assemble_step(chain: Chain, alpha: np.ndarray) -> KernelStep:
    """The contact step of ``chain`` at configuration α, from the energy of the chain, in
    O(N) (eqs. 20-31; :mod:`.step`): the compiled assembly every driver around a back-end
    runs (:func:`~.driver_kernel.assemble`), its bounds the chain's wall rows (copies).
    A chain of consecutive joints and contiguous free nodes (the layout every compiled
    route takes); any other is a ProblemError."""
    if not consecutive(chain):
        raise ProblemError("the contact step is assembled for joints that join consecutive "
                           "links, in order, and contiguous free nodes from node 1")
    step = _assemble(step_kernels(), chain, _arrays(chain),
                     np.array(alpha, dtype=float))  # (a copy: the step keeps its α)
    step.kernel = None  # (a module is no instance attribute of a step that may be pickled)
    step.lower, step.upper = step.lower.copy(), step.upper.copy()
    return step


class Profile:
    """What walls of any profile add to this driver (the profile kernel's scheme,
    :mod:`.profile_kernel`, around any back-end): each step's bounds are the walls at
    the nodes' x and its load has the slope load of the lagged reactions μ̄, ν̄
    (:func:`~.driver_kernel.profile_assemble`); the line search is on the merit
    P = E − Σ μ̄ h(x) + Σ ν̄ l(x) + σ Σ(penetration of the exact walls)
    (:func:`~.driver_kernel.profile_advance`); the driver stops where, besides
    max|Δα| < tol, the chain is on the right side of the exact walls to
    GEOMETRY_SLACK·ℓ (:func:`~.driver_kernel.profile_on_walls`). The walls are the
    tables of cubic pieces the kernels and the judge read
    (:func:`~.kernel_call.profile_args`)."""

    def __init__(self, kd, chain: Chain):
        lo, hi, _, _, ku, cu_, kl, cl_, _ = profile_args(chain)
        self.kd, self.chain = kd, chain
        self.walls = (hi, lo, ku, cu_, kl, cl_)
        n = chain.free_nodes.size
        self.mu_up, self.mu_lo = np.zeros(n), np.zeros(n)

    def start(self, start: DriverStart | None):
        """(u, α, warm) as :func:`~.outer.starting_point`: ``start``'s shape clipped to
        the walls at the nodes' x, else the arc, flattened by halves until it fits
        (:func:`~.profile_kernel.clipped_start`); α None where nothing fits. A warm
        start's net reactions are the first lagged ones."""
        chain = self.chain
        s_alpha = (np.zeros(0) if start is None
                   else np.ascontiguousarray(start.alpha, dtype=float))
        ok, cold, alpha, u = self.kd.profile_start(
            s_alpha, np.ascontiguousarray(chain.rest_alpha, dtype=float),
            float(chain.link_length), int(chain.free_nodes[0]) + 1, self.walls)
        if not ok:
            return u, None, None
        warm = None if cold or start is None else start.warm
        net = None if warm is None else warm.forces_net
        if net is not None and np.size(net) == u.size and np.all(np.isfinite(net)):
            _, hi, lo = self.on_walls(alpha)
            self.mu_up, self.mu_lo = self.split(hi, lo, net, np.asarray(warm.u, float))
        return u, alpha, warm

    def split(self, upper, lower, net, u):
        """The upper and lower reactions of ``net`` with the walls ``upper``, ``lower``
        at the nodes' x (:func:`~.profile.split_reactions`)."""
        chain = self.chain
        if chain.channel:
            chain = replace(chain, upper=upper, lower=lower)
        up, lo = split_reactions(chain, net, u)
        return np.ascontiguousarray(up, dtype=float), np.ascontiguousarray(lo, dtype=float)

    def lag(self, step: KernelStep, sol) -> None:
        """The step's net reactions as the next step's lagged ones."""
        net = sol.forces_net
        if net is not None and np.all(np.isfinite(net)):
            self.mu_up, self.mu_lo = self.split(step.upper, step.lower, net, sol.u)

    def on_walls(self, alpha: np.ndarray):
        """(how far α crosses the exact walls, the walls at its nodes' x: upper, lower)."""
        chain = self.chain
        return self.kd.profile_on_walls(alpha, float(chain.link_length),
                                        int(chain.free_nodes[0]) + 1, self.walls)

    def answer(self, alpha: np.ndarray) -> Chain | None:
        """The chain with its walls at the nodes' x of α (the answer's reactions split
        between them), or None where α crosses the exact walls by more than
        GEOMETRY_SLACK·ℓ (one more step is taken)."""
        worst, hi, lo = self.on_walls(alpha)
        if not worst <= GEOMETRY_SLACK * self.chain.length:
            return None
        return replace(self.chain, upper=hi, lower=lo) if self.chain.channel else self.chain

    def advance(self, step: KernelStep, sol, u, alpha, c):
        """:func:`~.driver_kernel.profile_advance`: (max|Δα|, t, α(t), E(α(t)), u(t))."""
        a, jl, jr, k, rest, fs, _, link_load, _, _ = c
        net = sol.forces_net
        net = (np.zeros(u.size) if net is None or np.size(net) != u.size
               else np.ascontiguousarray(net, dtype=float))
        return self.kd.profile_advance(
            np.ascontiguousarray(sol.u, dtype=float), u, alpha, step.inv_a_cos, step.alpha0,
            step.origin, step.phi_origin, step.coef, fs, k, rest, step.nodal_load, a, jl, jr,
            link_load, self.walls, self.mu_up, self.mu_lo, net, float(self.chain.force_scale))


def run(chain: Chain, solver, *, tol: float = 1e-3, max_outer: int = 200,
        start: DriverStart | None = None, stop_on_stall: bool = False,
        method: str = "globalised") -> DriverOutput:
    """Iterate contact steps to the equilibrium of ``chain`` with the parts around the
    back-end compiled, for a chain and step solver it :func:`takes` (and after a stop of
    the solve kernel or the profile kernel, :func:`lcpbench.model.compiled.reference`,
    with the default back-end's step solver); never raises on non-convergence.
    ``method``: "globalised" (the Armijo search on the exact energy from the clipped arc
    or ``start``; against walls of any profile on the merit of :class:`Profile`),
    "newton" (the same with the exact Hessian H + T, :func:`~.newton.newton_step`, once
    max|Δα| is below ``NEWTON_SWITCH``, or from a neighbour's answer) or "undamped"
    (:func:`undamped`). ``stop_on_stall``: end as soon as max|Δα| has
    stalled (:func:`~.outer.stall`) instead of at ``max_outer`` (after a kernel stop,
    where the escalations take a refusal over)."""
    kd = step_kernels()
    c = _arrays(chain)
    wall = Profile(kd, chain) if chain.profiled_walls else None
    if method == "undamped":
        if start is not None:
            raise ProblemError("a continuation start needs method='globalised'")
        return undamped(kd, chain, c, solver, tol, max_outer, wall)
    a, jl, jr, k, rest, fs, load, link_load, lo, hi = c
    cu, cl = _compliances(chain, chain.elastic_walls)
    n = chain.free_nodes.size
    steps: list[StepRecord] = []
    if wall is None:
        u, alpha, warm = starting_point(chain, start, feasible_start)
    else:
        u, alpha, warm = wall.start(start)
    if alpha is None:
        return failed_output(chain.rest_alpha, n, steps, "cannot fit the chain between the walls")
    u, alpha = np.ascontiguousarray(u, dtype=float), np.ascontiguousarray(alpha, dtype=float)
    E = energy(chain, alpha)
    stiffness_sum = float(np.sum(np.abs(chain.joint_stiffness)))
    newton = method == "newton"
    warm_start = start is not None and warm is not None  # a neighbour's answer: near already
    for _ in range(max_outer):
        near = newton and (steps[-1].max_dalpha < NEWTON_SWITCH if steps else warm_start)
        t0 = time.perf_counter()
        step = _assemble(kd, chain, c, alpha, wall)
        if near:
            step = _newton(step, chain)
        t_asm = time.perf_counter() - t0
        sol = solver(step, warm)
        if sol.status not in (Status.SOLVED, Status.INACCURATE):
            return step_failed(alpha, n, steps, sol, t_asm, E)
        if wall is None:
            dalpha, t, trial, E_t = kd.advance(
                np.ascontiguousarray(sol.u, dtype=float), u, alpha, E,
                stiffness_sum, step.inv_a_cos, step.alpha0, step.origin,
                step.phi_origin, step.coef, fs, k, rest, load, a, jl, jr, link_load, lo, hi,
                cu, cl)
            u_t = u + t * (sol.u - u)
        else:
            dalpha, t, trial, E_t, u_t = wall.advance(step, sol, u, alpha, c)
        if t == 0.0:
            return line_search_failed(alpha, n, steps, sol, t_asm, dalpha, E)
        u, alpha, E = u_t, trial, E_t
        steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm,
                                t, dalpha, E, step_setup_time(sol)))
        warm = sol
        done = _converged(chain, wall, step, sol, alpha, dalpha, steps, tol)
        if done is not None:
            return done
        if stop_on_stall and len(steps) >= 2 * STALL_STEPS and stall(steps) is not None:
            return out_of_iterations(alpha, n, steps, len(steps), tol)
    return out_of_iterations(alpha, n, steps, max_outer, tol)


def _converged(chain: Chain, wall: Profile | None, step: KernelStep, sol, alpha, dalpha,
               steps, tol: float):
    """After a step taken: against walls of any profile its net reactions become the
    next step's lagged ones; the converged output where max|Δα| < ``tol`` and α lies on
    the exact walls (:meth:`Profile.answer`), else None (one more step)."""
    if wall is not None:
        wall.lag(step, sol)
    if dalpha < tol:
        at = chain if wall is None else wall.answer(alpha)
        if at is not None:
            return converged_output(at, alpha, sol, steps, step)
    return None


def _newton(step: KernelStep, chain: Chain) -> KernelStep:
    """The kernel's step with the exact Hessian H + T where it is positive definite
    (:func:`~.newton.newton_step`), keeping the kernels' hooks."""
    new, used = newton_step(step, chain)
    if used:
        new.kernel, new.cu, new.cl = step.kernel, step.cu, step.cl
    return new


def undamped(kd, chain: Chain, c: tuple, solver, tol: float, max_outer: int,
             wall: Profile | None = None) -> DriverOutput:
    """The paper's scheme (Fig. 3): α ← α̂ of eq. (21) after every step, from the
    unconstrained arc (against walls of any profile, ``wall``: from the arc clipped to
    them, each step with the last step's reactions lagged, :class:`Profile`), until
    max|α̂ − α| < ``tol`` (and, with a profile, the chain on the right side of the exact
    walls); each step a Gauss–Newton step taken
    in full, which can leave the region where the linearisation is valid (kept so that
    benchmarks show where it breaks): a link that passes the vertical, where eq. (20) is
    singular, or a non-finite α̂ ends it, not converged."""
    n = chain.free_nodes.size
    steps: list[StepRecord] = []
    alpha = np.ascontiguousarray(chain.rest_alpha, dtype=float).copy()
    if wall is not None:
        alpha = wall.start(None)[1]
        if alpha is None:
            return failed_output(chain.rest_alpha, n, steps,
                                 "cannot fit the chain between the walls")
    branch = np.sign(np.cos(alpha))
    fs = c[5]
    warm = None
    for _ in range(max_outer):
        t0 = time.perf_counter()
        step = _assemble(kd, chain, c, alpha, wall)
        t_asm = time.perf_counter() - t0
        sol = solver(step, warm)
        if sol.status not in (Status.SOLVED, Status.INACCURATE):
            return step_failed(alpha, n, steps, sol, t_asm, np.nan)
        new = kd.predict(np.ascontiguousarray(sol.u, dtype=float), step.alpha0, step.origin,
                         step.inv_a_cos, fs)
        dalpha = float(np.max(np.abs(new - alpha), initial=0.0))
        steps.append(StepRecord(sol.iterations, sol.status.value, sol.solve_time, t_asm, 1.0,
                                dalpha, np.nan, step_setup_time(sol)))
        if not np.all(np.isfinite(new)):
            return failed_output(alpha, n, steps, "diverged: non-finite link angles")
        if np.any(np.sign(np.cos(new)) != branch):
            return failed_output(new, n, steps, "diverged: a link passed the vertical, where "
                                                "the linearisation of eq. (20) is singular")
        alpha, warm = new, sol
        done = _converged(chain, wall, step, sol, alpha, dalpha, steps, tol)
        if done is not None:
            return done
    return out_of_iterations(alpha, n, steps, max_outer, tol)


def warm_up() -> None:
    """Load (or compile, the first time) every kernel of this driver: both forms and
    one tiny solve with lcpbench's Lemke (no optional back-end needed), against a flat
    wall and a wall profile."""
    from ..problems.scenes import ActuatorScene
    from ..problems.walls import WallProfile
    from .step_solver import make_step_solver

    chain = ActuatorScene(theta=150, height=3.0, links=8).chain()
    step = _assemble(step_kernels(), chain, _arrays(chain), chain.rest_alpha)
    step.qp_form(step.length_scale, step.force_scale)
    step.lcp_form(step.length_scale, step.force_scale)
    run(chain, make_step_solver("lemke"), tol=1e-3)
    bump = WallProfile.from_table([0.0, 15.0, 30.0], [3.0, 2.5, 3.0])
    run(ActuatorScene(theta=150, links=8, wall_profile=bump).chain(),
        make_step_solver("lemke"), tol=1e-3)
