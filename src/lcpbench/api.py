"""The library call: ``lcpbench.solve(scene) -> ContactResult``: validate, plan
(:func:`lcpbench.plan.make_plan`), run the plan's route, judge, escalate
(:mod:`lcpbench.escalations`).

It reads no file and imports no benchmark code: ``solver="auto"`` is a fixed
rule (the built-in active set, exact and O(N) per face solve), and a back-end
chosen by measurement is passed in explicitly as the
:class:`~lcpbench.solvers.selection.Selection` that
:func:`lcpbench.select_backend` returns.
"""

from __future__ import annotations

import math
import time
from functools import partial

import numpy as np

from .accuracy import accuracy_settings, check_accuracy, held_to
from .errors import ProblemError
from .escalations import Context, escalate
from .model.compiled import check_engine, drive, reference, run_kernel
from .model.finish import finish
from .model.formulations import handed, resolve_formulation
from .model.judge import chain_args, judge
from .model.kernel_call import (
    BAIL_REASONS,
    call_kernel,
    call_profile_kernel,
    kernel_args,
    kernel_output,
)
from .model.lazy_result import LazyResult, lazy_result, stats_judge
from .model.outer import METHODS, DriverOutput, DriverStart
from .model.ramp import follow_load
from .model.result import ContactResult, Retry
from .model.step_solver import make_step_solver
from .model.wall_free import arc_far, solve_without_contact
from .plan import Plan, make_plan
from .problems.checks import check_flag, check_number, describe
from .problems.sections import check_scene
from .solvers.base import Settings
from .solvers.registry import DEFAULT, get_backend, get_settings
from .solvers.selection import Selection

#: The paper's driver tolerance (rad), the default of :func:`solve`.
PAPER_TOL = 1e-3


def check_tol(tol) -> float:
    """The driver tolerance ``tol`` (rad) as a float, or ProblemError.

    ``tol`` bounds max|α̂ − α| between contact steps (eq. 32; the paper's
    1e-3 rad); allowed: a real number in [1e-14, 1).
    """
    return float(check_number("tol", tol, low=1e-14, high=1.0, high_open=True, unit="rad"))


def _backend_of(solver, settings):
    """(back-end name, settings, why) for the ``solver`` argument of :func:`solve`."""
    if isinstance(solver, Selection):
        if solver.backend is None:
            raise ProblemError(f"solver: this Selection chose no back-end ({solver.reason})")
        return solver.backend, solver.settings or settings, "selected: " + solver.reason
    if not isinstance(solver, str):
        raise ProblemError(f"solver must be a back-end name, 'auto' or a Selection, got "
                           f"{describe(solver)}")
    if solver == "auto":
        return DEFAULT, settings, "auto: the built-in active set (exact)"
    return solver, settings, None


