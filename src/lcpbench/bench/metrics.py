"""Metrics of the benchmark, computed from stored runs only.

Error of a run
    |F − F_ref| / max(|F_ref|, EI/ℓ²): the total-force error against the
    scene's reference, relative where the force exceeds the chain's own
    force unit EI/ℓ² and in that unit below it (so no-contact scenes count).
Success
    the run converged (certificate accepted) and its error is at most
    :func:`success_tol` of its driver tolerance: min(1e-3, 100·tol). 1e-3 is
    the paper's own agreement criterion (0.1 % of total force, Fig. 26);
    100·tol is what an exact contact solver reaches at driver tolerance
    tol on the paper's scenes (measured: 7e-5 at 1e-3, 4e-8 at 1e-6,
    2e-11 at 1e-9 rad for the reference scene).
Score (Mittelmann's rule: every scene counts, a failure at its charge)
    per (back-end, settings, driver), over *all* its scenes: the shifted
    geometric mean exp(mean(log(v + s))) − s of its wall time, shift
    :data:`TIME_SHIFT_MS` = 1 ms, each unsuccessful run charged at the time
    limit (60 s), and of its outer iterations, shift
    :data:`ITERATION_SHIFT` = 1, each unsuccessful run charged at the
    driver's outer-iteration limit :data:`OUTER_LIMIT` = 200 (a run that
    used more, the baselines' root finders, at its own count: charging a
    failure never makes it cheaper than it was). Mittelmann (and the OET
    benchmark after him) charge a timeout at the time limit with shift 10
    s; here a solve takes 0.05 ms to 2.5 s, and the repeats of one sub-ms
    solve differ by ~0.1 ms (a factor 2), so the shift is 1 ms: a 0.1 ms
    jitter moves one scene's log by < 10 %, while solves of the contact
    scenes (1–30 ms) still count at their ratio.
Error score
    the same mean of each run's force error in units of its success
    tolerance, shift 10 (qpbenchmark's), unsuccessful runs at an error of
    1 (100 %) or their own, whichever is larger.
Continuation against cold
    per (back-end, settings, tol) stored both cold (method ``globalised``)
    and by continuation (``globalised+secant`` and the like): over the
    scenes where both converged, the total outer iterations of each, their
    ratio, and the largest |F_cold − F_cont| / max(|F_cold|, EI/ℓ²).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError
from ..model.judge import force_tol
from .jobs import DEFAULT_TIME_LIMIT

#: the shift of the error score (errors in units of the success tolerance), qpbenchmark's 10
SHIFT = 10.0
#: the shift of the time score, in ms (see the module docstring for why 1 ms)
TIME_SHIFT_MS = 1.0
#: the shift of the outer-iteration score: counts are exact, so only 0 needs it
ITERATION_SHIFT = 1.0
#: the charge of an unsuccessful run's outer iterations: the driver's limit (max_outer of
#: lcpbench.solve, the sweep's), or its own count if it used more
OUTER_LIMIT = 200
#: the methods of cold runs Table II shows: the globalised driver and the baselines
COLD_METHODS = ("globalised", "hybr", "lm")


def shifted_geometric_mean(values, shift: float = SHIFT) -> float:
    """exp(mean(log(v + shift))) − shift; NaN for no values (shift 0: the plain geometric mean).

    Held within [min v, max v], where every mean lies: the subtraction of the shift
    cancels (values near 0 gave −4e-16)."""
    v = np.asarray(list(values), float)
    if v.size == 0:
        return float("nan")
    if np.any(v < 0):
        raise ValueError("shifted geometric mean of negative values")
    with np.errstate(divide="ignore"):  # shift 0 and a zero value: the mean is 0
        m = float(np.exp(np.mean(np.log(v + shift))) - shift)
    return min(max(m, float(v.min())), float(v.max()))


def charged_sgm(values, solved, charge: float, shift: float) -> float:
    """The shifted geometric mean over every run, each unsuccessful one charged.

    ``values[i]`` is run i's measure (time, iterations) and ``solved[i]``
    whether it was a success; an unsuccessful run counts at
    max(``charge``, its own value), so a failure never counts as cheaper
    than it was (its value may be NaN: it then counts at ``charge``). NaN
    for no runs. Raises ProblemError for mismatched lengths, a NaN or
    negative value of a success, or a charge or shift that is not finite
    and >= 0.
    """
    v = np.asarray(list(values), float)
    ok = np.asarray(list(solved), bool)
    if v.ndim != 1 or v.shape != ok.shape:
        raise ProblemError(f"charged_sgm needs one 'solved' flag per value, got {v.size} "
                           f"values and {ok.size} flags")
    if not (math.isfinite(charge) and charge >= 0 and math.isfinite(shift) and shift >= 0):
        raise ProblemError(f"charged_sgm needs a finite charge and shift >= 0, got "
                           f"charge={charge!r}, shift={shift!r}")
    if np.any(~np.isfinite(v[ok])) or np.any(v[ok] < 0):
        raise ProblemError("charged_sgm: a successful run needs a finite value >= 0")
    own = np.where(np.isfinite(v) & (v >= 0), v, 0.0)
    return shifted_geometric_mean(np.where(ok, v, np.maximum(charge, own)), shift)


def geometric_mean(values) -> float:
    """The plain geometric mean (of positive values), NaN for none."""
    return shifted_geometric_mean(values, 0.0)


def error_of(total_force: float, reference: float, force_scale: float) -> float:
    """The force error of a run: |F − F_ref| / max(|F_ref|, EI/ℓ²).

    Relative where the reference force exceeds the chain's own force unit
    EI/ℓ², in that unit below it (so no-contact scenes, F_ref = 0, are judged
    too).
    """
    if not np.isfinite(total_force):
        return float("inf")
    return abs(total_force - reference) / max(abs(reference), force_scale)


def success_tol(driver_tol: float) -> float:
    """The force error a run at driver tolerance ``driver_tol`` (rad) may have and count as a
    success: min(1e-3, 100 · driver_tol), a relative error of the total reaction F. The
    same τ that lcpbench's result judge certifies (:func:`lcpbench.model.judge.force_tol`)."""
    return force_tol(driver_tol)


