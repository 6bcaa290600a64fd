"""The library call: ``lcpbench.solve(scene) -> ContactResult``.

It reads no file and imports no benchmark code: ``solver="auto"`` is a fixed
rule (the built-in active set, exact and O(N) per face solve), and a back-end
chosen by measurement is passed in explicitly as the
:class:`~lcpbench.solvers.selection.Selection` that
:func:`lcpbench.select_backend` returns.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from functools import partial

import numpy as np

from .errors import ProblemError
from .model import large_n
from .model.compiled import (
    _BAIL,
    applies,
    call_kernel,
    check_engine,
    direct,
    drive,
    heavy,
    kernel_args,
    kernel_output,
    reference,
    run_kernel,
)
from .model.driver import METHODS, DriverOutput, DriverStart
from .model.judge import force_tol, judge
from .model.judge_compiled import chain_args
from .model.lazy_result import LazyResult, lazy_result, stats_judge
from .model.ramp import follow_load
from .model.result import ContactResult, build_result
from .model.step_solver import make_step_solver
from .model.wall_free import solve_without_contact
from .problems.checks import check_flag, check_number, check_scene
from .problems.scenes import Chain
from .solvers.registry import DEFAULT, get_settings
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
                           f"{type(solver).__name__}")
    if solver == "auto":
        return DEFAULT, settings, "auto: the built-in active set (exact)"
    return solver, settings, None


def solve(
    scene,
    solver: str | Selection = "auto",
    tol: float | None = None,
    *,
    method: str = "globalised",
    max_outer: int = 200,
    settings: str = "default",
    scaled: bool = True,
    start: ContactResult | str | None = None,
    engine: str = "auto",
    pressure_limit: float | None = None,
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
    tol : convergence threshold on max|α̂ − α| (rad), eq. (32). Default: the
        paper's 1e-3 (``PAPER_TOL``), or with a Selection the driver
        tolerance its probes ran at (``selection.driver_tol``), so the
        selected force accuracy is reached.
    method : "globalised" (line search on the exact energy; default),
        "newton" (the same with the exact Hessian, H + T of
        :mod:`lcpbench.model.newton`: quadratic convergence near the answer)
        or "undamped" (the paper's Fig. 3 iteration, for comparison).
    max_outer : limit on contact steps.
    settings : accuracy profile of the back-end: "default" (its own defaults),
        "low" (1e-3), "mid" (1e-6) or "high" (1e-9).
    scaled : hand the back-end the nondimensionalised step (default) or the
        raw one (mm, N), to see what scaling does.
    start : a neighbouring scene's result (same N and length) to start from:
        continuation along θ or h. Its shape, clipped to this scene's walls, is
        the first iterate and its last contact step warm-starts back-ends that
        take one. Globalised scheme only; the answer is the same equilibrium
        to the tolerance (tests check 1e-8 at tight tol). Or ``"ramp"``: follow
        the load from zero, the bend angles grown from a straight chain in steps
        of at most 10° (:mod:`lcpbench.model.ramp`), the state the pressurised
        actuator reaches where a scene has several; a cold solve where the path
        stops. A cold start that the judge refuses is ramped anyway (the built-in
        back-end); ``extra["ramped"]`` says when either happened.
    engine : "auto" (default: the default back-end with the globalised driver
        runs in one compiled kernel, :mod:`lcpbench.model.compiled`; another
        back-end that takes a QP or an LCP has the driver's own parts around
        its calls compiled, :mod:`lcpbench.model.compiled_driver`; every other
        solve in numpy), "compiled" (the kernel or the compiled driver, or
        ProblemError where neither applies) or "numpy" (the readable
        reference). Both engines
        take the same path and give the same answer to round-off;
        ``result.extra["engine"]`` says which one ran.
    pressure_limit : a safety threshold on the contact pressure per length (N/mm,
        >= 0; None: none). The result reports ``pressure`` and ``indentation``
        per node, and ``pressure_exceeded`` is True when the largest pressure
        passes the limit (tissue walls, ``wall_stiffness``).

    Returns
    -------
    ContactResult
        Never raises on non-convergence: ``converged`` is False with a reason.
    """
    check_scene(scene)
    scaled = check_flag("scaled", scaled)
    if tol is not None:
        tol = check_tol(tol)
    elif isinstance(solver, Selection):
        tol = check_tol(solver.driver_tol)
    else:
        tol = PAPER_TOL  # (a float in range)
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
    if name == DEFAULT:  # built in: only its settings to check; its step solver when used
        get_settings(settings)
        step = None
    else:
        step = make_step_solver(name, settings, scaled)  # validates them first
    if getattr(scene, "links", None) == "auto":
        raise ProblemError("links='auto' is resolved by the discretisation study (Sec. III-D), "
                           "which runs several solves: use lcpbench.studies.discretisation."
                           "auto_links(scene) and scene.with_links(N)")
    t0 = time.perf_counter()
    chain = scene.chain()
    if isinstance(start, str) and start == "ramp":
        return _ramp_first(scene, chain, solver, tol=tol, method=method, max_outer=max_outer,
                           settings=settings, scaled=scaled, engine=engine,
                           pressure_limit=pressure_limit, name=name, why=why, t0=t0)
    begin = _driver_start(start, chain, method)
    # the compiled kernel where it takes the chain, unless the numpy reference is asked for
    kernel = engine != "numpy" and applies(DEFAULT, "globalised", chain)
    args = kernel_args(chain) if kernel else None  # the chain's arrays, once for all
    make_step = partial(make_step_solver, name, settings, scaled) if step is None \
        else lambda: step
    out: DriverOutput | None
    # drive()'s own route to the kernel, without the calls between
    route = kernel and name == DEFAULT and begin is None and method != "undamped" and \
        direct(chain)
    if route and not chain.channel:  # one wall: the kernels, the rest of the result when read
        res = _one_wall(scene, chain, args, make_step, tol=tol, max_outer=max_outer,
                        method=method, settings=settings, why=why,
                        pressure_limit=pressure_limit, t0=t0)
    else:
        if route:
            out, used = run_kernel(chain, make_step, settings=settings, tol=tol,
                                   max_outer=max_outer, method=method, args=args)
        else:
            out = solve_without_contact(chain, tol, max_outer, begin,
                                        engine="compiled" if kernel else "numpy", args=args)
            used = "compiled" if kernel else "numpy"
            if out is None:
                out, used = drive(chain, make_step(), backend=name, settings=settings,
                                  engine=engine, tol=tol, max_outer=max_outer, method=method,
                                  start=begin, args=args)
        res = finish(scene, chain, out, solver=name, method=method, tol=tol,
                     elapsed=time.perf_counter() - t0, settings=settings, engine=used,
                     compiled_judge=kernel, why=why,
                     judge_args=None if args is None else chain_args(chain, args),
                     pressure_limit=pressure_limit)
    return res if res.converged else retried(
        res, chain, make_step, backend=name, settings=settings, engine=engine, tol=tol,
        max_outer=max_outer, method=method, why=why, pressure_limit=pressure_limit)