def solve(
    scene,
    solver: str | Selection = "auto",
    tol: float | None = None,
    *,
    accuracy: float | None = None,
    method: str = "globalised",
    max_outer: int = 200,
    settings: str | Settings = "default",
    start: ContactResult | str | None = None,
    pressure_limit: float | None = None,
    formulation: str | None = None,
) -> ContactResult:
    """Find the constrained equilibrium of a scene.

    Parameters
    ----------
    scene : ActuatorScene, SectionedScene or CantileverScene
        With an integer number of links N (``links="auto"`` needs the
        discretisation study of Sec. III-D, several solves:
        ``lcpbench.studies.discretisation.auto_links(scene)`` gives the N).
    solver : name of the contact-step back-end (``lcpbench solvers`` lists them
        all), "auto" (the built-in active set: a fixed rule, nothing is read),
        or a :class:`Selection` from :func:`lcpbench.select_backend`, whose
        back-end and settings are used.
    accuracy : the relative accuracy of the total force F = ΣR wanted, in
        [1e-9, 0.1] (F₀ = max(|F|, EI/ℓ²), as lcpbench's judge measures it):
        translated into the driver's tol, min(accuracy, 1e-3) rad, and the
        back-end's ε, min(accuracy, 1e-3) (:mod:`lcpbench.accuracy`,
        docs/accuracy.md). A converged answer's judge's bound meets it: one whose
        bound is over it is continued at tol accuracy/100, else returned
        ``converged=False``. Not with ``settings`` or a Selection (they set
        both); ``tol``, if given, is used instead of the translated one.
    tol : convergence threshold on max|α̂ − α| (rad), eq. (32), for experts.
        Default: the settings profile's ``driver_tol`` (the paper's 1e-3 for "default" and
        "low", 1e-6 for "mid", 1e-9 for "high"), or with a Selection the driver
        tolerance its probes ran at (``selection.driver_tol``), so the
        selected force accuracy is reached.
    method : "globalised" (line search on the exact energy; default),
        "newton" (the same with the exact Hessian, H + T of
        :mod:`lcpbench.model.newton`: quadratic convergence near the answer)
        or "undamped" (the paper's Fig. 3 iteration, for comparison).
    max_outer : limit on contact steps.
    settings : accuracy profile, one for the whole solve
        (:data:`lcpbench.solvers.base.PROFILES`: the back-end's ε and the
        driver's ``tol``, as in ``sweep`` and ``select``): "default" (the
        back-end's own defaults, 1e-3 rad), "low" (1e-3), "mid" (1e-6) or
        "high" (1e-9).
    start : a neighbouring scene's result (same N and length) to start from:
        continuation along θ or h. Its shape, clipped to this scene's walls, is
        the first iterate and its last contact step warm-starts back-ends that
        take one. Globalised scheme only; the answer is the same equilibrium
        to the tolerance (tests check 1e-8 at tight tol). Or ``"ramp"``: follow
        the load from zero, the bend angles grown from a straight chain in steps
        of at most 10° (:mod:`lcpbench.model.ramp`), the state the pressurised
        actuator reaches where a scene has several; a cold solve where the path
        stops. A cold start that the judge refuses is ramped anyway (the built-in
        back-end): ``result.route`` is "load path" for the first, and
        ``result.retries`` names "ramped" for the second (or "cold" where the
        path stopped).
    pressure_limit : a safety threshold on the contact pressure per length (N/mm,
        >= 0; None: none). The result reports ``pressure`` and ``indentation``
        per node, and ``pressure_exceeded`` is True when the largest pressure
        passes the limit (tissue walls, ``wall_stiffness``).
    formulation : the form each contact step is handed to the back-end in
        (:mod:`lcpbench.model.formulations`, docs/formulations.md): "gaps" (F1, the
        LCP), "heights" (F2, the box QP), "lifted" (F3), "reactions" (F4), "angles"
        (F5), each also "+ruiz" (equilibrated), each with an optional "@EPS", the
        tolerance handed to the back-end in place of the profile's ("angles@1e-6");
        "best": the back-end's measured recipe on the committed evidence
        (results/formulations): its form and, where the table gives one (OSQP and SCS
        at "default"), its ε; None (default): the back-end's own form, as before.
        ``result.extra["formulation"]`` and ``result.eps`` say what ran; the judge
        keeps ``settings``' accuracy whatever ε the back-end was handed. Elastic walls
        keep their own forms (no formulation, no recipe ε).

    Returns
    -------
    ContactResult
        Never raises on non-convergence: ``converged`` is False with a reason.
        The route, the start and the escalations are planned once
        (:func:`lcpbench.plan.make_plan`); the result's ``route``, ``engine``,
        ``judge`` and ``retries`` say what ran.
    """
    return solve_internal(scene, solver, tol, accuracy=accuracy, method=method,
                          max_outer=max_outer, settings=settings, start=start,
                          pressure_limit=pressure_limit, formulation=formulation)


