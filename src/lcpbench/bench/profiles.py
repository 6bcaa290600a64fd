"""Dolan–Moré performance profiles and Moré–Wild data profiles of stored runs.

A *problem* p is a scene; a *solver* s is a (back-end, settings, driver)
triple, as in the comparison table. The cost t_{p,s} of a run is its wall
time, outer iterations or inner iterations when the run is a success by
the report's rule (:func:`~.metrics.succeeded`: converged and force error at
most min(1e-3, 100·tol)), and +inf otherwise (also when s has no row for p).

Performance profile (Dolan & Moré, Math. Program. 91, 2002)
    r_{p,s} = t_{p,s} / min_σ t_{p,σ}, the performance ratio, and
    ρ_s(τ) = |{p : r_{p,s} ≤ τ}| / |P|. ρ_s(1) is the share of problems
    on which s is the cheapest (ties count for each tied solver), ρ_s is
    non-decreasing and right-continuous, and ρ_s(τ) → the share of problems
    s solved as τ → ∞. A problem no solver solved has r = inf for all.
Data profile (Moré & Wild, SIAM J. Optim. 20, 2009)
    d_s(κ) = |{p : t_{p,s} / n_p ≤ κ}| / |P|: the share of problems s solves
    within a budget κ. Moré and Wild count function evaluations per simplex
    gradient, n_p = (dimension + 1); here the inner iterations are divided by
    n_p = N + 1 (N links, the number of unknowns of a contact step), outer
    iterations and times are counted as they are (n_p = 1). Unlike the
    performance profile it is absolute, so adding a solver does not change
    another's curve.

Failures are charged as in the report's scores, at a cost beyond every
budget plotted: Dolan and Moré's r_M, here +inf, so a failure never counts
as solved at any τ or κ (charging it at the time limit instead would only
add a jump at τ = limit / best, ~10⁵, off the plotted range).

Back-ends that report no inner iteration count (0 on every run, contact
scenes included: HiGHS and DAQP through qpsolvers, Siconos' enumeration,
the finite-difference baseline's Jacobian count;
:func:`~.metrics.silent_inner`) are left out of the inner-iteration
profiles, since a zero would make them the cheapest everywhere and set the
ratios of everyone else; :attr:`Profile.left_out` names them.

Costs of iteration counts are floored at 1 (a solve that needed no
iteration, a no-contact scene, costs one), so ratios stay defined; times
are floored at 1 µs. Inner iterations mean different things per back-end
(pivots, active-set changes, ADMM or interior-point iterations): their
profile compares work counts, not like with like; the time profile is the
one to read first.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass

import numpy as np

from .metrics import silent_inner

#: measure -> (row field, floor, scale to the unit of the axis, label)
MEASURES = {
    "time": ("wall_time", 1e-6, 1e3, "wall time (ms)"),
    "outer": ("outer_iterations", 1.0, 1.0, "outer iterations"),
    "inner": ("inner_iterations", 1.0, 1.0, "inner iterations"),
}


@dataclass
class Profile:
    """One profile: ρ_s (or d_s) of each solver at the breakpoints ``x``.

    ``values[s][i]`` is the curve of solver ``solvers[s]`` at ``x[i]`` (a
    step function, constant from ``x[i]`` to ``x[i+1]``); ``solved[s]`` its
    limit, the share of problems the solver solved; ``problems`` is |P|.
    """

    kind: str  # "performance" or "data"
    measure: str
    group: str  # the settings profile the curves compare ("all": every solver)
    solvers: list[str]
    x: np.ndarray
    values: np.ndarray  # (solvers, len(x))
    solved: np.ndarray
    problems: int
    left_out: tuple[str, ...] = ()  # back-ends left out (no count of this measure)

    def at(self, solver: str, x: float) -> float:
        """The curve of ``solver`` at ``x`` (τ or κ), from the breakpoints."""
        i = int(np.searchsorted(self.x, x, side="right")) - 1
        return 0.0 if i < 0 else float(self.values[self.solvers.index(solver), i])

    def same_curves(self) -> list[list[int]]:
        """The solvers grouped by identical curves (every breakpoint and the solved
        share equal), each group in solver order, groups in order of their first."""
        groups: dict[tuple, list[int]] = {}
        for s in range(len(self.solvers)):
            key = (tuple(self.values[s].tolist()), float(self.solved[s]))
            groups.setdefault(key, []).append(s)
        return list(groups.values())


def performance_ratios(cost: np.ndarray) -> np.ndarray:
    """r_{p,s} = t_{p,s} / min_σ t_{p,σ} for a (problems × solvers) cost array.

    Failures are +inf; a problem no solver solved has r = +inf everywhere.
    """
    cost = np.asarray(cost, float)
    if cost.ndim != 2:
        raise ValueError("cost must be a (problems x solvers) array")
    if np.any(np.isnan(cost)) or np.any(cost <= 0):
        raise ValueError("costs must be > 0 (failures +inf), not NaN")
    best = cost.min(axis=1, initial=math.inf, keepdims=True)
    with np.errstate(invalid="ignore"):
        r = cost / best
    r[~np.isfinite(best[:, 0]), :] = math.inf
    return r


def _step_curves(per_problem: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Breakpoints (finite values, sorted) and the share of problems ≤ each, per column."""
    P = per_problem.shape[0]
    finite = per_problem[np.isfinite(per_problem)]
    x = np.unique(finite) if finite.size else np.array([1.0])
    values = np.empty((per_problem.shape[1], x.size))
    for s in range(per_problem.shape[1]):
        col = np.sort(per_problem[:, s])
        values[s] = np.searchsorted(col, x, side="right") / P if P else 0.0
    return x, values


