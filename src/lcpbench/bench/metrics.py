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
Shifted geometric mean
    exp(mean(log(v + s))) − s, as in qpbenchmark (shift s = 10): of times
    in milliseconds, and of errors in units of the success tolerance.
    Unsuccessful runs count at the time limit and at an error of 1
    (100 %) or their own, whichever is larger, as qpbenchmark penalises
    failures.
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

from ..model.judge import force_tol
from .jobs import DEFAULT_TIME_LIMIT

SHIFT = 10.0
#: the methods of cold runs Table II shows: the globalised driver and the baselines
COLD_METHODS = ("globalised", "hybr", "lm")


def shifted_geometric_mean(values, shift: float = SHIFT) -> float:
    """exp(mean(log(v + shift))) − shift; NaN for no values (shift 0: the plain geometric mean)."""
    v = np.asarray(list(values), float)
    if v.size == 0:
        return float("nan")
    if np.any(v < 0):
        raise ValueError("shifted geometric mean of negative values")
    return float(np.exp(np.mean(np.log(v + shift))) - shift)


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
        out.append(Evaluated(r, err, ok))
    return out


def summarise(evaluated: list[Evaluated], *, time_limit: float = DEFAULT_TIME_LIMIT
              ) -> list[dict]:
    """Per (back-end, settings, method): success, times, errors, iterations, speed-ups.

    Rows are sorted by back-end then settings (default, low, mid, high), the
    baselines last.
    """
    baseline_time = {b: {e.row["scene"]: e.row["wall_time"] for e in evaluated
                         if e.backend == b and e.success} for b in ("baseline", "baseline-fd")}
    groups: dict[tuple, list[Evaluated]] = {}
    for e in evaluated:
        groups.setdefault((e.backend, e.settings, e.row["method"]), []).append(e)
    rows = []
    for (backend, settings, method), es in groups.items():
        ok = [e for e in es if e.success]
        t_ms = [1e3 * (e.row["wall_time"] if e.success else time_limit) for e in es]
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
            "time_sgm_ms": shifted_geometric_mean(t_ms),
            "time_median_ms": float(np.median([1e3 * e.row["wall_time"] for e in ok]))
            if ok else float("nan"),
            "error_sgm": shifted_geometric_mean(err_units),
            "error_median": float(np.median(errors)) if errors else float("nan"),
            "error_max": float(max((e.error for e in ok), default=float("nan"))),
            "outer_mean": float(np.mean([e.row["outer_iterations"] for e in ok]))
            if ok else float("nan"),
            "inner_mean": float(np.mean([e.row["inner_iterations"] for e in ok]))
            if ok else float("nan"),
            "speedup_vs_baseline": geometric_mean(speedups["baseline"]),
            "speedup_vs_baseline_fd": geometric_mean(speedups["baseline-fd"]),
        })
    order = {"default": 0, "low": 1, "mid": 2, "high": 3}
    rows.sort(key=lambda r: (r["backend"].startswith("baseline"), r["backend"],
                             order.get(r["settings"], 9), r["method"]))
    best_t = min((r["time_sgm_ms"] for r in rows), default=float("nan"))
    best_e = min((r["error_sgm"] for r in rows), default=float("nan"))
    for r in rows:
        r["time_sgm_rel"] = r["time_sgm_ms"] / best_t if best_t > 0 else float("nan")
        r["error_sgm_rel"] = (r["error_sgm"] + SHIFT) / (best_e + SHIFT)
    return rows


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