def solve_internal(
    scene,
    solver: str | Selection = "auto",
    tol: float | None = None,
    *,
    accuracy: float | None = None,
    method: str = "globalised",
    max_outer: int = 200,
    settings: str | Settings = "default",
    scaled: bool = True,
    start: ContactResult | str | None = None,
    engine: str = "auto",
    pressure_limit: float | None = None,
    formulation: str | None = None,
) -> ContactResult:
    """:func:`solve` with its internals reachable, for the tests, the benchmarks and
    ``lcpbench solve --raw``; the other parameters are :func:`solve`'s.

    Parameters
    ----------
    scaled : hand the back-end the nondimensionalised step (default) or the
        raw one (mm, N), to see what scaling does.
    engine : "auto" (default: the default back-end with the globalised driver
        runs in one compiled kernel, :mod:`lcpbench.model.compiled`; another
        back-end that takes a QP or an LCP has the driver's own parts around
        its calls compiled, :mod:`lcpbench.model.compiled_driver`, also against
        walls of any profile and for the other schemes)
        or "compiled" (the kernel or the compiled driver, or ProblemError where
        neither applies); ``result.engine`` says which one ran. (The numpy
        reference engine, "numpy", was removed: passing it is a ProblemError.)
    """
    check_scene(scene)
    scaled = check_flag("scaled", scaled)
    if accuracy is not None:  # one knob: the driver tol and the back-end ε
        if isinstance(solver, Selection):
            raise ProblemError("accuracy: a Selection carries its own accuracy "
                               f"(force_tol {solver.force_tol:g}); give one of them")
        if not (isinstance(settings, str) and settings == "default"):
            raise ProblemError("accuracy sets the back-end's tolerance and the driver's: "
                               f"give accuracy or settings, not both (settings {settings!r})")
        settings = accuracy_settings(accuracy)
    if tol is not None:
        tol = check_tol(tol)
    elif isinstance(solver, Selection):
        tol = check_tol(solver.driver_tol)
    else:
        tol = get_settings(settings).driver_tol  # the profile's (a float in range)
    if method not in METHODS:
        raise ProblemError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if isinstance(max_outer, bool) or not (isinstance(max_outer, (int, np.integer))
                                           and max_outer >= 1):
        raise ProblemError(f"max_outer must be an integer >= 1, got {max_outer!r}")
    engine = check_engine(engine)
    if pressure_limit is not None:
        pressure_limit = float(check_number("pressure_limit", pressure_limit, low=0.0,
                                            high=1e12, unit="N/mm"))
    name, settings, why = _backend_of(solver, settings)
    if formulation is None and isinstance(solver, Selection):
        formulation = solver.formulation  # the form it was selected in
    # None: the back-end's own form (today's path)
    form = None if formulation is None else resolve_formulation(get_backend(name), formulation,
                                                                get_settings(settings))
    if name == DEFAULT and form is None:  # built in: its settings to check; its solver later
        get_settings(settings)
        step = None
    else:
        step = make_step_solver(name, settings, scaled, form)  # validates them first
    if getattr(scene, "links", None) == "auto":
        raise ProblemError("links='auto' is resolved by the discretisation study (Sec. III-D), "
                           "which runs several solves: use lcpbench.studies.discretisation."
                           "auto_links(scene) and scene.with_links(N)")
    t0 = time.perf_counter()
    chain = scene.chain()
    ramp = isinstance(start, str) and start == "ramp"
    if ramp and method == "undamped":
        raise ProblemError("start='ramp' (a continuation) needs method='globalised' or "
                           "'newton'")
    begin = None if ramp else _driver_start(start, chain, method)
    plan = make_plan(chain, name, method, engine, tol,
                     "ramp" if ramp else "cold" if begin is None else "warm", scaled=scaled)
    make_step = partial(make_step_solver, name, settings, scaled, form) \
        if step is None or ramp else lambda: step
    ctx = Context(chain, make_step, name, settings, engine, tol, int(max_outer), method, why,
                  pressure_limit)
    res = run_plan(plan, scene, ctx, begin, t0)
    ran = None if chain.elastic_walls else form  # elastic walls: each step its own forms
    res.eps = handed(get_settings(settings), ran).eps  # the recipe's where it gives one
    if ran is not None:
        res.extra["formulation"] = str(ran)
    if accuracy is None:
        return res
    return held_to(res, check_accuracy(accuracy), lambda t, r: solve_internal(
        scene, solver, t, method=method, max_outer=max_outer, settings=settings,
        scaled=scaled, start=None if method == "undamped" else r, engine=engine,
        pressure_limit=pressure_limit, formulation=formulation))