def performance_profile(cost, solvers, *, measure: str = "", group: str = "all"
                        ) -> Profile:
    """The Dolan–Moré performance profile of a (problems × solvers) cost array."""
    cost = np.asarray(cost, float)
    r = performance_ratios(cost)
    x, values = _step_curves(r)
    if x[0] > 1.0:  # τ = 1 is always a breakpoint (the "fastest" share)
        x = np.concatenate([[1.0], x])
        values = np.concatenate([np.zeros((values.shape[0], 1)), values], axis=1)
    solved = np.isfinite(cost).mean(axis=0) if cost.shape[0] else np.zeros(cost.shape[1])
    return Profile("performance", measure, group, list(solvers), x, values, solved,
                   cost.shape[0])


def data_profile(cost, solvers, units=None, *, measure: str = "", group: str = "all"
                 ) -> Profile:
    """The Moré–Wild data profile: d_s(κ) = share of problems with t_{p,s} / n_p ≤ κ."""
    cost = np.asarray(cost, float)
    if np.any(np.isnan(cost)) or np.any(cost <= 0):
        raise ValueError("costs must be > 0 (failures +inf), not NaN")
    n = np.ones(cost.shape[0]) if units is None else np.asarray(units, float)
    if n.shape != (cost.shape[0],) or np.any(n <= 0):
        raise ValueError("units must be one positive number per problem")
    budget = cost / n[:, None]
    x, values = _step_curves(budget)
    solved = np.isfinite(cost).mean(axis=0) if cost.shape[0] else np.zeros(cost.shape[1])
    return Profile("data", measure, group, list(solvers), x, values, solved, cost.shape[0])


# -- from judged runs --------------------------------------------------------------------
def solver_label(backend: str, settings: str, method: str, drivers: int) -> str:
    """The name of a solver in the profiles: back-end/settings (and driver if several)."""
    name = backend if settings == "-" else f"{backend}/{settings}"
    return f"{name} ({method})" if drivers > 1 and not backend.startswith("baseline") else name


def cost_matrix(evaluated, measure: str, *, settings: str | None = None,
                leave_out=()) -> tuple[list[str], list[str], np.ndarray, np.ndarray]:
    """(problems, solvers, cost array, links of each problem) from judged runs.

    ``settings``: only the solvers at that profile (the baselines, settings
    "-", are kept in every group); ``leave_out``: back-ends not to include.
    Unsuccessful runs, and missing ones, cost +inf.
    """
    if measure not in MEASURES:
        raise ValueError(f"unknown measure {measure!r}; one of {', '.join(MEASURES)}")
    field, floor, scale, _ = MEASURES[measure]
    chosen = [e for e in evaluated if e.backend not in leave_out
              and (settings is None or e.settings in (settings, "-"))]
    drivers = len({e.row["method"] for e in chosen if not e.backend.startswith("baseline")})
    problems = sorted({e.row["scene"] for e in chosen})
    links = {e.row["scene"]: int(e.row["links"]) for e in chosen}
    label = {id(e): solver_label(e.backend, e.settings, e.row["method"], drivers)
             for e in chosen}
    solvers = sorted(set(label.values()), key=lambda s: (s.startswith("baseline"), s))
    pi = {p: i for i, p in enumerate(problems)}
    si = {s: j for j, s in enumerate(solvers)}
    cost = np.full((len(problems), len(solvers)), math.inf)
    for e in chosen:
        if e.success:
            v = e.row[field]
            v = math.inf if v is None or not math.isfinite(float(v)) else float(v)
            cost[pi[e.row["scene"]], si[label[id(e)]]] = max(v * scale, floor * scale)
    return problems, solvers, cost, np.array([links[p] for p in problems], float)


