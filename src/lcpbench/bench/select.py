"""Back-end selection: the fastest back-end that meets an accuracy on a kind of scene.

A *kind* of scene is what changes the numerics: N, ℓ, EI, w and one wall or
two. Its probe set is four contact scenes of that kind at fixed fractions of
ℓ (θ = 90°, 150°, 180° and two wall heights), so every scene of a kind shares
one set of probes. Each candidate (back-end, settings) runs every probe
through the sweep harness into the store: the probes are cached there, and a
second selection for the same kind and accuracy solves nothing. Without a
store (nor ``$LCPBENCH_STORE``) they are kept in memory: nothing is written.

What is probed (issue 16, "selection that means something"):

1. Candidates that cannot meet ``force_tol`` are ruled out before any solve
   (:func:`~.select_evidence.ruled_out`: documented failures, a profile
   looser than the accuracy on an inexact back-end, a failure already
   collected on this kind of scene at a looser driver tolerance).
2. The rest run the *screening* probe first (θ = 180°, h = ℓ/15: the probe
   that failed the most candidates on the default probes, 46 of 76). Those
   that fail it, or whose quickest timing there is more than :data:`SLOW_CUT`
   times the slowest timing of the fastest that passed it, are not probed
   further.
3. The survivors run the other three probes. Every converged run is timed
   ``repeat`` times (its time the median, its spread stored), unless its
   first solve took :data:`REPEAT_UNDER` seconds or more.

The choice: among the candidates that converged on every probe with a force
error (against the probe's reference) at most ``force_tol`` and, if given, a mean
time within ``time_budget``, the fastest geometric-mean time, unless others
are tied with it within the measured noise
(:func:`~.select_evidence.compare`); among tied candidates the simpler
profile (``default`` first), then an exact back-end, is preferred. The
confidence is the chosen one against the fastest other back-end: "A is
1.8× ± 0.2 faster than B" (± one standard error).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..accuracy import driver_tol_for
from ..errors import ProblemError
from ..problems.checks import check_number, describe
from ..problems.scenes import ActuatorScene
from ..solvers.selection import Selection
from .grid import Grid, scene_key
from .jobs import ReferenceJob, RunJob
from .metrics import error_of, geometric_mean, succeeded
from .select_evidence import (
    COMMITTED_RUNS,
    compare,
    kind_of,
    preference,
    read_runs_csv,
    ruled_out,
    student_t,
)
from .store import Store
from .sweep import DEFAULT_TIME_LIMIT, sweep

#: probe scenes of a kind: (θ in degrees, h / ℓ)
PROBES = ((90.0, 0.1), (150.0, 0.1), (180.0, 2.0 / 30.0), (150.0, 5.0 / 30.0))
STORE_ENV = "LCPBENCH_STORE"
#: index in PROBES of the screening probe, run first by every candidate
SCREEN = 2
#: a candidate this many times slower than the fastest on the screening probe is dropped.
#: Measured on the default probes (N = 140, force_tol 1e-6, one run of every candidate on
#: all four): those 5x slower or more there (Lemke, HiGHS, Siconos Lemke, quadprog, dense
#: ProxQP) were 2.5-24x slower than the built-in active set over all four probes.
SLOW_CUT = 5.0
#: timings of each converged probe run (the time is their median)
DEFAULT_REPEAT = 3
#: a probe run whose first solve takes this long (s) is timed once: its relative noise is
#: small, and it is far slower than the contact solvers that win (5-50 ms at N = 140)
REPEAT_UNDER = 0.5


@dataclass(frozen=True)
class ProbeJob(RunJob):
    """A probe run (a :class:`~.jobs.RunJob`, the same store row) repeated only when fast.

    The first solve's time decides: under ``repeat_under`` seconds a converged
    run is timed ``repeat`` times (its time the median), otherwise once.
    """

    repeat_under: float = field(default=REPEAT_UNDER, kw_only=True, compare=False)

    def repeats(self, first: dict) -> int:
        return self.repeat if first["wall_time"] < self.repeat_under else 1


def probe_scenes(scene_or_grid) -> list[ActuatorScene]:
    """The probe scenes of every kind of scene in ``scene_or_grid``."""
    if isinstance(scene_or_grid, Grid):
        scenes = scene_or_grid.scenes()
    elif isinstance(scene_or_grid, ActuatorScene):
        scenes = [scene_or_grid]
    elif isinstance(scene_or_grid, (list, tuple)) and scene_or_grid and all(
            isinstance(s, ActuatorScene) for s in scene_or_grid):
        scenes = list(scene_or_grid)
    else:
        raise ProblemError("scene_or_grid must be an ActuatorScene, a list of them or a "
                           f"Grid, got {describe(scene_or_grid)}")
    kinds = {}
    for s in scenes:
        if s.links == "auto":
            raise ProblemError("links='auto' must be resolved before selecting a back-end")
        kinds[(int(s.links), s.length, s.EI, s.weight, bool(s.channel))] = s
    probes = []
    for (links, length, ei, w, channel) in kinds:
        for theta, frac in PROBES:
            probes.append(ActuatorScene(theta=theta, height=round(frac * length, 12),
                                        links=links, length=length, EI=ei, weight=w,
                                        channel=channel))
    return probes


def _check(force_tol, time_budget) -> tuple[float, float | None]:
    force_tol = check_number("force_tol", force_tol, low=1e-12, high=0.1,
                             unit="(relative force error)")
    if time_budget is not None:
        time_budget = check_number("time_budget", time_budget, low=0.0, low_open=True, unit="s")
    return force_tol, time_budget


def select_backend(scene_or_grid, force_tol: float = 1e-6, time_budget: float | None = None, *,
                   store: Store | str | os.PathLike | None = None,
                   candidates: list[str] | None = None,
                   settings: tuple[str, ...] = ("default", "low", "mid", "high"),
                   probe: bool = True, workers: int = 1, progress=None,
                   repeat: int = DEFAULT_REPEAT,
                   evidence: list[str | os.PathLike] | None = None,
                   formulation: str | None = None) -> Selection:
    """The fastest back-end that meets the accuracy ``force_tol`` on this kind of scene.

    Parameters
    ----------
    scene_or_grid : ActuatorScene, list of scenes, or Grid.
    force_tol : largest relative error of the total reaction F = ΣR (eq. 30) allowed
        on every probe, against the probe's reference (not a driver tolerance).
    time_budget : largest geometric-mean time of one solve (s), or None.
    store : a Store or a path where the probes are cached (default:
        ``$LCPBENCH_STORE`` when set, else an in-memory store: nothing is
        written to disk and nothing is cached for the next call; ``lcpbench
        select`` caches in ``results/lcpbench.sqlite`` unless told otherwise).
    candidates : back-end names (default: every installed one; with a named
        ``formulation``, every installed one that takes it).
    settings : the profiles tried for each back-end.
    probe : run the probes that are not cached (False: use the cache only,
        and answer with what it holds).
    workers : processes for the probes.
    repeat : timings of each converged probe run (its time is their median).
    evidence : ``runs.csv`` files of earlier sweeps whose failures rule
        candidates out (default: the committed standard sweep, when the
        package runs from a checkout that has it; ``[]``: none). The
        store's own runs always count.
    formulation : the form every candidate's contact steps are handed in
        (:mod:`lcpbench.model.formulations`: a name, or "best": each back-end's at
        each profile); None: each back-end's own. The probes are stored as method
        ``globalised@form``, the evidence counts the runs of the same form, and the
        Selection carries the chosen pair's form (``solve(scene, solver=sel)`` runs it).

    Returns
    -------
    Selection
        ``backend`` is None when no candidate qualifies (the reason says why).
    """
    from ..solvers.registry import available_backends, get_backend, get_settings

    force_tol, time_budget = _check(force_tol, time_budget)
    if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
        raise ProblemError(f"repeat must be an integer >= 1, got {repeat!r}")
    probes = probe_scenes(scene_or_grid)
    names = available_backends() if candidates is None else list(candidates)
    for n in names:
        get_backend(n)
    for p in settings:
        get_settings(p)
    if formulation is not None and candidates is None:  # every installed one that takes it
        names = [n for n in names if _takes(n, settings, formulation)]
        if not names:
            raise ProblemError(f"formulation {formulation!r}: no installed back-end takes it")
    forms = _forms(names, settings, formulation)
    if evidence is None:
        evidence = [COMMITTED_RUNS] if COMMITTED_RUNS.exists() else []
    dtol = driver_tol_for(force_tol)
    limit = DEFAULT_TIME_LIMIT if time_budget is None else min(DEFAULT_TIME_LIMIT,
                                                                max(1.0, 20 * time_budget))
    own = not isinstance(store, Store)
    if own:
        path = Path(store) if store is not None else (
            Path(os.environ[STORE_ENV]) if os.environ.get(STORE_ENV) else None)
        if not probe and (path is None or not path.exists()):
            where = "no store given" if path is None else f"no store at {path}"
            return _fallback(force_tol, dtol, f"no probes cached ({where}); run "
                                              "`lcpbench select` to measure them")
        store = Store.in_memory() if path is None else Store(path, create=probe)
    try:
        return _select(store, probes, [(n, p) for n in names for p in settings], force_tol,
                       dtol, time_budget, probe=probe, workers=workers, limit=limit,
                       progress=progress, repeat=repeat, evidence=evidence, forms=forms)
    finally:
        if own:
            store.close()


def _forms(names, settings, formulation) -> dict[tuple[str, str], str]:
    """(back-end, profile) -> the form its probes run in, for the pairs not in their own
    form (:func:`~lcpbench.model.formulations.resolve_formulation`: a form a back-end does
    not take is one ProblemError)."""
    if formulation is None:
        return {}
    from ..model.formulations import resolve_formulation
    from ..solvers.registry import get_backend

    pairs = {(n, p): resolve_formulation(get_backend(n), formulation, p)
             for n in names for p in settings}
    return {c: str(f) for c, f in pairs.items() if f is not None}


def _takes(name: str, settings, formulation) -> bool:
    """Whether back-end ``name`` takes ``formulation`` at every profile of ``settings``."""
    try:
        _forms([name], settings, formulation)
    except ProblemError:
        return False
    return True


def _method(cand, forms) -> str:
    """The stored method of a candidate's probes (as :attr:`.jobs.RunJob.label`)."""
    return "globalised" if cand not in forms else f"globalised@{forms[cand]}"