def retried(res: ContactResult, chain: Chain, make_step: Callable, **kw) -> ContactResult:
    """An answer the result judge did not certify, solved further where that may be all
    it needs (the built-in back-end only): in increments where the round-off of node
    heights may have kept it from the tolerance (:func:`in_increments`), then, where the
    force error bound alone refused it, continued at a tenth of the driver's tolerance
    (:func:`tightened`). Keyword arguments: :func:`in_increments`'s."""
    res = in_increments(res, chain, make_step, **kw)
    res = res if res.converged else tightened(res, chain, make_step, **kw)
    res = res if res.converged else escaped(res, chain, make_step, **kw)
    return res if res.converged else ramped(res, chain, make_step, **kw)


def ramped(res: ContactResult, chain: Chain, make_step: Callable, *, backend: str,
           settings, engine: str, tol: float, max_outer: int, method: str,
           why: str | None, pressure_limit: float | None) -> ContactResult:
    """``res`` solved again along the loading path (:func:`lcpbench.model.ramp.follow_load`:
    the bend angles from zero, each step started from the last), where the judge refused
    it after the other escalations (the driver did not converge, stopped at a saddle it
    could not leave, or short of its force bound). The built-in back-end only, as
    :func:`tightened`; not the undamped scheme. The path's answer is continued as
    :func:`tightened` continues any answer. A certified answer has ``extra["ramped"]``;
    otherwise ``res`` is returned with why there."""
    judgement = res.judgement
    if backend != DEFAULT or method == "undamped" or judgement is None:
        return res
    t0 = time.perf_counter()
    out, used, told = follow_load(res.scene, make_step, backend=backend, settings=settings,
                                  engine=engine, tol=tol, max_outer=max_outer, method=method)
    elapsed = res.time_s + time.perf_counter() - t0
    if out is not None:
        again = _restart_judged(res.scene, chain, out, used, make_step, elapsed=elapsed,
                                solver=res.solver, backend=backend, settings=settings,
                                engine=engine, tol=tol, max_outer=max_outer, method=method,
                                why=why, pressure_limit=pressure_limit)
        if again.converged:
            again.extra["ramped"] = f"the cold start was refused ({res.reason}); {told}"
            return again
        told = f"{told}; refused: {again.reason}"
    res.extra["ramped"] = told
    res.time_s = elapsed
    return res