def profiles_of(evaluated) -> list[Profile]:
    """Every profile of the report: per settings profile, for each measure, both kinds.

    The inner-iteration profiles leave out the back-ends that report no
    inner count (:func:`~.metrics.silent_inner`), named in ``left_out``.
    """
    groups = sorted({e.settings for e in evaluated if e.settings != "-"},
                    key=lambda s: ({"default": 0, "low": 1, "mid": 2, "high": 3}.get(s, 9), s))
    silent = silent_inner(evaluated)
    out = []
    for g in groups:
        for m in MEASURES:
            leave = silent if m == "inner" else set()
            _, solvers, cost, links = cost_matrix(evaluated, m, settings=g, leave_out=leave)
            if not solvers:
                continue
            left = tuple(sorted({e.backend for e in evaluated if e.backend in leave
                                 and e.settings in (g, "-")}))
            for p in (performance_profile(cost, solvers, measure=m, group=g),
                      data_profile(cost, solvers, links + 1 if m == "inner" else None,
                                   measure=m, group=g)):
                p.left_out = left
                out.append(p)
    return out


def write_csv(profiles: list[Profile], path: str | os.PathLike) -> int:
    """The profiles as CSV: kind, measure, settings, solver, x, value, solved, problems.

    One row per breakpoint and solver (x is τ for a performance profile, κ
    for a data profile; the curve is constant until the next x). Returns the
    number of data rows.
    """
    n = 0
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["kind", "measure", "settings", "solver", "x", "value", "solved",
                    "problems"])
        for p in profiles:
            for s, name in enumerate(p.solvers):
                for x, v in zip(p.x, p.values[s]):
                    w.writerow([p.kind, p.measure, p.group, name, repr(float(x)),
                                repr(float(v)), repr(float(p.solved[s])), p.problems])
                    n += 1
    return n


def read_csv(path: str | os.PathLike) -> list[Profile]:
    """The profiles written by :func:`write_csv`, back as :class:`Profile` objects."""
    rows: dict[tuple, dict[str, list]] = {}
    meta: dict[tuple, dict] = {}
    with open(path, newline="") as fh:
        for r in csv.DictReader(fh):
            key = (r["kind"], r["measure"], r["settings"])
            rows.setdefault(key, {}).setdefault(r["solver"], []).append(
                (float(r["x"]), float(r["value"])))
            meta.setdefault(key, {})[r["solver"]] = (float(r["solved"]), int(r["problems"]))
    out = []
    for key, by in rows.items():
        solvers = list(by)
        x = np.array([a for a, _ in by[solvers[0]]])
        values = np.array([[v for _, v in by[s]] for s in solvers])
        solved = np.array([meta[key][s][0] for s in solvers])
        out.append(Profile(key[0], key[1], key[2], solvers, x, values, solved,
                           meta[key][solvers[0]][1]))
    return out


def profiles_section(figures: list[str]) -> str:
    """The report's section on the profiles: what they are, and their figures."""
    lines = [
        "",
        "## Performance and data profiles",
        "",
        "Dolan–Moré performance profiles: ρ_s(τ) is the share of scenes on which solver s "
        "(back-end/settings) succeeded within τ times the cost of the best solver on that "
        "scene; ρ_s(1) is the share on which it was the cheapest, and the curve levels off "
        "at the share it solved. Moré–Wild data profiles: d_s(κ) is the share of scenes s "
        "solved within a budget κ (inner iterations per N + 1 unknowns; outer iterations and "
        "milliseconds as they are). Success is the rule above; a failure is charged beyond "
        "every τ and κ plotted (a cost of ∞, Dolan–Moré's r_M), so it never counts as solved. "
        "One panel per settings profile, the baselines in each. Inner iterations count "
        "different work per back-end (pivots, active-set changes, ADMM or interior-point "
        "iterations); back-ends that report no inner count (0 on every run, contact scenes "
        "included) are left out of the inner-iteration profiles, and each panel names them. "
        "Solvers whose curves are identical share one legend entry.",
        "",
    ]
    for f in figures:
        lines += [f"![{f[:-4]}]({f})", ""]
    lines += ["The curves as data: [profiles.csv](profiles.csv) (kind, measure, settings, "
              "solver, x = τ or κ, value, solved share, scenes).", ""]
    return "\n".join(lines)


__all__ = ["MEASURES", "Profile", "cost_matrix", "data_profile", "performance_profile",
           "performance_ratios", "profiles_of", "profiles_section", "read_csv", "solver_label", "write_csv"]