def _fallback(force_tol, dtol, why, evidence=()) -> Selection:
    return Selection(None, None, force_tol, dtol, math.nan, math.nan, why, list(evidence))


def _select(store: Store, probes, pairs, force_tol, dtol, time_budget, *, probe, workers,
            limit, progress, repeat, evidence, forms) -> Selection:
    keys = [scene_key(s) for s in probes]
    screen = [k for i, k in enumerate(keys) if i % len(PROBES) == SCREEN]
    rest = [k for k in keys if k not in screen]
    kinds = {kind_of(s) for s in probes}
    collected = [r for r in store.runs(arrays=False, where="WHERE converged = 0")
                 if kind_of(r) in kinds]
    for f in evidence:
        collected += read_runs_csv(f)
    out = ruled_out(pairs, kinds, force_tol, dtol, collected,
                    methods={c: _method(c, forms) for c in pairs})
    report = [{"backend": b, "settings": s, "ok": False, "stage": "ruled out", "why": why}
              for (b, s), why in out.items()]
    live = [c for c in pairs if c not in out]

    def run(scene_keys, cands):
        jobs = [ReferenceJob(k) for k in keys] + [
            ProbeJob(k, b, s, dtol, repeat=repeat, formulation=forms.get((b, s)))
            for k in scene_keys for b, s in cands]
        if probe:
            sweep(store, jobs, workers=workers, time_limit=limit, progress=progress)
        refs = {k: r for k, r in store.refs(arrays=False).items() if k in keys}
        marks = ", ".join("?" * len(keys))
        methods = sorted({_method(c, forms) for c in pairs})
        rows = {(r["scene"], r["backend"], r["settings"]): r
                for r in store.runs(arrays=False, where=f"WHERE tol = ? AND method IN "
                                    f"({', '.join('?' * len(methods))}) AND scene IN ({marks})",
                                    params=(dtol, *methods, *keys))
                if r["method"] == _method((r["backend"], r["settings"]), forms)}
        return refs, rows

    refs, rows = run(screen, live)
    missing_refs = [k for k in keys if k not in refs or not refs[k]["converged"]]
    if missing_refs:
        if not probe and not refs:
            return _fallback(force_tol, dtol, "no probes cached for this kind of scene; run "
                                        "`lcpbench select` to measure them", report)
        return _fallback(force_tol, dtol, f"{len(missing_refs)} probe reference(s) missing or "
                                    "not converged; probe again", report)
    first = {c: _assess(c, screen, rows, refs, force_tol) for c in live}
    passed = {c: e for c, e in first.items() if e["ok"]}
    survivors = list(passed)
    cut: list[tuple[str, str]] = []
    if passed:
        # robust to a burst of load: the candidate's quickest repeat against the
        # fastest one's slowest
        best = min(passed, key=lambda c: passed[c]["time_s"])
        ceiling = _screen_time(best, screen, rows, "wall_time_max")
        for c, e in passed.items():
            slow = _screen_time(c, screen, rows, "wall_time_min") / ceiling
            if slow > SLOW_CUT:
                survivors.remove(c)
                cut.append(c)
                e.update(ok=False, why=f"{slow:.0f}x slower than {best[0]} ({best[1]}) on the "
                                       f"first probe, quickest timing against its slowest "
                                       f"(cut at {SLOW_CUT:g}x)")
    for c, e in first.items():
        if c not in survivors:
            report.append({**e, "stage": "first probe"})
    if survivors:
        refs, rows = run(rest, survivors)
    full = {c: _assess(c, keys, rows, refs, force_tol) for c in survivors}
    for e in full.values():
        if e["ok"] and time_budget is not None and e["time_s"] > time_budget:
            e.update(ok=False, why=f"time {e['time_s']:.3g} s > budget {time_budget:g} s")
        report.append({**e, "stage": "all probes"})
    cut.sort(key=lambda c: passed[c]["time_s"])
    sel = _choose(full, rows, keys, probes, force_tol, dtol, time_budget, out, report,
                  cut, screen)
    if sel.backend is not None:
        sel.formulation = forms.get((sel.backend, sel.settings))
    return sel