def _restart_judged(scene, chain: Chain, out: DriverOutput, used: str, make_step: Callable,
                    *, elapsed: float, solver: str, backend: str, settings, engine: str,
                    tol: float, max_outer: int, method: str, why: str | None,
                    pressure_limit: float | None) -> ContactResult:
    """A restart's answer (:func:`escaped`, :func:`ramped`) judged as every answer, and
    continued as :func:`tightened` continues a refusal on the force bound alone."""
    kernel = engine != "numpy" and applies(DEFAULT, "globalised", chain)
    res = finish(scene, chain, out, solver=solver, method=method, tol=tol, elapsed=elapsed,
                 settings=settings, engine=used, compiled_judge=kernel, why=why,
                 pressure_limit=pressure_limit)
    return res if res.converged else tightened(
        res, chain, make_step, backend=backend, settings=settings, engine=engine, tol=tol,
        max_outer=max_outer, method=method, why=why, pressure_limit=pressure_limit)


def escaped(res: ContactResult, chain: Chain, make_step: Callable, *, backend: str,
            settings, engine: str, tol: float, max_outer: int, method: str,
            why: str | None, pressure_limit: float | None) -> ContactResult:
    """``res`` left downhill where the result judge refused it as a saddle (check
    "stability" alone): the driver restarts from α ± t d along each direction d of
    negative curvature on its contact set (:func:`lcpbench.model.escape.escape_starts`)
    and the lowest-energy certified answer is returned, with ``extra["escaped"]``
    saying from what. Every back-end: a saddle is a fixed point of any exact contact
    step, not a failure of one back-end. Where no restart is certified, ``res`` with
    why in ``extra["escaped"]``; ``time_s`` counts every solve."""
    judgement = res.judgement
    if judgement is None or judgement.failed != ["stability"] or method == "undamped":
        return res
    from .model.chain import energy
    from .model.escape import escape_starts

    t0 = time.perf_counter()
    lower = res.forces_lower if res.forces_lower is not None else np.zeros_like(res.forces)
    starts = escape_starts(chain, np.asarray(res.alpha, float), res.forces, lower,
                           judgement.contact_threshold)
    best, tried = None, []
    for alpha in starts:
        out, used = drive(chain, make_step(), backend=backend, settings=settings,
                          engine=engine, tol=tol, max_outer=max_outer, method=method,
                          start=DriverStart(alpha))
        again = _restart_judged(res.scene, chain, out, used, make_step, elapsed=0.0,
                                solver=res.solver, backend=backend, settings=settings,
                                engine=engine, tol=tol, max_outer=max_outer, method=method,
                                why=why, pressure_limit=pressure_limit)
        tried.append(again.reason)
        if again.converged and (best is None or energy(chain, again.alpha)
                                < energy(chain, best.alpha)):
            best = again
    elapsed = res.time_s + time.perf_counter() - t0
    told = (f"the driver reached a saddle (F = {res.total_force:.6g} N, "
            f"{judgement.unstable_directions} unstable directions)")
    if best is None:
        res.extra["escaped"] = (f"{told}; {len(starts)} restarts downhill of it"
                                + (f", none certified: {tried[0]}" if tried else ""))
        res.time_s = elapsed
        return res
    best.extra["escaped"] = (f"{told}; restarted downhill along its negative curvature "
                             f"({len(starts)} restarts) to this stable equilibrium")
    best.time_s = elapsed
    return best