def run_plan(plan: Plan, scene, ctx: Context, begin: DriverStart | None,
             t0: float) -> ContactResult:
    """The result of ``plan`` (:func:`lcpbench.plan.make_plan`) for ``scene``: its route,
    then its escalations on a refused answer (:func:`lcpbench.escalations.escalate`);
    the load path's fallback where the path stops or is refused."""
    if plan.route == "load path":
        return _load_path(plan, scene, ctx, t0)
    chain = ctx.chain
    kernel = plan.kernel_takes  # the kernels take the chain: its arrays, once
    args = kernel_args(chain) if kernel else None
    lean_profile = (plan.route == PROFILE and begin is None and not chain.channel
                    and arc_far(chain))  # (a cold start, one wall, its arc far past it)
    if plan.route == ONE_WALL or lean_profile:  # the kernels, the rest of the result when read
        res = _one_wall(scene, chain, args, ctx.make_step, tol=ctx.tol,
                        max_outer=ctx.max_outer, method=ctx.method, settings=ctx.settings,
                        why=ctx.why, pressure_limit=ctx.pressure_limit, t0=t0,
                        route=plan.route)
    else:
        out: DriverOutput | None
        if plan.route == "channel kernel":
            out, used = run_kernel(chain, ctx.make_step, settings=ctx.settings, tol=ctx.tol,
                                   max_outer=ctx.max_outer, method=ctx.method, args=args)
        else:
            out = solve_without_contact(chain, ctx.tol, ctx.max_outer, begin, args=args)
            used = "compiled"  # (the wall-free tests and search are compiled)
            if out is None:
                out, used = drive(chain, ctx.make_step(), backend=ctx.backend,
                                  settings=ctx.settings, engine=ctx.engine, tol=ctx.tol,
                                  max_outer=ctx.max_outer, method=ctx.method, start=begin,
                                  args=args)
        res = finish(scene, chain, out, solver=ctx.backend, method=ctx.method, tol=ctx.tol,
                     elapsed=time.perf_counter() - t0, settings=ctx.settings, engine=used,
                     why=ctx.why, judge_args=None if args is None else chain_args(chain, args),
                     pressure_limit=ctx.pressure_limit, route=plan.route)
    return res if res.converged else escalate(res, ctx, plan.escalations)


def _load_path(plan: Plan, scene, ctx: Context, t0: float) -> ContactResult:
    """The "load path" route (``start="ramp"``): the loading path's answer where the
    judge certifies it, else the plan's fallback, the cold plan (with its own
    escalations), whose ``retries`` begin with ("cold", what the path did)."""
    out, used, told = follow_load(scene, ctx.make_step, backend=ctx.backend,
                                  settings=ctx.settings, engine=ctx.engine, tol=ctx.tol,
                                  max_outer=ctx.max_outer, method=ctx.method)
    if out is not None:
        res = finish(scene, ctx.chain, out, solver=ctx.backend, method=ctx.method,
                     tol=ctx.tol, elapsed=time.perf_counter() - t0, settings=ctx.settings,
                     engine=used, why=ctx.why,
                     pressure_limit=ctx.pressure_limit, route=plan.route)
        if res.converged:
            return res
        told = f"{told}; refused: {res.reason}"
    if plan.fallback is None:  # (make_plan gives the load path one)
        raise ValueError("a load path plan without its cold fallback")
    cold = run_plan(plan.fallback, scene, ctx, None, time.perf_counter())
    cold.retries = (Retry("cold", f"start='ramp': {told}; solved cold instead"),
                    *cold.retries)
    return cold