def _screen_time(cand, scene_keys, rows, column) -> float:
    """Geometric mean over ``scene_keys`` of a candidate's ``column`` (else its wall time)."""
    vals = []
    for k in scene_keys:
        r = rows[(k, *cand)]
        vals.append(max(r.get(column) or r["wall_time"], 1e-9))
    return geometric_mean(vals)


def _assess(cand, scene_keys, rows, refs, force_tol) -> dict:
    """A candidate on the probes ``scene_keys``: converged, worst error, time, ok, why."""
    backend, settings = cand
    mine = [rows.get((k, backend, settings)) for k in scene_keys]
    base = {"backend": backend, "settings": settings, "probes": len(mine)}
    if any(r is None for r in mine) or any(k not in refs for k in scene_keys):
        return {**base, "cached": sum(r is not None for r in mine), "ok": False,
                "why": "not all probes cached"}
    errors = [error_of(r["total_force"], refs[r["scene"]]["total_force"],
                       r["EI"] / r["length"] ** 2) for r in mine]
    conv = sum(bool(r["converged"]) for r in mine)
    worst = max(errors)
    ok = all(succeeded(r["converged"], e, force_tol) for r, e in zip(mine, errors))
    why = ("" if ok else f"converged on {conv}/{len(mine)} probes" if conv < len(mine)
           else f"force error {worst:.1e} > {force_tol:.0e}")
    return {**base, "converged": conv, "error": worst,
            "time_s": geometric_mean([max(r["wall_time"], 1e-9) for r in mine]),
            "repeats": min(int(r.get("repeats") or 1) for r in mine), "ok": ok, "why": why}


