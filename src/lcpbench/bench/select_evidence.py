"""What a selection knows before and after it probes: rule-outs, noise, ties.

Ruled out without a probe (:func:`ruled_out`)
    1. A documented expected failure on the contact step
       (:mod:`.expected`): PGS/SOR and Siconos Newton-min do not converge;
       OSQP at its own defaults misses 0.1 % of the force (ruled out when
       ``force_tol`` ≤ 1e-3).
    2. A profile whose residual tolerance ε (``Settings.eps``) is looser
       than ``force_tol``, on a back-end that stops on residuals (not an
       exact pivoting or active-set method): it is asked for less accuracy
       than the selection needs. Measured on the default probes at
       force_tol 1e-6: every such pair (OSQP, Clarabel, ProxQP, cvxpy, PIQP,
       SCS, Siconos Newton-FB at ``low``, ε = 1e-3) failed.
    3. Evidence already collected on scenes of the same kind (N, ℓ, EI, w,
       channel): a run of the same back-end and profile, driver ``globalised``,
       that did not converge at a driver tolerance at least as loose as the
       probes'. The driver stops when max|Δα| ≤ tol, so a run at a tighter
       tolerance follows the same path at least as far and meets the same
       failure. The evidence is the store's own runs and the committed
       standard sweep (``results/sweep/runs.csv``) when it is there.

Noise and ties (:func:`compare`)
    The time of a candidate on a probe is the median of its repeats. A
    comparison of B with A uses the per-probe log ratios dᵢ = ln t_B,i − ln t_A,i:
    the ratio is exp(mean dᵢ), its standard error s combines the scatter of dᵢ
    over the probes (s.e. of the mean) with the spread of the repeats
    (half the log range of each probe's repeats). B is *tied* with A when
    mean dᵢ ≤ t·s, t the one-sided 97.5 % Student quantile with n − 1
    degrees of freedom (n probes): B is not slower beyond the measured noise.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from .expected import EXPECTED, OFF_REFERENCE

#: the committed standard sweep, read as evidence when the package runs from a checkout
COMMITTED_RUNS = Path(__file__).resolve().parents[3] / "results" / "sweep" / "runs.csv"
#: profiles from the simplest (the back-end's own defaults) to the most demanding
PROFILE_ORDER = ("default", "low", "mid", "high")
#: statuses that say the back-end failed on its own (not a timeout or a crash of the machine)
FAILED = ("not_converged", "max_iterations", "invalid", "diverged")


def kind_of(row_or_scene) -> tuple:
    """The kind of a scene (N, ℓ, EI, w, channel) from a scene or a run row."""
    get = (row_or_scene.get if isinstance(row_or_scene, dict)
           else lambda k: getattr(row_or_scene, k))
    return (int(get("links")), float(get("length")), float(get("EI")), float(get("weight")),
            bool(int(get("channel"))))


def read_runs_csv(path: str | Path) -> list[dict]:
    """The runs of a report's ``runs.csv`` (the columns a rule-out needs)."""
    out = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            try:
                out.append({"backend": r["backend"], "settings": r["settings"],
                            "tol": float(r["tol"]), "method": r["method"],
                            "status": r["status"], "converged": int(r["converged"]),
                            "links": r["links"], "length": r["length"], "EI": r["EI"],
                            "weight": r["weight"], "channel": r["channel"],
                            "source": str(path)})
            except (KeyError, ValueError):
                continue  # not a run row of this schema
    return out