#: the driver tolerance of :func:`tightened`, as a fraction of the requested one
TIGHTER = 0.1
#: outer steps :func:`tightened` may take: an answer a step short of its bound needs
#: one or two; one at the driver's round-off (N = 10⁵, tol 1e-10) wanders at
#: 1e-11…1e-10 rad for 19 steps, 0.45 s, and is refused all the same
TIGHTEN_STEPS = 5


def tightened(res: ContactResult, chain: Chain, make_step: Callable, *, backend: str,
              settings, engine: str, tol: float, max_outer: int, method: str,
              why: str | None, pressure_limit: float | None) -> ContactResult:
    """``res`` continued from its own angles (and its last step, as a warm start) with the
    driver's tolerance :data:`TIGHTER` · ``tol``, where lcpbench's result judge refused it
    on its force error bound alone (the total's, a node's, or a judge step that did not
    settle: the judge's check "force error bound"); otherwise ``res`` itself. The built-in
    back-end only: another back-end's refusal stays its own, as a benchmark must see it;
    not the paper's undamped scheme.

    The bound, |F_k − F_{k+1}| / (1 − ρ) with ρ from the last steps, is an a-posteriori
    estimate: an answer within τ can fail it when the driver stopped on max|Δα| < tol a
    step early (θ = 96.7°, h = 4.41 mm, N = 173: 5.4·10⁻⁴ F₀ from the reference, bounded
    by 1.1·10⁻³ against the allowed 10⁻³; one more outer step, 7.8·10⁻⁶). The
    continuation is judged at ``tol``, as every answer, by the same judge, on the step
    records of both solves (ρ from all of them); it takes at most :data:`TIGHTEN_STEPS`
    of the outer steps ``res`` left of ``max_outer`` (where the driver is at its
    round-off, more would not help). A certified continuation's outer iterations, step
    records and ``time_s`` count both solves; where it is refused too, ``res`` is returned
    with its own steps, ``time_s`` counting both, and why in ``extra["tightened"]``."""
    if backend != DEFAULT or method == "undamped":
        return res
    judgement = res.judgement
    left = max_outer - res.outer_iterations
    if judgement is None or judgement.failed != ["force error bound"] or left < 1:
        return res
    t0 = time.perf_counter()
    out, used = drive(chain, make_step(), backend=backend, settings=settings, engine=engine,
                      tol=TIGHTER * tol, max_outer=min(left, TIGHTEN_STEPS), method=method,
                      start=DriverStart(np.asarray(res.alpha, dtype=float),
                                        res.extra.get("last_step")))
    out.steps = [*res.steps, *out.steps]  # judged, and reported, as one run
    kernel = engine != "numpy" and applies(DEFAULT, "globalised", chain)
    again = finish(res.scene, chain, out, solver=res.solver, method=method, tol=tol,
                   elapsed=res.time_s + time.perf_counter() - t0, settings=settings,
                   engine=used, compiled_judge=kernel, why=why, pressure_limit=pressure_limit)
    told = (f"refused on the force error bound alone ({judgement.reason}); continued from "
            f"its angles at driver tolerance {TIGHTER * tol:.1e} rad")
    if not again.converged:
        res.extra["tightened"] = f"{told}: {again.reason}"
        res.time_s = again.time_s  # both solves
        return res
    again.extra["tightened"] = f"{told} ({res.outer_iterations} outer steps before, counted)"
    for key, value in res.extra.items():  # a batch's continuation, discarded attempt
        again.extra.setdefault(key, value)
    return again