def _choose(full, rows, keys, probes, force_tol, dtol, time_budget, out, report, cut,
            screen) -> Selection:
    good = sorted((c for c, e in full.items() if e["ok"]), key=lambda c: full[c]["time_s"])
    if not good:
        if not full or all(e.get("why") == "not all probes cached" for e in full.values()):
            why = ("no probes cached for this kind of scene; run `lcpbench select` to "
                   "measure them")
            if out and not full and not any(e.get("stage") == "first probe" for e in report):
                why = f"every candidate was ruled out before probing ({len(out)})"
            return _fallback(force_tol, dtol, why, report)
        return Selection(None, None, force_tol, dtol, math.nan, math.nan,
                         f"no back-end met a force error of {force_tol:.0e} on all {len(probes)} "
                         "probes" + (f" within the time budget of {time_budget:g} s" if time_budget
                                     else ""),
                         report)

    def times(c, on=keys):
        return [rows[(k, *c)] for k in on]

    fastest = good[0]
    ties = [fastest] + [c for c in good[1:] if compare(times(fastest), times(c))["tied"]]
    pick = min(ties, key=lambda c: preference(c[0], c[1], full[c]["time_s"]))
    best = full[pick]
    reason = (f"fastest of {len(good)} qualified (back-end, settings) pairs, or tied with it "
              f"within the noise: {1e3 * best['time_s']:.3g} ms per solve (geometric mean over {len(probes)} "
              f"probes, each the median of {best['repeats']} timing(s)), worst error "
              f"{best['error']:.1e} <= {force_tol:.0e}")
    # against the fastest other back-end: over all probes, or where it was cut, the first
    runner = next((c for c in good if c[0] != pick[0]), None)
    on = keys
    if runner is None:
        runner, on = next((c for c in cut if c[0] != pick[0]), None), screen
    confidence = None
    if runner is not None:
        cmp = compare(times(pick, on), times(runner, on))
        confidence = {"versus": {"backend": runner[0], "settings": runner[1]},
                      "probes": len(on), **cmp}
        half = student_t(len(on) - 1) * cmp["log_se"]  # the 95 % interval of the ratio
        lo, hi = math.exp(cmp["log_ratio"] - half), math.exp(cmp["log_ratio"] + half)
        reason += (f"; {cmp['ratio']:.2g}x faster than {runner[0]} ({runner[1]})"
                   + ("" if on is keys else " on the first probe, where it was cut")
                   + f" (95 % interval {lo:.2g}x to {hi:.2g}x over {len(on)} probe(s)"
                   + (": not significant, so a tie" if cmp["tied"] else "") + ")")
    others = [c for c in ties if c != pick]
    if others:
        reason += ("; tied within the noise with " + ", ".join(f"{b} ({s})" for b, s in others)
                   + ": the simpler profile, then an exact back-end, preferred")
    dropped = sum(e.get("stage") == "first probe" for e in report)
    reason += (f"; {len(out)} candidate(s) ruled out before probing, {dropped} dropped after "
               "the first probe")
    tie_rows = [{"backend": b, "settings": s, "time_s": full[(b, s)]["time_s"]} for b, s in ties]
    return Selection(pick[0], pick[1], force_tol, dtol, best["time_s"], best["error"], reason,
                     report, confidence, tie_rows)