def succeeded(converged: bool, error: float, force_tol: float) -> bool:
    """The success rule: the run converged and its force error is at most ``force_tol``."""
    return bool(converged) and error <= force_tol


@dataclass
class Evaluated:
    """One stored run judged against its scene's reference."""

    row: dict
    error: float  # inf when there is no reference
    success: bool
    reference_force: float = math.nan  # F_ref of the scene (NaN: none)

    @property
    def backend(self) -> str:
        return self.row["backend"]

    @property
    def settings(self) -> str:
        return self.row["settings"]


def evaluate(runs: list[dict], refs: dict[str, dict]) -> list[Evaluated]:
    """Judge every run against the reference of its scene."""
    out = []
    for r in runs:
        ref = refs.get(r["scene"])
        if ref is None or not ref["converged"]:
            out.append(Evaluated(r, float("inf"), False))
            continue
        err = error_of(r["total_force"], ref["total_force"], r["EI"] / r["length"] ** 2)
        ok = succeeded(r["converged"], err, success_tol(r["tol"]))
        out.append(Evaluated(r, err, ok, float(ref["total_force"])))
    return out


def silent_inner(evaluated: list[Evaluated]) -> set[str]:
    """The back-ends that report no inner iteration count (HiGHS, DAQP through qpsolvers).

    A back-end is silent when it stored 0 inner iterations on every one of
    its runs although at least one of them is on a scene with contact
    (F_ref > 0, where every counting back-end does some work); a back-end
    run on no-contact scenes only is not judged silent. Their zeros are not
    costs: the iteration profiles and the inner column leave them out.
    """
    counted: dict[str, bool] = {}
    contact: dict[str, bool] = {}
    for e in evaluated:
        b = e.backend
        counted[b] = counted.get(b, False) or int(e.row["inner_iterations"] or 0) > 0
        contact[b] = contact.get(b, False) or (math.isfinite(e.reference_force)
                                               and e.reference_force > 0)
    return {b for b in counted if contact[b] and not counted[b]}