def in_increments(res: ContactResult, chain: Chain, make_step: Callable, *, backend: str,
                  settings, engine: str, tol: float, max_outer: int, method: str, why: str | None,
                  pressure_limit: float | None) -> ContactResult:
    """``res`` again, solved in increments on the tridiagonal factor, where the round-off
    of the height formulation may have kept the judge from certifying it
    (:func:`lcpbench.model.large_n.roundoff_limited`); otherwise ``res`` itself. Only
    the built-in back-end's answers (``backend``): another back-end's rejection stays
    its own, as a benchmark must see it.

    In node heights round-off grows with cond H ~ N⁴: on the paper scene the answer at
    N = 3000 stops 1.6·10⁻⁷ F₀ from the force (the judge's exact step sees it), so it
    cannot be certified at tol 1e-9 (τ = 100 tol = 10⁻⁷), however long the driver runs.
    The same solve in increments (cond ~ N², as from ``LARGE_N`` links) starts from
    ``res``'s angles (``chain``: its scene's) with the outer steps ``res`` left of
    ``max_outer``, and is judged in increments too. Its outer steps are the answer's
    (``extra["increments"]`` says why it ran and how many ``res`` took); ``time_s``
    counts both solves; ``res``'s other ``extra`` entries (a batch's continuation) are
    kept. Where it does not converge either, ``res`` is returned with that in
    ``extra["increments"]``. A chain heavy enough for SQP steps in the link angles
    (:func:`lcpbench.model.compiled.heavy`) is not retried: those steps are not in
    node heights."""
    from dataclasses import replace

    if backend != DEFAULT or not large_n.roundoff_may_limit(chain, force_tol(tol), method):
        return res  # (its judgement not read: a lazy result stays lazy)
    judgement = res.judgement
    left = max_outer - res.outer_iterations
    if judgement is None or left < 1 or heavy(chain) \
            or not large_n.roundoff_limited(chain, judgement, method):
        return res
    t0 = time.perf_counter()
    chain = replace(chain, increments=True)
    out, used = drive(chain, make_step(), backend=backend, settings=settings,
                      engine=engine, tol=tol, max_outer=left, method=method,
                      start=DriverStart(np.asarray(res.alpha, dtype=float)))
    again = finish(res.scene, chain, out, solver=res.solver, method=method, tol=tol,
                   elapsed=res.time_s + time.perf_counter() - t0, settings=settings,
                   engine=used, compiled_judge=False, why=why, pressure_limit=pressure_limit)
    told = (f"the judge in node heights did not certify the answer ({judgement.reason}); at "
            f"N = {chain.links} their round-off (cond H · ε = "
            f"{large_n.heights_condition(chain.links) * np.finfo(float).eps:.1e}) may reach "
            f"τ = {judgement.force_tol:.1e}")
    if not again.converged:
        res.extra["increments"] = f"{told}; solved again in increments: {again.reason}"
        res.time_s = again.time_s  # both solves
        return res
    again.extra["increments"] = (f"{told}; solved again in increments on the tridiagonal "
                                 f"factor from that answer ({res.outer_iterations} outer "
                                 f"steps there, not counted)")
    for key, value in res.extra.items():  # a batch's continuation, discarded attempt
        again.extra.setdefault(key, value)
    return again