def _one_wall(scene, chain, args: tuple | None, make_step, *, tol: float, max_outer: int,
              method: str, settings, why: str | None, pressure_limit: float | None,
              t0: float, route: str = "one-wall kernel") -> ContactResult:
    """:func:`solve`'s direct route on a chain with one wall: the solve kernel (``route``
    "profile kernel": the profile kernel, its wall a profile), then, on a converged
    answer, the judge kernel and its verdict
    (:func:`lcpbench.model.batch_verdict.accepted`, the checks of the judge, as a
    batch line decides it); the result's other fields are built when read
    (:class:`~lcpbench.model.lazy_result.LazyResult`), by the same functions as
    :func:`run_kernel` and :func:`finish`. Where the kernel stops, its compiled
    fall-back, as :func:`run_kernel`; where the driver did not converge, :func:`finish` at once."""
    profile = route == PROFILE
    if profile:  # (the walls at the answer's x, its last two outputs: one wall, unused)
        got, kernel_s, name = call_profile_kernel(chain, tol=tol, max_outer=max_outer,
                                                  start=None, settings=settings)
        got = got[:-2]
    else:
        got, kernel_s, name = call_kernel(chain, tol=tol, max_outer=max_outer, start=None,
                                          settings=settings, args=args,
                                          newton=method == "newton")
    code = got[0]
    if code in BAIL_REASONS:
        out, used = reference(chain, make_step, BAIL_REASONS[code], tol=tol,
                              max_outer=max_outer, method=method, settings=settings)
        return finish(scene, chain, out, solver=DEFAULT, method=method, tol=tol,
                      elapsed=time.perf_counter() - t0, settings=settings, engine=used,
                      why=why, judge_args=chain_args(chain, args),
                      pressure_limit=pressure_limit, route=route)
    elapsed = time.perf_counter() - t0
    judge_args = chain_args(chain, args)
    build = partial(_built, scene, chain, got, kernel_s, name, method=method, tol=tol,
                    max_outer=max_outer, elapsed=elapsed, settings=settings, why=why,
                    pressure_limit=pressure_limit, route=route)
    jk = _JUDGE[0] if _JUDGE else _judge_kernels()
    if code != jk[0].CONVERGED:  # the driver's failure: judged at once, as always
        return build(judged=partial(judge, args=judge_args))
    alpha, rec, count, R = got[1], got[6], got[7], got[9]
    kern, f64 = jk[1], _contiguous  # (numpy's own float64: the AOT kernels' quick check)
    settled_code, st, fu, fl, tres = (kern.judge_walls if profile else kern.judge_answer)(
        f64(alpha, dtype=float), *judge_args, f64(R, dtype=float).copy(), np.zeros(R.size), tol,
        f64(rec[2, :count], dtype=float).copy())
    settled = bool(settled_code == kern.SETTLED)
    forces = fu if settled else R.copy()  # build_result's: the judge's R, else the driver's
    return lazy_result(LazyResult, {
        "scene": scene, "links": chain.links, "alpha": alpha, "forces": forces,
        "forces_lower": None, "total_force": float(_add_reduce(forces)),
        "outer_iterations": count,
        "converged": bool(jk[2].accepted(settled, f64(st, dtype=float), tol)),
        "solver": DEFAULT, "method": method, "tol": tol, "time_s": elapsed,
        "pressure_limit": pressure_limit, "route": route, "engine": "compiled",
        "judge": "heights", "retries": ()},
        partial(build, judged=stats_judge(settled, kern.STATS, st, fu, fl, tres)))