def summarise(evaluated: list[Evaluated], *, time_limit: float = DEFAULT_TIME_LIMIT
              ) -> list[dict]:
    """Per (back-end, settings, method): success, scores, errors, iterations, speed-ups.

    ``time_sgm_ms`` and ``outer_sgm`` are the scores over every run (module
    docstring: failures charged at ``time_limit`` and at :data:`OUTER_LIMIT`),
    ``time_sgm_rel`` and ``outer_sgm_rel`` the same over the best row's;
    ``time_median_successes_ms`` and ``inner_mean`` are over the successful
    runs only (``inner_mean`` NaN and ``inner_reported`` False for a back-end
    that reports no inner count, :func:`silent_inner`). Rows are sorted by
    back-end then settings (default, low, mid, high), the baselines last.
    """
    if not (math.isfinite(time_limit) and time_limit > 0):
        raise ProblemError(f"time_limit must be a finite number of seconds > 0, got "
                           f"{time_limit!r}")
    baseline_time = {b: {e.row["scene"]: e.row["wall_time"] for e in evaluated
                         if e.backend == b and e.success} for b in ("baseline", "baseline-fd")}
    silent = silent_inner(evaluated)
    groups: dict[tuple, list[Evaluated]] = {}
    for e in evaluated:
        groups.setdefault((e.backend, e.settings, e.row["method"]), []).append(e)
    rows = []
    for (backend, settings, method), es in groups.items():
        ok = [e for e in es if e.success]
        solved = [e.success for e in es]
        tol = es[0].row["tol"]
        err_units = [max(e.error, 0.0 if e.success else 1.0) / success_tol(e.row["tol"])
                     for e in es]
        errors = [e.error for e in es if math.isfinite(e.error)]
        speedups = {b: [times[e.row["scene"]] / e.row["wall_time"] for e in ok
                        if e.row["scene"] in times and e.row["wall_time"] > 0]
                    for b, times in baseline_time.items()}
        rows.append({
            "backend": backend,
            "settings": settings,
            "method": method,
            "tol": tol,
            "runs": len(es),
            "success": len(ok) / len(es),
            "converged": sum(bool(e.row["converged"]) for e in es) / len(es),
            "converged_but_off": sum(bool(e.row["converged"]) and not e.success for e in es),
            "time_sgm_ms": charged_sgm([1e3 * _number(e.row["wall_time"]) for e in es],
                                       solved, 1e3 * time_limit, TIME_SHIFT_MS),
            "outer_sgm": charged_sgm([_number(e.row["outer_iterations"]) for e in es],
                                     solved, OUTER_LIMIT, ITERATION_SHIFT),
            "time_median_successes_ms": float(np.median([1e3 * e.row["wall_time"]
                                                         for e in ok]))
            if ok else float("nan"),
            "error_sgm": shifted_geometric_mean(err_units),
            "error_median": float(np.median(errors)) if errors else float("nan"),
            "error_max": float(max((e.error for e in ok), default=float("nan"))),
            "outer_mean": float(np.mean([e.row["outer_iterations"] for e in ok]))
            if ok else float("nan"),
            "inner_reported": backend not in silent,
            "inner_mean": float(np.mean([e.row["inner_iterations"] for e in ok]))
            if ok and backend not in silent else float("nan"),
            "speedup_vs_baseline": geometric_mean(speedups["baseline"]),
            "speedup_vs_baseline_fd": geometric_mean(speedups["baseline-fd"]),
        })
    order = {"default": 0, "low": 1, "mid": 2, "high": 3}
    rows.sort(key=lambda r: (r["backend"].startswith("baseline"), r["backend"],
                             order.get(r["settings"], 9), r["method"]))
    best_t = min((r["time_sgm_ms"] for r in rows), default=float("nan"))
    best_o = min((r["outer_sgm"] for r in rows), default=float("nan"))
    best_e = min((r["error_sgm"] for r in rows), default=float("nan"))
    for r in rows:
        r["time_sgm_rel"] = r["time_sgm_ms"] / best_t if best_t > 0 else float("nan")
        r["outer_sgm_rel"] = r["outer_sgm"] / best_o if best_o > 0 else float("nan")
        r["error_sgm_rel"] = (r["error_sgm"] + SHIFT) / (best_e + SHIFT)
    return rows


