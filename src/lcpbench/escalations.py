"""What :func:`lcpbench.solve` does with an answer the result judge refused: the
escalations, as data in one place (:data:`ESCALATIONS`).

Each escalation has a name, a predicate on the solve (``planned``: whether a plan
lists it, decided up front by :func:`lcpbench.plan.make_plan` from the chain, the
back-end, the method and the tolerance), a predicate on the refused result
(``applies``) and its function (``run``: the result to go on with and one line on
why it ran and what came of it). :func:`escalate` runs a plan's escalations in the
table's order while the answer stays refused; each that ran is a
:class:`~lcpbench.model.result.Retry` in the result's ``retries``.

In the table's order:

- ``in_increments``: the same solve in increments on the tridiagonal factor, where the
  round-off of node heights may have kept the judge from certifying it;
- ``tightened``: continued at a tenth of the driver's tolerance, where the force error
  bound alone refused it;
- ``escaped``: restarted downhill where it is a saddle (the check "stability" alone),
  then, where a restart is certified, the loading path as a second start; the distinct
  stable states these starts reach are the result's ``states``;
- ``from_neighbour``: in :func:`lcpbench.solve_many` only, a row of sections solved by
  SQP steps in the link angles from the loading path's answer of a neighbouring row of
  the same batch (:attr:`Context.neighbour`, chosen by :mod:`lcpbench.studies.batch`);
- ``ramped``: solved again along the loading path (the bend angles from zero).

The built-in back-end only, but ``escaped`` (a saddle is a fixed point of any exact
contact step); never the paper's undamped scheme. Another back-end's refusal stays
its own, as a benchmark must see it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .model import large_n
from .model.angle_step import in_reach
from .model.chain import energy
from .model.compiled import drive, heavy
from .model.finish import finish
from .model.heavy_driver import run_heavy
from .model.judge import Judgement, force_tol
from .model.outer import DriverOutput, DriverStart
from .model.ramp import first_multipliers, follow_load
from .model.result import ContactResult, ReachedState, Retry
from .problems.scenes import Chain
from .solvers.registry import DEFAULT

#: the driver tolerance of :func:`tightened`, as a fraction of the requested one
TIGHTER = 0.1
#: outer steps :func:`tightened` may take: an answer a step short of its bound needs
#: one or two; one at the driver's round-off (N = 10⁵, tol 1e-10) wanders at
#: 1e-11…1e-10 rad for 19 steps, 0.45 s, and is refused all the same
TIGHTEN_STEPS = 5


@dataclass(frozen=True)
class Context:
    """The solve an escalation continues: its chain, a maker of its step solver, and
    the arguments of :func:`lcpbench.solve` (checked)."""

    chain: Chain
    make_step: Callable[[], Callable]
    backend: str
    settings: Any
    engine: str
    tol: float
    max_outer: int
    method: str
    why: str | None = None
    pressure_limit: float | None = None
    #: :func:`lcpbench.solve_many`: the loading path's answer of a neighbouring row of the
    #: batch (:func:`from_neighbour`); None in :func:`lcpbench.solve`
    neighbour: ContactResult | None = None


@dataclass(frozen=True)
class Escalation:
    """One row of :data:`ESCALATIONS`."""

    planned: Callable[[Chain, str, str, float], bool]  # (chain, back-end, method, tol)
    applies: Callable[[ContactResult, Context], bool]  # to this refused result
    #: (result, why): ``res`` itself, or a new result whose ``retries`` are those of the
    #: solves inside the escalation (a restart's continuation)
    run: Callable[[ContactResult, Context], tuple[ContactResult, str]]
    #: planned only where the solve has a neighbour's answer (:attr:`Context.neighbour`:
    #: :func:`lcpbench.solve_many`'s rows of sections)
    needs_neighbour: bool = False


def escalate(res: ContactResult, ctx: Context, names) -> ContactResult:
    """``res``, or where the judge refused it, the escalations ``names`` (a plan's, in
    the table's order) each run where it applies, until one is certified. The result
    keeps ``res``'s route; its ``retries`` are ``res``'s, then one per escalation that
    ran (with those of the restarts inside it)."""
    for name in names:
        if res.converged:
            break
        step = ESCALATIONS[name]
        if not step.applies(res, ctx):
            continue
        got, why = step.run(res, ctx)
        inner = got.retries if got is not res else ()
        got.retries = (*res.retries, Retry(name, why), *inner)
        got.route = res.route
        res = got
    return res


def _judgement(res: ContactResult) -> Judgement:
    """``res``'s judgement (an escalation applies to judged results only)."""
    if res.judgement is None:
        raise ValueError("an escalation runs on a judged result")
    return res.judgement


def _left(res: ContactResult, ctx: Context) -> int:
    return ctx.max_outer - res.outer_iterations


def _failed_only(check: str) -> Callable[[ContactResult, Context], bool]:
    def applies(res: ContactResult, ctx: Context) -> bool:
        j = res.judgement
        return j is not None and j.failed == [check] and (check == "stability"
                                                           or _left(res, ctx) >= 1)
    return applies


def _keep_extra(res: ContactResult, again: ContactResult) -> None:
    for key, value in res.extra.items():  # a batch's continuation, discarded attempt
        again.extra.setdefault(key, value)


def _judged(res: ContactResult, ctx: Context, chain: Chain, out: DriverOutput, used: str,
            t0: float) -> ContactResult:
    return finish(res.scene, chain, out, solver=res.solver, method=ctx.method, tol=ctx.tol,
                  elapsed=res.time_s + time.perf_counter() - t0, settings=ctx.settings,
                  engine=used, why=ctx.why,
                  pressure_limit=ctx.pressure_limit, route=res.route)


# -- in increments ------------------------------------------------------------------
def _increments_planned(chain: Chain, backend: str, method: str, tol: float) -> bool:
    return (backend == DEFAULT and large_n.roundoff_may_limit(chain, force_tol(tol), method)
            and not heavy(chain))


def _increments_apply(res: ContactResult, ctx: Context) -> bool:
    if not large_n.roundoff_may_limit(ctx.chain, force_tol(ctx.tol), ctx.method):
        return False  # (its judgement not read: a lazy result stays lazy)
    j = res.judgement
    return (j is not None and _left(res, ctx) >= 1 and not heavy(ctx.chain)
            and large_n.roundoff_limited(ctx.chain, j, ctx.method))


def in_increments(res: ContactResult, ctx: Context) -> tuple[ContactResult, str]:
    """``res`` again, solved in increments on the tridiagonal factor, where the round-off
    of the height formulation may have kept the judge from certifying it
    (:func:`lcpbench.model.large_n.roundoff_limited`).

    In node heights round-off grows with cond H ~ N⁴: on the paper scene the answer at
    N = 3000 stops 1.6·10⁻⁷ F₀ from the force (the judge's exact step sees it), so it
    cannot be certified at tol 1e-9 (τ = 100 tol = 10⁻⁷), however long the driver runs.
    The same solve in increments (cond ~ N², as from ``LARGE_N`` links) starts from
    ``res``'s angles with the outer steps ``res`` left of ``max_outer``, and is judged in
    increments too. Its outer steps are the answer's; ``time_s`` counts both solves;
    ``res``'s ``extra`` entries (a batch's continuation) are kept. Where it does not
    converge either, ``res`` is returned. A chain heavy enough for SQP steps in the link
    angles (:func:`lcpbench.model.compiled.heavy`) is not retried: those steps are not
    in node heights."""
    judgement = _judgement(res)
    t0 = time.perf_counter()
    chain = replace(ctx.chain, increments=True)
    out, used = drive(chain, ctx.make_step(), backend=ctx.backend, settings=ctx.settings,
                      engine=ctx.engine, tol=ctx.tol, max_outer=_left(res, ctx),
                      method=ctx.method, start=DriverStart(np.asarray(res.alpha, dtype=float)))
    again = _judged(res, ctx, chain, out, used, t0)
    told = (f"the judge in node heights did not certify the answer ({judgement.reason}); at "
            f"N = {chain.links} their round-off (cond H · ε = "
            f"{large_n.heights_condition(chain.links) * np.finfo(float).eps:.1e}) may reach "
            f"τ = {judgement.force_tol:.1e}")
    if not again.converged:
        res.time_s = again.time_s  # both solves
        return res, f"{told}; solved again in increments: {again.reason}"
    _keep_extra(res, again)
    return again, (f"{told}; solved again in increments on the tridiagonal factor from "
                   f"that answer ({res.outer_iterations} outer steps there, not counted)")


# -- tightened ----------------------------------------------------------------------
def _own_globalised(chain: Chain, backend: str, method: str, tol: float) -> bool:
    return backend == DEFAULT and method != "undamped"


def tightened(res: ContactResult, ctx: Context) -> tuple[ContactResult, str]:
    """``res`` continued from its own angles (and its last step, as a warm start) with the
    driver's tolerance :data:`TIGHTER` · ``tol``, where the result judge refused it on
    its force error bound alone (the total's, a node's, or a judge step that did not
    settle: the judge's check "force error bound").

    The bound, |F_k − F_{k+1}| / (1 − ρ) with ρ from the last steps, is an a-posteriori
    estimate: an answer within τ can fail it when the driver stopped on max|Δα| < tol a
    step early (θ = 96.7°, h = 4.41 mm, N = 173: 5.4·10⁻⁴ F₀ from the reference, bounded
    by 1.1·10⁻³ against the allowed 10⁻³; one more outer step, 7.8·10⁻⁶). The
    continuation is judged at ``tol``, as every answer, by the same judge, on the step
    records of both solves (ρ from all of them); it takes at most :data:`TIGHTEN_STEPS`
    of the outer steps ``res`` left of ``max_outer`` (where the driver is at its
    round-off, more would not help). A certified continuation's outer iterations, step
    records and ``time_s`` count both solves; where it is refused too, ``res`` is returned
    with its own steps, ``time_s`` counting both."""
    judgement = _judgement(res)
    t0 = time.perf_counter()
    out, used = drive(ctx.chain, ctx.make_step(), backend=ctx.backend, settings=ctx.settings,
                      engine=ctx.engine, tol=TIGHTER * ctx.tol,
                      max_outer=min(_left(res, ctx), TIGHTEN_STEPS), method=ctx.method,
                      start=DriverStart(np.asarray(res.alpha, dtype=float),
                                        res.extra.get("last_step")))
    out.steps = [*res.steps, *out.steps]  # judged, and reported, as one run
    again = _judged(res, ctx, ctx.chain, out, used, t0)
    told = (f"refused on the force error bound alone ({judgement.reason}); continued from "
            f"its angles at driver tolerance {TIGHTER * ctx.tol:.1e} rad")
    if not again.converged:
        res.time_s = again.time_s  # both solves
        return res, f"{told}: {again.reason}"
    _keep_extra(res, again)
    return again, f"{told} ({res.outer_iterations} outer steps before, counted)"


def _restart_judged(res: ContactResult, ctx: Context, out: DriverOutput, used: str,
                    elapsed: float) -> ContactResult:
    """A restart's answer (:func:`escaped`, :func:`ramped`) judged as every answer, and
    continued as :func:`tightened` continues a refusal on the force bound alone."""
    again = finish(res.scene, ctx.chain, out, solver=res.solver, method=ctx.method,
                   tol=ctx.tol, elapsed=elapsed, settings=ctx.settings, engine=used,
                   why=ctx.why,
                   pressure_limit=ctx.pressure_limit, route=res.route)
    planned = ESCALATIONS["tightened"].planned(ctx.chain, ctx.backend, ctx.method, ctx.tol)
    return escalate(again, ctx, ("tightened",) if planned else ())


# -- escaped ------------------------------------------------------------------------
def _not_undamped(chain: Chain, backend: str, method: str, tol: float) -> bool:
    return method != "undamped"


def escaped(res: ContactResult, ctx: Context) -> tuple[ContactResult, str]:
    """``res`` left downhill where the result judge refused it as a saddle (check
    "stability" alone): the driver restarts from α ± t d along each direction d of
    negative curvature on its contact set (:func:`lcpbench.model.escape.escape_starts`)
    and the lowest-energy certified answer is returned. Every back-end: a saddle is a
    fixed point of any exact contact step, not a failure of one back-end. Where no
    restart is certified, ``res``; ``time_s`` counts every solve.

    A saddle separates stable states, so the scene has more than one in reach. Where
    a restart is certified and the built-in back-end solves, the loading path
    (:func:`lcpbench.model.ramp.follow_load`, the bend angles from zero) is followed
    too, as a second start: it costs a few warm solves, a tenth of the restarts
    (16–31 ms against 360–590 ms on the channel scenes of issue 36). The answer stays
    the escape's; where the certified answers of all these starts hold distinct states,
    the result's ``states`` lists each with its exact energy (:func:`reached_states`:
    distinct in the force of a wall, :func:`same_state`)."""
    from .model.escape import escape_starts

    judgement = _judgement(res)
    chain = ctx.chain
    t0 = time.perf_counter()
    lower = res.forces_lower if res.forces_lower is not None else np.zeros_like(res.forces)
    starts = escape_starts(chain, np.asarray(res.alpha, float), res.forces, lower,
                           judgement.contact_threshold)
    certified: list[tuple[str, ContactResult]] = []
    tried = []
    for alpha in starts:
        out, used = drive(chain, ctx.make_step(), backend=ctx.backend, settings=ctx.settings,
                          engine=ctx.engine, tol=ctx.tol, max_outer=ctx.max_outer,
                          method=ctx.method, start=DriverStart(alpha))
        again = _restart_judged(res, ctx, out, used, elapsed=0.0)
        tried.append(again.reason)
        if again.converged:
            certified.append(("escape", again))
    best = min((r for _, r in certified), key=lambda r: energy(chain, r.alpha), default=None)
    told = (f"the driver reached a saddle (F = {res.total_force:.6g} N, "
            f"{judgement.unstable_directions} unstable directions)")
    if best is None:
        res.time_s = res.time_s + time.perf_counter() - t0
        return res, (f"{told}; {len(starts)} restarts downhill of it"
                     + (f", none certified: {tried[0]}" if tried else ""))
    path = ""
    if _own_globalised(chain, ctx.backend, ctx.method, ctx.tol):
        ended, used, path = follow_load(res.scene, ctx.make_step, backend=ctx.backend,
                                        settings=ctx.settings, engine=ctx.engine,
                                        tol=ctx.tol, max_outer=ctx.max_outer,
                                        method=ctx.method)
        if ended is not None:
            loaded = _restart_judged(res, ctx, ended, used, elapsed=0.0)
            if loaded.converged:
                certified.append(("loading path", loaded))
            else:
                path = f"{path}; refused: {loaded.reason}"
    best.states = reached_states(chain, best, certified)
    best.time_s = res.time_s + time.perf_counter() - t0
    several = (f"; {len(best.states)} distinct stable states reached, the answer's energy "
               f"{next(s.energy for s in best.states if s.answer):.6g} N·mm (result.states)"
               if best.states else "")
    return best, (f"{told}; restarted downhill along its negative curvature "
                  f"({len(starts)} restarts) to this stable equilibrium"
                  + (f"; the loading path as a second start: {path}" if path else "")
                  + several)


def same_state(a: ContactResult, b: ContactResult) -> bool:
    """Whether two certified answers of one scene are one state for the user: the total
    force of each wall agrees to the accuracy asked of both, the larger of their τ·F₀
    (:func:`lcpbench.model.judge.force_tol`, F₀ = max(|F|, EI/ℓ²)). Not the link
    angles: a folded chain in a channel has a valley of equal energy along which
    certified answers at tol 1e-3 differ by up to 1.1 rad but by 10⁻⁵ in force."""
    ja, jb = _judgement(a), _judgement(b)
    allowed = max(ja.force_tol * ja.force_unit, jb.force_tol * jb.force_unit)

    def lower(r: ContactResult) -> float:
        return 0.0 if r.forces_lower is None else float(np.sum(r.forces_lower))

    return (abs(a.total_force - b.total_force) <= allowed
            and abs(lower(a) - lower(b)) <= allowed)


def reached_states(chain: Chain, answer: ContactResult,
                   certified: list[tuple[str, ContactResult]]) -> tuple[ReachedState, ...]:
    """The distinct states (:func:`same_state`) among the ``certified`` answers of a
    solve's starts ((start, result) pairs, ``answer`` among them), lowest energy first,
    each with its exact energy (:func:`lcpbench.model.chain.energy`); of answers that
    are one state the answer is kept, else the first. () where there is one state."""
    kept: list[tuple[str, ContactResult]] = []
    for start, r in sorted(certified, key=lambda sr: sr[1] is not answer):
        if not any(same_state(r, k) for _, k in kept):
            kept.append((start, r))
    if len(kept) < 2:
        return ()
    states = [ReachedState(start, float(energy(chain, np.asarray(r.alpha, float))),
                           float(r.total_force), r is answer, np.array(r.alpha, float))
              for start, r in kept]
    return tuple(sorted(states, key=lambda s: s.energy))


# -- ramped -------------------------------------------------------------------------
def _judged_at_all(res: ContactResult, ctx: Context) -> bool:
    return res.judgement is not None


def ramped(res: ContactResult, ctx: Context) -> tuple[ContactResult, str]:
    """``res`` solved again along the loading path (:func:`lcpbench.model.ramp.follow_load`:
    the bend angles from zero, each step started from the last), where the judge refused
    it after the other escalations (the driver did not converge, stopped at a saddle it
    could not leave, or short of its force bound). The path's answer is continued as
    :func:`tightened` continues any answer. Where it is refused too, ``res``."""
    t0 = time.perf_counter()
    out, used, told = follow_load(res.scene, ctx.make_step, backend=ctx.backend,
                                  settings=ctx.settings, engine=ctx.engine, tol=ctx.tol,
                                  max_outer=ctx.max_outer, method=ctx.method)
    elapsed = res.time_s + time.perf_counter() - t0
    if out is not None:
        again = _restart_judged(res, ctx, out, used, elapsed)
        if again.converged:
            return again, f"the cold start was refused ({res.reason}); {told}"
        told = f"{told}; refused: {again.reason}"
    res.time_s = elapsed
    return res, told


# -- from_neighbour -------------------------------------------------------------
def _angles_planned(chain: Chain, backend: str, method: str, tol: float) -> bool:
    return _own_globalised(chain, backend, method, tol) and in_reach(chain)


def _neighbour_given(res: ContactResult, ctx: Context) -> bool:
    return ctx.neighbour is not None and res.judgement is not None


def from_neighbour(res: ContactResult, ctx: Context) -> tuple[ContactResult, str]:
    """``res`` solved again by SQP steps in the link angles
    (:func:`lcpbench.model.heavy_driver.run_heavy`, regular where a link is near the
    vertical, where height steps stall) from the loading path's answer of a neighbouring
    row of the batch (:attr:`Context.neighbour`: the same row but for its bend angles and
    h, close to it in both) and its wall reactions as the first multipliers; judged as
    every answer. A continuation from the neighbour's state: :func:`ramped` grows the bend
    angles from zero instead, so the two can reach different states where the scene has
    several; results/row-neighbours.md measures how often they do (never, where both
    certify, on its 4,300 rows). Where the SQP does not converge or its answer is
    refused, ``res``."""
    t0 = time.perf_counter()
    nb = ctx.neighbour
    assert nb is not None  # (_neighbour_given)
    lower = np.zeros_like(nb.forces) if nb.forces_lower is None else nb.forces_lower
    start = DriverStart(np.asarray(nb.alpha, float), None,
                        first_multipliers(nb.forces, lower, ctx.tol, ctx.chain.force_scale))
    out = run_heavy(ctx.chain, start, ctx.tol, ctx.max_outer, why=_NEIGHBOUR)
    elapsed = res.time_s + time.perf_counter() - t0
    if out is None:
        res.time_s = elapsed
        return res, "SQP steps in the link angles from a neighbouring row did not converge"
    again = _restart_judged(res, ctx, out, f"compiled SQP (SQP steps in the link angles: "
                            f"{_NEIGHBOUR})", elapsed)
    if again.converged:
        return again, f"the cold start was refused ({res.reason}); {_NEIGHBOUR}"
    res.time_s = again.time_s
    return res, f"{_NEIGHBOUR}: refused ({again.reason})"


_NEIGHBOUR = "started from the answer of a neighbouring row of the batch"


#: The escalations, in the order they run: name → (planned, applies, run).
ESCALATIONS: dict[str, Escalation] = {
    "in_increments": Escalation(_increments_planned, _increments_apply, in_increments),
    "tightened": Escalation(_own_globalised, _failed_only("force error bound"), tightened),
    "escaped": Escalation(_not_undamped, _failed_only("stability"), escaped),
    "from_neighbour": Escalation(_angles_planned, _neighbour_given, from_neighbour,
                                 needs_neighbour=True),
    "ramped": Escalation(_own_globalised, _judged_at_all, ramped),
}

__all__ = ["ESCALATIONS", "TIGHTEN_STEPS", "TIGHTER", "Context", "Escalation",
           "escalate", "escaped", "from_neighbour", "in_increments", "ramped",
           "reached_states", "same_state", "tightened"]