def _built(scene, chain, got: tuple, kernel_s: float, name: str, *, method: str, tol: float,
           max_outer: int, elapsed: float, settings, why, pressure_limit, judged, route: str
           ) -> ContactResult:
    """The complete result of :func:`_one_wall`, judged by ``judged``."""
    out = kernel_output(chain, *got, elapsed=kernel_s, settings=name, max_outer=max_outer,
                        tol=tol)
    return finish(scene, chain, out, solver=DEFAULT, method=method, tol=tol, elapsed=elapsed,
                  settings=settings, engine="compiled", why=why,
                  judged_by=judged, pressure_limit=pressure_limit, route=route)


ONE_WALL = "one-wall kernel"  # the routes of _one_wall (lcpbench.plan.ROUTES)
PROFILE = "profile kernel"
_JUDGE: list = []  # (solve kernel, judge kernel, batch_verdict), once loaded
_add_reduce = np.add.reduce
_contiguous = np.ascontiguousarray


def _judge_kernels() -> tuple:
    from .model import judge as judge_module
    from .model import kernel_call
    from .numba_cache import held, kernel_module

    found = (kernel_call.solve_kernel(), judge_module._kernel(),
             kernel_module("lcpbench.model.batch_verdict", "accepted"))
    held(_JUDGE).append(found)
    return found


def _driver_start(start, chain, method: str):
    if start is None:
        return None
    if not isinstance(start, ContactResult):
        raise ProblemError(f"start must be a ContactResult of a neighbouring scene or "
                           f"'ramp', got {describe(start)}")
    if method == "undamped":
        raise ProblemError("start (continuation) needs method='globalised' or 'newton'")
    if start.links != chain.links or \
            not math.isclose(getattr(start.scene, "length", chain.length), chain.length):
        raise ProblemError(f"start must have the same links and length as the scene "
                           f"(start: N = {start.links}; scene: N = {chain.links})")
    return DriverStart(np.asarray(start.alpha, float), start.extra.get("last_step"))


def solve_path(scene, states=None, tol: float | None = None, *, max_outer: int = 100,
               solver: str | None = None, lcp=None) -> list:
    """Solve a loading path: one :class:`~lcpbench.model.friction_result.FrictionResult`
    per state, each state solved from the last (issue 39, docs/friction.md).

    Parameters
    ----------
    scene : ActuatorScene or SectionedScene
        With ``friction``, ``left_end``, ``right_end`` and ``pull`` as it needs.
    states : sequence of dict, optional
        The scene fields each state changes, applied in turn (``theta``, ``height``,
        ``pull``, ``friction``, ``weight``, ``EI``; a row of sections also ``sections``,
        and its ``theta`` scales every section's θ); default: one state, the scene.
    tol : the outer loop's threshold on max|Δα| (rad; the paper's 1e-3 by default).
    max_outer : limit on contact steps per state.
    solver : the back-end of the frictional step, by name (default "lemke"): one whose
        registry record takes friction (``Backend.friction_form``: "lcp", Lemke and
        the LCP back-ends; "fc2d", the active set and Siconos' fc2d solvers; "tresca",
        the QP back-ends by a fixed point of Tresca steps; docs/friction.md).
    lcp : instead of ``solver``, a function ``(M, q) -> LCPSolution`` on the step's LCP.

    The path starts from the frictionless equilibrium of its first state; slips are
    measured from the previous state. A path in the paper's model (μ = 0, both ends
    pinned, no pull) is :func:`solve` for each state, unchanged. Never raises on
    non-convergence: a state's ``converged`` is False with a reason, and the states
    after it say so.
    """
    from .model.friction_path import run_path

    tol = PAPER_TOL if tol is None else check_tol(tol)
    if isinstance(max_outer, bool) or not (isinstance(max_outer, (int, np.integer))
                                           and max_outer >= 1):
        raise ProblemError(f"max_outer must be an integer >= 1, got {max_outer!r}")
    return run_path(scene, states, tol=tol, max_outer=int(max_outer), solve=solve, lcp=lcp,
                    solver=solver)
