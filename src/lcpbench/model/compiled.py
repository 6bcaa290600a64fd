"""The compiled engine: the default solve in one numba kernel, Python entered once.

``lcpbench.solve(scene)`` with the default back-end (the dual active set,
``solver="auto"`` or ``"active-set"``) and the globalised driver runs
:func:`lcpbench.model.compiled_kernel.solve_chain`: assembly of the banded
step, the dual active set with its refinement and certificate, the judge's
natural residual, the Armijo search on the exact energy and the outer loop,
in one call. Its answers are checked against independent oracles (the energy
minimisation, beam theory, the exact-geometry certificate: tests/model/test_compiled.py).

numba is imported, and the kernel loaded from numba's on-disk cache (or
compiled, the first time), at the first solve that uses it, never at
``import lcpbench``.

Where the kernel stops (:data:`~.kernel_call.BAIL_REASONS`: the primal safeguard of
the active set, a face not positive definite, a repeated working set, a step the
certificate or the judge rejects) the solve falls back to compiled code
(:func:`reference`): the compiled driver around the default back-end's step solver,
the increments on the tridiagonal factor, or, for a refused step, a not-converged
answer that the plan's escalations take over. The DriverOutput is built by the
driver's own helpers and judged afterwards by the same certificate and judge
(:mod:`lcpbench.model.judge`) as every other back-end.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np

from ..errors import ProblemError
from ..problems.scenes import Chain
from ..solvers.judge import requested
from ..solvers.registry import DEFAULT, get_settings
from . import angle_step, compiled_driver, heavy_driver, large_n, wall_free
from .kernel_call import (
    BAIL_REASONS,
    applies,
    profile_applies,
    run_compiled,
    run_profile_compiled,
)
from .outer import DriverOutput, DriverStart

#: ``engine`` of :func:`lcpbench.api.solve_internal`: "auto" (the kernel where it
#: applies, the compiled driver elsewhere), "compiled" (the kernel or the compiled driver,
#: or ProblemError where neither applies). The numpy reference engine ("numpy") was
#: removed: a kernel that stops falls back to compiled code (:func:`reference`).
ENGINES = ("auto", "compiled")
#: What ran, as ``result.engine`` begins (:func:`drive`): the solve kernel (the default
#: back-end's outer loop fused in one compiled call), the compiled driver (another
#: back-end's steps in Python, the loop's pieces compiled), the large-N driver in
#: increments (its loop in Python, its steps compiled), the SQP in the link angles
#: (compiled). No engine is numpy.
ENGINES_RUN = ("compiled", "compiled driver", "increments driver", "compiled SQP")


def check_engine(engine) -> str:
    if isinstance(engine, str) and engine == "numpy":
        raise ProblemError("engine='numpy' was removed (the numpy reference solve is gone: "
                           "a kernel that stops falls back to compiled code); engine must "
                           f"be one of {', '.join(ENGINES)}")
    if not isinstance(engine, str) or engine not in ENGINES:
        raise ProblemError(f"engine must be one of {', '.join(ENGINES)}, got {engine!r}")
    return engine


def drive(chain: Chain, step_solver, *, backend: str, settings, engine: str = "auto",
          tol: float, max_outer: int, method: str, start: DriverStart | None,
          args: tuple | None = None) -> tuple[DriverOutput, str]:
    """The driver's answer and the engine that produced it (:data:`ENGINES_RUN`:
    "compiled", "compiled driver", "increments driver" (large N: the outer loop in
    Python, its steps on the tridiagonal factor compiled) or "compiled SQP" (a heavy
    chain's SQP steps in the link angles), with why in parentheses where it was not the
    plan's).

    The one place where the compiled kernel is chosen: a back-end other than the
    default runs the compiled driver (:mod:`.compiled_driver`) where it takes the
    chain (flat walls, rigid or elastic, or walls of any profile; the globalised, Newton
    or undamped scheme, and the undamped scheme with the default back-end too, and its
    Newton scheme on a wall profile); a kernel that stops runs its compiled fall-back
    (:func:`reference`); a chain no driver takes is a ProblemError. ``args``: the
    chain's :func:`~.kernel_call.kernel_args`, given by a caller that has checked that the kernel
    takes the chain's layout.

    Heavy chains (:mod:`lcpbench.model.heavy_driver`): from wℓ³/EI ≥
    :data:`~lcpbench.model.angle_step.HEAVY` the SQP steps in the link angles run
    first (the height steps where they fail); a loaded chain whose height steps do
    not converge (within :data:`~lcpbench.model.heavy_driver.FIRST_TRY` outer
    iterations from wℓ³/EI ≥ :data:`~lcpbench.model.heavy_driver.MODERATE`) is
    finished by them, its outer iterations counted with the height steps'.
    """
    engine = check_engine(engine)
    angles = method != "undamped" and angle_step.in_reach(chain)
    if angles:
        q = angle_step.load_parameter(chain)
        # with contact, the SQP's reactions stand in for the default back-end only: a
        # sweep's other back-ends keep the height steps, with their whole budget of outer
        # iterations; the SQP's answer is taken for them only where it touches no wall
        # (no back-end is involved, as on the wall-free path, which heavy chains skip)
        own = backend in (DEFAULT, "auto")
        if q >= angle_step.HEAVY:
            out = heavy_driver.run_heavy(chain, start, tol, max_outer)
            if out is not None and (own or heavy_driver.no_contact(out)):  # (its reason)
                return out, "compiled SQP (SQP steps in the link angles: a heavy chain)"
        first = (min(max_outer, heavy_driver.FIRST_TRY) if own and q >= heavy_driver.MODERATE
                 else max_outer)
        out, used = _drive(chain, step_solver, backend=backend, settings=settings,
                           engine=engine, tol=tol, max_outer=first, method=method,
                           start=start, args=args)
        budget = max_outer - len(out.steps) if own else max_outer
        if out.converged or q < heavy_driver.MODERATE or budget <= 0:
            return out, used
        rescue = heavy_driver.run_heavy(chain, start, tol, budget)
        if rescue is None or not (own or heavy_driver.no_contact(rescue)):
            return out, used
        rescue.steps = out.steps + rescue.steps  # the reason says the SQP finished it
        rescue.reason = "converged (height steps, then SQP steps in the link angles)"
        return rescue, used
    return _drive(chain, step_solver, backend=backend, settings=settings, engine=engine,
                  tol=tol, max_outer=max_outer, method=method, start=start, args=args)


def _drive(chain: Chain, step_solver, *, backend: str, settings, engine: str,
           tol: float, max_outer: int, method: str, start: DriverStart | None,
           args: tuple | None = None) -> tuple[DriverOutput, str]:
    """:func:`drive` in the node heights: the kernel, the large-N increments or the
    compiled driver."""
    if method == "globalised" and large_n.applies(chain):  # N >= LARGE_N: increments
        from .large_driver import run_large
        from .nested_start import nested_start

        if start is None:  # the same solve at fewer links, interpolated (nested iteration;
            # its outer steps are not the answer's, its time is in the solve's)
            start = nested_start(chain, functools.partial(_coarse_solve, tol=tol))
        return (run_large(chain, step_solver, tol=tol, max_outer=max_outer, start=start),
                "increments driver (large N: increments on the tridiagonal factor)")
    if applies(backend, method, None if args is not None else chain):
        return run_kernel(chain, lambda: step_solver, settings=settings, tol=tol,
                          max_outer=max_outer, method=method, start=start, args=args)
    elif profile_applies(backend, method, chain):
        out, why = run_profile_compiled(chain, tol=tol, max_outer=max_outer, start=start,
                                        settings=settings)
        if out is not None:
            return out, "compiled"
        return reference(chain, lambda: step_solver, why, tol=tol, max_outer=max_outer,
                         method=method, start=start, settings=settings)
    elif compiled_driver.takes(chain, step_solver, method):
        # another back-end (or scheme): its calls in Python, lcpbench's parts around them
        # compiled; walls of any profile a parameter of its step and merit
        return (compiled_driver.run(chain, step_solver, tol=tol, max_outer=max_outer,
                                    start=start, method=method), compiled_driver.ENGINE)
    raise ProblemError("no driver takes this chain: the compiled driver runs a chain of "
                       "consecutive joints and contiguous free nodes from node 1, with flat "
                       "walls or walls of any profile (method 'globalised', 'newton' or "
                       f"'undamped'); got method {method!r}")


def _coarse_solve(coarse: Chain, *, tol: float) -> DriverOutput | None:
    """The nested start's solve of the coarse chain (:mod:`.nested_start`): the built-in
    active set whatever the fine solve's back-end (a start needs no particular one, and a
    dense back-end at 1000 links can take minutes), Gauss–Newton height steps (no SQP
    route: it is cubic in N), at most :data:`~.nested_start.COARSE_OUTER` outer steps;
    None where a factorisation fails (the fine solve then starts cold)."""
    from .nested_start import COARSE_OUTER
    from .step_solver import make_step_solver

    try:
        return _drive(coarse, make_step_solver(DEFAULT), backend=DEFAULT, settings="default",
                      engine="auto", tol=tol,
                      max_outer=COARSE_OUTER, method="globalised", start=None)[0]
    except np.linalg.LinAlgError:
        return None


def run_kernel(chain: Chain, make_step: Callable[[], Callable], *, settings, tol: float,
               max_outer: int, method: str, start: DriverStart | None = None,
               args: tuple | None = None) -> tuple[DriverOutput, str]:
    """The default back-end's solve in the kernel (:func:`~.kernel_call.run_compiled`), or,
    where the kernel stops, its compiled fall-back (:func:`reference`, with the step
    solver ``make_step()``, called then only): the answer and the engine that produced
    it."""
    out, why = run_compiled(chain, tol=tol, max_outer=max_outer, start=start,
                            settings=settings, args=args, newton=method == "newton")
    if out is not None:
        return out, "compiled"
    return reference(chain, make_step, why, tol=tol, max_outer=max_outer, method=method,
                     start=start, settings=settings)


def step_request(settings) -> float:
    """The accuracy the kernel asks of each step (its step judge's request): the
    settings' ``eps``, else ``DEFAULT_TOL``."""
    return float(requested(get_settings(settings)))


#: the kernel's bail reasons that the round-off of node heights can cause (and a cold
#: solve stopped for its stall, 16, taken as the refused steps 14 and 15 it stands in for)
ROUNDOFF_BAILS = frozenset((BAIL_REASONS[12], BAIL_REASONS[14], BAIL_REASONS[15],
                            BAIL_REASONS[16]))
#: the bail reasons that are a refusal of the kernel's own step (:func:`reference`); 16,
#: a cold solve stopped where its line searches stalled (thresholds.STALL_STEP), which
#: went on to a refused step (or a face the walk could not solve) on every scene measured
REFUSED_STEPS = frozenset((BAIL_REASONS[14], BAIL_REASONS[15], BAIL_REASONS[16]))


def reference(chain: Chain, make_step: Callable[[], Callable], why: str, *, tol: float,
              max_outer: int, method: str, start: DriverStart | None = None,
              settings="default") -> tuple[DriverOutput, str]:
    """Where the solve kernel or the profile kernel stopped (``why``, one of its bail
    reasons): the compiled code that takes over, its answer and the engine that
    produced it.

    Where the reason is one that round-off of node heights can cause
    (:data:`ROUNDOFF_BAILS`) and cond H · ε reaches the step's own accuracy
    (:func:`step_request` of ``settings``, the kernel's: 1e-6 by default, N ≳ 400;
    :func:`lcpbench.model.large_n.roundoff_may_limit`), the
    solve runs in increments on the tridiagonal factor instead, as from ``LARGE_N``
    links: a solve in heights would meet the same round-off, and its step solver then
    falls back to a dense Lemke step, O(N³) (97 s at N = 3999).

    Where the kernel's own step was refused (:data:`REFUSED_STEPS`: its certificate or
    lcpbench's step judge, or a cold solve stopped on its stalled line searches before
    it reached such a refusal) the solve is not run again in node heights, the kernel's own
    scheme: on 41 such stops (rows of sections past 150°, elastic walls and the paper
    grid at tol 1e-3 and 1e-9, the hard cases) a rerun never converged where the kernel
    had stopped, at up to 50 ms a scene. The answer is reported not converged with the
    kernel's reason, and the plan's escalations (the loading path) take over.

    The other stops (crossed walls, the face-solve limit, a face not positive definite,
    a repeated working set) run the compiled driver (:func:`.compiled_driver.run`: the
    same globalised loop, its assembly and line search compiled) around the default
    back-end's step solver ``make_step()``, which has what the kernel lacks (the primal
    active set, the dense Lemke fall-back), stopping where max|Δα| stalls (against walls
    of any profile, the profile kernel's step and merit, :class:`.compiled_driver.Profile`); on elastic
    walls the answer is reported not converged as for a refused step (the compiled
    driver assembles elastic walls for the other back-ends; around the default
    back-end's step solver there it has not been measured)."""
    kernel = kernel_name(chain)
    if beyond_heights(chain, why):
        return out_of_reach(chain, why), "compiled (stopped: see the reason)"
    if why in ROUNDOFF_BAILS and large_n.roundoff_may_limit(chain, step_request(settings),
                                                            method):
        from dataclasses import replace

        from .large_driver import run_large

        return (run_large(replace(chain, increments=True), make_step(), tol=tol,
                          max_outer=max_outer, start=start),
                f"increments driver (increments on the tridiagonal factor; {kernel} "
                f"stopped: {why})")
    if why not in REFUSED_STEPS and not chain.elastic_walls:
        return (compiled_driver.run(chain, make_step(), tol=tol, max_outer=max_outer,
                                    start=start, stop_on_stall=True, method=method),
                f"{compiled_driver.ENGINE} ({kernel} stopped: {why})")
    return stopped(chain, why), f"compiled (stopped: {why})"


def stopped(chain: Chain, why: str) -> DriverOutput:
    """The not-converged answer of a kernel stop that no compiled route takes over
    (the plan's escalations may): the unconstrained arc, the reason naming the stop."""
    from .outer import failed_output

    return failed_output(chain.rest_alpha.copy(), chain.free_nodes.size, [],
                         f"{kernel_name(chain)} stopped: {why} (no answer: the shape "
                         f"given is the unconstrained arc)")


def kernel_name(chain: Chain) -> str:
    """The kernel whose stop a reason names: the profile kernel against walls of any
    profile (:func:`.compiled_kernel.solve_profile_chain`), else the compiled solve kernel."""
    return "the profile kernel" if chain.profiled_walls else "the compiled kernel"


def beyond_heights(chain: Chain, why: str) -> bool:
    """Whether a kernel stop ``why`` at this N is the round-off of the height formulation
    with nothing to take over: from ``LARGE_N`` links, a face not positive definite or
    a round-off stop (:data:`ROUNDOFF_BAILS`), on a chain the increment formulation does
    not take (a joint layout other than :func:`lcpbench.model.large_n.layout_fits`). A
    driver in heights meets the same round-off there, and its step solver's
    dense Lemke fallback is O(N³) (a solve of elastic walls at N = 10⁵ failed after
    42 s before elastic walls ran in increments)."""
    return (chain.links >= large_n.LARGE_N and not large_n.takes(chain)
            and (why in ROUNDOFF_BAILS or why == BAIL_REASONS[11]))


def out_of_reach(chain: Chain, why: str) -> DriverOutput:
    """The failed answer of :func:`beyond_heights`, its reason naming the limit."""
    from .outer import failed_output

    cond = large_n.heights_condition(chain.links) * np.finfo(float).eps
    return failed_output(chain.rest_alpha.copy(), chain.free_nodes.size, [],
                         f"{kernel_name(chain)} stopped ({why}) at N = {chain.links}: the "
                         f"round-off of the node heights (cond H · ε ≈ {cond:.1e}) is out of "
                         f"reach there, and the increment formulation does not take this "
                         f"joint layout; N < {large_n.LARGE_N} solves it")


def direct(chain: Chain) -> bool:
    """Whether :func:`drive` takes this chain straight to :func:`run_kernel` with the
    default back-end (the globalised or Newton scheme, a cold start), and
    :func:`lcpbench.model.wall_free.solve_without_contact` answers None at once: the
    kernel takes the chain (:func:`~.kernel_call.applies`), it is not large
    (:func:`lcpbench.model.large_n.applies`) nor loaded enough for SQP steps in the
    angles (:data:`~lcpbench.model.heavy_driver.MODERATE`, below
    :data:`~lcpbench.model.angle_step.HEAVY`), and its arc crosses the wall too far for
    the wall-free search (:func:`~lcpbench.model.wall_free_kernel.arc_far_past_wall`). The
    route :func:`lcpbench.solve` takes without the calls in between (tests compare)."""
    return (applies(DEFAULT, "globalised", chain) and not large_n.applies(chain)
            and not heavy(chain) and wall_free.arc_far(chain))


def heavy(chain: Chain) -> bool:
    """Whether :func:`drive` may take SQP steps in the link angles for this chain: it is
    in reach of them and loaded from :data:`~lcpbench.model.heavy_driver.MODERATE` on
    (wℓ³/EI)."""
    return angle_step.in_reach(chain) and angle_step.load_parameter(chain) >= heavy_driver.MODERATE


def warm_up() -> None:
    """Load the kernels by one tiny solve each, compiling them into numba's on-disk cache
    the first time (about a minute). Call it before starting processes that
    solve under a time limit (the sweep's workers), so that no job pays for
    the compilation."""
    from ..problems.scenes import ActuatorScene

    run_compiled(ActuatorScene(theta=150, height=3.0, links=8).chain(), tol=1e-3)
    compiled_driver.warm_up()  # the driver around the other back-ends