def finish(scene, chain, out, *, solver: str, method: str, tol: float, elapsed: float,
           settings, engine: str, compiled_judge: bool, why: str | None,
           judge_args: tuple | None = None,
           pressure_limit: float | None = None,
           judged_by: Callable | None = None) -> ContactResult:
    """The judged result of a driver run (the end of :func:`solve`; also the batch's).

    Judged by the compiled judge (the same checks and verdicts as the numpy judge,
    independent of the solve kernel) where ``compiled_judge`` (it takes the chain,
    whichever back-end solved the steps); engine="numpy" keeps the numpy judge, the
    reference. ``judge_args``: the chain's arrays for the judge kernel, when the
    caller has them (:func:`lcpbench.model.judge_compiled.chain_args`). ``judged_by``:
    the judgement already made (a batch line's, from the judge kernel's numbers), in
    place of the judge call."""
    if not out.converged and getattr(scene, "theta", 0) > 180:
        out.reason = ("theta > 180 deg: the end links start beyond the vertical, where the "
                      "linearisation of eq. (20) is singular for a cold start; start='ramp' "
                      f"follows the load from zero instead ({out.reason})")
    compiled_judge = compiled_judge and not large_n.applies(chain)  # large N: increments
    if judged_by is None:
        judged_by = judge
        if compiled_judge:
            judged_by = _FAST[0] if _FAST else _judge_fast()
            if judge_args is not None:
                judged_by = partial(judged_by, args=judge_args)
    res = build_result(scene, chain, out, solver=solver, method=method, tol=tol,
                       time_s=elapsed, judged_by=judged_by)
    res.extra["last_step"] = out.last_step  # what a continuation hands the next scene
    res.extra["settings"] = settings if isinstance(settings, str) else "custom"
    res.extra["engine"] = engine
    res.extra["judge"] = "compiled" if compiled_judge else "numpy"
    res.pressure_limit = pressure_limit
    if why is not None:
        res.extra["auto"] = why
    return res


def _one_wall(scene, chain, args: tuple | None, make_step, *, tol: float, max_outer: int,
              method: str, settings, why: str | None, pressure_limit: float | None,
              t0: float) -> ContactResult:
    """:func:`solve`'s direct route on a chain with one wall: the solve kernel, then,
    on a converged answer, the judge kernel and its verdict
    (:func:`lcpbench.model.batch_verdict.accepted`, the checks of the judge, as a
    batch line decides it); the result's other fields are built when read
    (:class:`~lcpbench.model.lazy_result.LazyResult`), by the same functions as
    :func:`run_kernel` and :func:`finish`. Where the kernel stops, the numpy reference,
    as :func:`run_kernel`; where the driver did not converge, :func:`finish` at once."""
    got, kernel_s, name = call_kernel(chain, tol=tol, max_outer=max_outer, start=None,
                                      settings=settings, args=args, newton=method == "newton")
    code = got[0]
    if code in _BAIL:
        out, used = reference(chain, make_step, _BAIL[code], tol=tol, max_outer=max_outer,
                              method=method, settings=settings)
        return finish(scene, chain, out, solver=DEFAULT, method=method, tol=tol,
                      elapsed=time.perf_counter() - t0, settings=settings, engine=used,
                      compiled_judge=True, why=why, judge_args=chain_args(chain, args),
                      pressure_limit=pressure_limit)
    elapsed = time.perf_counter() - t0
    judge_args = chain_args(chain, args)
    build = partial(_built, scene, chain, got, kernel_s, name, method=method, tol=tol,
                    max_outer=max_outer, elapsed=elapsed, settings=settings, why=why,
                    pressure_limit=pressure_limit)
    jk = _JUDGE[0] if _JUDGE else _judge_kernels()
    if code != jk[0].CONVERGED:  # the driver's failure: judged at once, as always
        return build(judged=partial(_FAST[0] if _FAST else _judge_fast(), args=judge_args))
    alpha, rec, count, R = got[1], got[6], got[7], got[9]
    judge, f64 = jk[1], _contiguous  # (numpy's own float64: the AOT kernels' quick check)
    settled_code, st, fu, fl, tres = judge.judge_answer(
        f64(alpha, dtype=float), *judge_args, f64(R, dtype=float).copy(), np.zeros(R.size), tol,
        f64(rec[2, :count], dtype=float).copy())
    settled = bool(settled_code == judge.SETTLED)
    forces = fu if settled else R.copy()  # build_result's: the judge's R, else the driver's
    return lazy_result(LazyResult, {
        "scene": scene, "links": chain.links, "alpha": alpha, "forces": forces,
        "forces_lower": None, "total_force": float(_add_reduce(forces)),
        "outer_iterations": count,
        "converged": bool(jk[2].accepted(settled, f64(st, dtype=float), tol)),
        "solver": DEFAULT, "method": method, "tol": tol, "time_s": elapsed,
        "pressure_limit": pressure_limit},
        partial(build, judged=stats_judge(settled, judge.STATS, st, fu, fl, tres)))