def ruled_out(candidates: list[tuple[str, str]], kinds: set[tuple], force_tol: float,
              driver_tol: float, evidence: list[dict],
              methods: dict[tuple[str, str], str] | None = None) -> dict[tuple[str, str], str]:
    """The candidates (back-end, profile) that cannot meet ``force_tol``, each with why.

    ``kinds``: the kinds of scene selected for; ``evidence``: run rows (store
    rows or :func:`read_runs_csv` rows) on any scenes; ``methods``: each candidate's
    stored method (default "globalised": its own form), whose runs alone count.
    """
    from ..solvers.registry import get_backend, get_settings

    out: dict[tuple[str, str], str] = {}
    smallest = min(k[0] for k in kinds) if kinds else 0
    for b, s in candidates:
        for e in EXPECTED:
            if e.backend != b or e.settings not in (None, s) or e.partial:
                continue
            if e.min_links is not None and smallest < e.min_links:
                continue  # documented at larger N only
            if "not_converged" in e.statuses or (OFF_REFERENCE in e.statuses
                                                  and force_tol <= 1e-3):
                out[(b, s)] = f"documented failure: {e.why}"
                break
        if (b, s) in out:
            continue
        eps = get_settings(s).eps
        if eps is not None and eps > force_tol and not get_backend(b).exact:
            out[(b, s)] = (f"profile {s} stops at residual {eps:.0e}, looser than the "
                           f"force accuracy {force_tol:.0e}, and {b} is not exact")
    for r in evidence:
        key = (r["backend"], r["settings"])
        if (key not in candidates or key in out
                or r["method"] != (methods or {}).get(key, "globalised")
                or r["status"] not in FAILED or bool(int(r["converged"]))
                or float(r["tol"]) < driver_tol or kind_of(r) not in kinds):
            continue
        where = r.get("source", "the store")
        out[key] = (f"did not converge ({r['status']}) at driver tolerance {float(r['tol']):.0e} "
                    f"rad ≥ {driver_tol:.0e} on a scene of this kind ({where})")
    return out


def log_noise(row: dict) -> float:
    """Half the log range of a run's repeated times (0 for one timing)."""
    lo, hi = row.get("wall_time_min"), row.get("wall_time_max")
    if not row.get("repeats") or row["repeats"] < 2 or not lo or not hi:
        return 0.0
    return 0.5 * math.log(max(hi, 1e-12) / max(lo, 1e-12))


def student_t(dof: int) -> float:
    """The one-sided 97.5 % quantile of Student's t with ``dof`` degrees of freedom."""
    from scipy.stats import t

    return float(t.ppf(0.975, max(1, dof)))


def compare(a: list[dict], b: list[dict]) -> dict:
    """How much slower B is than A over the same probes (rows in the same order).

    Returns ``ratio`` (geometric mean of t_B/t_A), ``se`` (its standard error,
    as a ratio: ratio·s), ``log_ratio``, ``log_se`` and ``tied`` (B not slower
    than A beyond the noise, see the module's docstring).
    """
    if len(a) != len(b) or not a:
        raise ValueError("compare needs the same probes for both candidates")
    d = np.array([math.log(max(y["wall_time"], 1e-9) / max(x["wall_time"], 1e-9))
                  for x, y in zip(a, b)])
    n = len(d)
    scatter = float(np.var(d, ddof=1)) / n if n > 1 else 0.0
    repeats = sum(log_noise(x) ** 2 + log_noise(y) ** 2 for x, y in zip(a, b)) / n ** 2
    s = math.sqrt(scatter + repeats)
    mean = float(d.mean())
    ratio = math.exp(mean)
    return {"ratio": ratio, "se": ratio * s, "log_ratio": mean, "log_se": s,
            "tied": mean <= student_t(n - 1) * s}


def preference(backend: str, settings: str, time_s: float) -> tuple:
    """The order among tied candidates: the simpler profile, then an exact back-end, then time."""
    from ..solvers.registry import get_backend

    rank = PROFILE_ORDER.index(settings) if settings in PROFILE_ORDER else len(PROFILE_ORDER)
    return (rank, not get_backend(backend).exact, time_s)


__all__ = ["COMMITTED_RUNS", "PROFILE_ORDER", "compare", "kind_of", "log_noise", "preference",
           "read_runs_csv", "ruled_out", "student_t"]
