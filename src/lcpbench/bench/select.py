"""Back-end selection: the fastest back-end that meets an accuracy on a kind of scene.

A *kind* of scene is what changes the numerics: N, ℓ, EI, w and one wall or
two. Its probe set is four contact scenes of that kind at fixed fractions of
ℓ (θ = 90°, 150°, 180° and two wall heights), so every scene of a kind shares
one set of probes. Each candidate (back-end, settings) runs every probe
through the sweep harness into the store: the probes are cached there, and a
second selection for the same kind and accuracy solves nothing.

The choice: among the candidates that converged on every probe with a force
error (against the probe's reference) at most ``force_tol`` and, if given, a mean
time within ``time_budget``, the one with the smallest geometric-mean time.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from ..errors import ProblemError
from ..problems.checks import check_number
from ..problems.scenes import ActuatorScene
from ..solvers.selection import Selection
from .grid import Grid, scene_key
from .jobs import Job, RunJob
from .metrics import error_of, geometric_mean, succeeded
from .store import DEFAULT_STORE, Store
from .sweep import DEFAULT_TIME_LIMIT, plan_sweep, sweep

#: probe scenes of a kind: (θ in degrees, h / ℓ)
PROBES = ((90.0, 0.1), (150.0, 0.1), (180.0, 2.0 / 30.0), (150.0, 5.0 / 30.0))
STORE_ENV = "LCPBENCH_STORE"


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
                           f"Grid, got {type(scene_or_grid).__name__}")
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


def driver_tol_for(force_tol: float) -> float:
    """Driver tolerance (rad) of the probes for a force accuracy ``force_tol``.

    An exact contact solver reaches a force error of about x/10 at driver
    tolerance x rad on the probe scenes (measured: 7e-5 at 1e-3 rad, 4e-8 at
    1e-6, 2e-11 at 1e-9), so the probes run at min(force_tol, 1e-3) rad.
    """
    return min(force_tol, 1e-3)


def select_backend(scene_or_grid, force_tol: float = 1e-6, time_budget: float | None = None, *,
                   store: Store | str | os.PathLike | None = None,
                   candidates: list[str] | None = None,
                   settings: tuple[str, ...] = ("default", "low", "mid", "high"),
                   probe: bool = True, workers: int = 1,
                   progress=None) -> Selection:
    """The fastest back-end that meets the accuracy ``force_tol`` on this kind of scene.

    Parameters
    ----------
    scene_or_grid : ActuatorScene, list of scenes, or Grid.
    force_tol : largest relative error of the total reaction F = ΣR (eq. 30) allowed
        on every probe, against the probe's reference (not a driver tolerance).
    time_budget : largest geometric-mean time of one solve (s), or None.
    store : a Store or a path (default: ``$LCPBENCH_STORE`` or
        ``results/lcpbench.sqlite``); the probes are cached there.
    candidates : back-end names (default: every installed one).
    settings : the profiles tried for each back-end.
    probe : run the probes that are not cached (False: use the cache only,
        and answer with what it holds).
    workers : processes for the probes.

    Returns
    -------
    Selection
        ``backend`` is None when no candidate qualifies (the reason says why).
    """
    from ..solvers.registry import available_backends, get_backend, get_settings

    force_tol, time_budget = _check(force_tol, time_budget)
    probes = probe_scenes(scene_or_grid)
    names = available_backends() if candidates is None else list(candidates)
    for n in names:
        get_backend(n)
    for p in settings:
        get_settings(p)
    dtol = driver_tol_for(force_tol)
    jobs = plan_sweep(probes, names, list(settings), tol=dtol, baselines=())
    limit = DEFAULT_TIME_LIMIT if time_budget is None else min(DEFAULT_TIME_LIMIT,
                                                                max(1.0, 20 * time_budget))
    own = not isinstance(store, Store)
    if own:
        path = Path(os.environ.get(STORE_ENV) or DEFAULT_STORE) if store is None else Path(store)
        if not probe and not path.exists():
            return _fallback(force_tol, dtol, "no probes cached (no store at "
                                        f"{path}); run `lcpbench select` to measure them")
        store = Store(path, create=probe)
    try:
        if probe:
            sweep(store, jobs, workers=workers, time_limit=limit, progress=progress)
        return _choose(store, jobs, probes, force_tol, dtol, time_budget)
    finally:
        if own:
            store.close()


def _fallback(force_tol, dtol, why) -> Selection:
    return Selection(None, None, force_tol, dtol, math.nan, math.nan, why)


def _choose(store: Store, jobs: list[Job], probes, force_tol, dtol, time_budget) -> Selection:
    keys = {scene_key(s) for s in probes}
    refs = {k: r for k, r in store.refs(arrays=False).items() if k in keys}
    marks = ", ".join("?" * len(keys))
    rows = {(r["scene"], r["backend"], r["settings"], r["tol"], r["method"]): r
            for r in store.runs(arrays=False, where=f"WHERE tol = ? AND scene IN ({marks})",
                                params=(dtol, *sorted(keys)))}
    missing_refs = [k for k in keys if k not in refs or not refs[k]["converged"]]
    if missing_refs:
        return _fallback(force_tol, dtol, f"{len(missing_refs)} probe reference(s) missing or "
                                    "not converged; probe again")
    evidence = []
    runs = [j for j in jobs if isinstance(j, RunJob)]
    for (backend, settings) in dict.fromkeys((j.backend, j.settings) for j in runs):
        mine = [rows.get(j.key) for j in runs if (j.backend, j.settings) == (backend, settings)]
        if any(r is None for r in mine):
            evidence.append({"backend": backend, "settings": settings, "probes": len(mine),
                             "cached": sum(r is not None for r in mine), "ok": False,
                             "why": "not all probes cached"})
            continue
        errors = [error_of(r["total_force"], refs[r["scene"]]["total_force"],
                           r["EI"] / r["length"] ** 2) for r in mine]
        conv = sum(bool(r["converged"]) for r in mine)
        t = geometric_mean([max(r["wall_time"], 1e-9) for r in mine])
        worst = max(errors)
        ok = all(succeeded(r["converged"], e, force_tol) for r, e in zip(mine, errors))
        why = ("" if ok else f"converged on {conv}/{len(mine)} probes" if conv < len(mine)
               else f"force error {worst:.1e} > {force_tol:.0e}")
        if ok and time_budget is not None and t > time_budget:
            ok, why = False, f"time {t:.3g} s > budget {time_budget:g} s"
        evidence.append({"backend": backend, "settings": settings, "probes": len(mine),
                         "converged": conv, "error": worst, "time_s": t, "ok": ok,
                         "why": why})
    good = sorted((e for e in evidence if e["ok"]), key=lambda e: e["time_s"])
    if not good:
        if all(e.get("why") == "not all probes cached" for e in evidence):
            return _fallback(force_tol, dtol, "no probes cached for this kind of scene; run "
                                        "`lcpbench select` to measure them")
        return Selection(None, None, force_tol, dtol, math.nan, math.nan,
                         f"no back-end met a force error of {force_tol:.0e} on all {len(probes)} "
                         "probes" + (f" within the time budget of {time_budget:g} s" if time_budget
                                     else ""),
                         evidence)
    best = good[0]
    runner_up = next((e for e in good if e["backend"] != best["backend"]), None)
    reason = (f"fastest of {len(good)} (back-end, settings) pairs that met a force error of "
              f"{force_tol:.0e} on all {len(probes)} probes: {1e3 * best['time_s']:.3g} ms per "
              f"solve, worst error {best['error']:.1e}")
    if runner_up is not None:
        reason += (f"; next {runner_up['backend']} ({runner_up['settings']}) "
                   f"{runner_up['time_s'] / best['time_s']:.2f}x slower")
    return Selection(best["backend"], best["settings"], force_tol, dtol, best["time_s"],
                     best["error"], reason, evidence)