def _built(scene, chain, got: tuple, kernel_s: float, name: str, *, method: str, tol: float,
           max_outer: int, elapsed: float, settings, why, pressure_limit, judged
           ) -> ContactResult:
    """The complete result of :func:`_one_wall`, judged by ``judged``."""
    out = kernel_output(chain, *got, elapsed=kernel_s, settings=name, max_outer=max_outer,
                        tol=tol)
    return finish(scene, chain, out, solver=DEFAULT, method=method, tol=tol, elapsed=elapsed,
                  settings=settings, engine="compiled", compiled_judge=True, why=why,
                  judged_by=judged, pressure_limit=pressure_limit)


_JUDGE: list = []  # (solve kernel, judge kernel, batch_verdict), once loaded
_add_reduce = np.add.reduce
_contiguous = np.ascontiguousarray


def _judge_kernels() -> tuple:
    from .model import compiled, judge_compiled
    from .numba_cache import held, kernel_module

    found = (compiled._kernel(), judge_compiled._kernel(),
             kernel_module("lcpbench.model.batch_verdict", "accepted"))
    held(_JUDGE).append(found)
    return found


_FAST: list = []  # judge_fast, once imported


def _judge_fast():
    from .model.judge_compiled import judge_fast

    _FAST.append(judge_fast)
    return judge_fast


def _ramp_first(scene, chain, solver, *, tol, method, max_outer, settings, scaled, engine,
                pressure_limit, name, why, t0) -> ContactResult:
    """``solve(scene, start="ramp")``: the loading path's answer where the judge certifies
    it, else the cold solve (with its own escalations), each saying what was tried."""
    if method == "undamped":
        raise ProblemError("start='ramp' (a continuation) needs method='globalised' or "
                           "'newton'")
    make_step = partial(make_step_solver, name, settings, scaled)
    out, used, told = follow_load(scene, make_step, backend=name, settings=settings,
                                  engine=engine, tol=tol, max_outer=max_outer, method=method)
    if out is not None:
        kernel = engine != "numpy" and applies(DEFAULT, "globalised", chain)
        res = finish(scene, chain, out, solver=name, method=method, tol=tol,
                     elapsed=time.perf_counter() - t0, settings=settings, engine=used,
                     compiled_judge=kernel, why=why, pressure_limit=pressure_limit)
        if res.converged:
            res.extra["ramped"] = told
            return res
        told = f"{told}; refused: {res.reason}"
    cold = solve(scene, solver, tol, method=method, max_outer=max_outer, settings=settings,
                 scaled=scaled, engine=engine, pressure_limit=pressure_limit)
    cold.extra.setdefault("ramped", f"start='ramp': {told}; solved cold instead")
    return cold


def _driver_start(start, chain, method: str):
    if start is None:
        return None
    if not isinstance(start, ContactResult):
        raise ProblemError(f"start must be a ContactResult of a neighbouring scene or "
                           f"'ramp', got {start!r}" if isinstance(start, str) else
                           f"start must be a ContactResult of a neighbouring scene or "
                           f"'ramp', got {type(start).__name__}")
    if method == "undamped":
        raise ProblemError("start (continuation) needs method='globalised' or 'newton'")
    if start.links != chain.links or \
            not math.isclose(getattr(start.scene, "length", chain.length), chain.length):
        raise ProblemError(f"start must have the same links and length as the scene "
                           f"(start: N = {start.links}; scene: N = {chain.links})")
    return DriverStart(np.asarray(start.alpha, float), start.extra.get("last_step"))