def _number(v) -> float:
    """A stored measure as a float (None, a missing measurement, as NaN)."""
    return math.nan if v is None else float(v)


def time_table(evaluated: list[Evaluated], height: float, settings: str = "default"
               ) -> tuple[list[float], dict[str, dict[float, float | None]], float]:
    """Table II of the paper: wall time per bend angle at one height, over the fastest.

    Returns (bend angles, {back-end: {θ: time / fastest or None if not a
    success}}, fastest time in ms). Back-ends run at ``settings``; the
    baselines are included as they are.
    """
    cells: dict[str, dict[float, float | None]] = {}
    best = math.inf
    thetas: set[float] = set()
    for e in evaluated:
        r = e.row
        if not math.isclose(r["height"], height) or (
                e.settings not in (settings, "-")) or r["method"] not in COLD_METHODS:
            continue  # the globalised driver, cold (and the baselines) only
        thetas.add(r["theta"])
        t = r["wall_time"] if e.success else None
        cells.setdefault(e.backend, {})[r["theta"]] = t
        if t is not None:
            best = min(best, t)
    for row in cells.values():
        for th, t in row.items():
            row[th] = None if t is None else t / best
    return sorted(thetas), cells, 1e3 * best


def continuation_pairs(runs: list[dict]) -> list[dict]:
    """Continuation runs against the cold runs of the same back-end, settings and tol.

    One dict per (back-end, settings, tol, continuation method) that has cold
    ``globalised`` runs too: over the scenes both have (``scenes``) and where
    both converged (``compared``), the total outer iterations cold and by
    continuation, ``ratio`` = cold / continuation (> 1: continuation took
    fewer), the total wall times, and the largest force difference
    |F_cold − F_cont| / max(|F_cold|, EI/ℓ²).
    """
    by: dict[tuple, dict[str, dict]] = {}
    for r in runs:
        by.setdefault((r["backend"], r["settings"], r["tol"], r["method"]), {})[r["scene"]] = r
    out = []
    for (backend, settings, tol, method), cont in sorted(by.items()):
        if not method.startswith("globalised+"):
            continue
        cold = by.get((backend, settings, tol, "globalised"))
        if not cold:
            continue
        both = [k for k in cont if k in cold]
        ok = [k for k in both if cold[k]["converged"] and cont[k]["converged"]]
        outer_cold = sum(int(cold[k]["outer_iterations"]) for k in ok)
        outer_cont = sum(int(cont[k]["outer_iterations"]) for k in ok)
        diff = max((error_of(cont[k]["total_force"], cold[k]["total_force"],
                             cold[k]["EI"] / cold[k]["length"] ** 2) for k in ok),
                   default=float("nan"))
        out.append({
            "backend": backend, "settings": settings, "tol": tol, "method": method,
            "scenes": len(both), "compared": len(ok),
            "outer_cold": outer_cold, "outer_continuation": outer_cont,
            "ratio": outer_cold / outer_cont if outer_cont > 0 else float("nan"),
            "time_cold_s": float(sum(cold[k]["wall_time"] for k in ok)),
            "time_continuation_s": float(sum(cont[k]["wall_time"] for k in ok)),
            "force_difference_max": diff,
        })
    return out
