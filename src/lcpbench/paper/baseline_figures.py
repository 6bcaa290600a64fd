"""Stages against the appendix's root-finding baseline: Figs. 26-27, Tables I-II, errata.

The baseline is :func:`lcpbench.reference.root_finding.solve_baseline`, the paper's
single-reaction model of 3N + 2 equations (appendix, Table I). Fig. 26
measures the disagreement |R_LCP - R_NL| / (R_LCP + R_NL) x 100; Table II
times both models at h = 1 mm; the errata stage bounds what the eq. (13)
misprint of gamma would change.
"""

from __future__ import annotations

import math
import os
import platform
import statistics
import time
from dataclasses import replace

import numpy as np

from ..api import solve
from ..problems.scenes import DEFAULT_LENGTH, DEFAULT_WEIGHT, ActuatorScene
from ..reference.root_finding import BaselineSystem, solve_baseline
from .data import PAPER, PAPER_TOL, Plan
from .figures import model_solve
from .output import Output
from .plots import plot_fig26, plot_fig27, plot_table2


# -- Figs. 26, 27, Tables I, II -------------------------------------------------------------------
def _disagreement(r_lcp: float, r_nl: float) -> float:
    """|R_LCP − R_NL| / (R_LCP + R_NL) × 100, the paper's measure (Fig. 26)."""
    total = r_lcp + r_nl
    return 100 * abs(r_lcp - r_nl) / total if total > 0 else math.nan


def _baseline_row(scene: ActuatorScene, jacobian: str, lcp_force: float) -> dict:
    b = solve_baseline(scene, jacobian=jacobian)
    return {f"{jacobian}_status": b.status, f"{jacobian}_converged": b.converged,
            f"{jacobian}_valid": b.valid, f"{jacobian}_force": b.total_force,
            f"{jacobian}_disagreement_percent": (_disagreement(lcp_force, b.total_force)
                                                 if b.converged else math.nan),
            f"{jacobian}_max_penetration": b.max_penetration if b.converged else math.nan,
            f"{jacobian}_time_s": b.time_s, f"{jacobian}_nfev": b.iterations}


def fig26_disagreement(plan: Plan, out: Output) -> dict:
    """LCP against the single-reaction root-finding baseline over θ and h (Fig. 26)."""
    rows = []
    for h in plan.fig26_heights:
        for th in plan.fig26_thetas:
            scene = ActuatorScene(theta=th, height=h, links=plan.links)
            lcp = model_solve(scene)
            row = {"theta": th, "height": h, "links": plan.links,
                   "lcp_force": lcp.total_force, "lcp_converged": lcp.converged,
                   "lcp_contact_nodes": (np.asarray(lcp.contact_nodes) + 2).tolist(),
                   "lcp_midspan_only": (np.asarray(lcp.contact_nodes) + 2).tolist()
                   == [plan.links // 2 + 1]}
            und = model_solve(scene, method="undamped")
            row.update({"undamped_converged": und.converged,
                        "undamped_force": und.total_force if und.converged else math.nan,
                        "undamped_reason": "" if und.converged else und.reason})
            for jac in ("analytic", "fd"):
                row.update(_baseline_row(scene, jac, lcp.total_force))
            rows.append(row)
    out.csv("fig26-disagreement.csv", rows)

    def worst(sel, jac="analytic"):
        v = [r[f"{jac}_disagreement_percent"] for r in sel
             if math.isfinite(r[f"{jac}_disagreement_percent"])]
        return max(v) if v else math.nan

    per_h = {h: {"max_disagreement_percent": worst([r for r in rows if r["height"] == h]),
                 "valid": sum(r["analytic_valid"] for r in rows if r["height"] == h),
                 "converged": sum(r["analytic_converged"] for r in rows if r["height"] == h),
                 "fd_converged": sum(r["fd_converged"] for r in rows if r["height"] == h),
                 "fd_max_disagreement_percent": worst([r for r in rows if r["height"] == h],
                                                      "fd"),
                 "scenes": sum(r["height"] == h for r in rows),
                 "max_penetration": max((r["analytic_max_penetration"] for r in rows
                                         if r["height"] == h and r["analytic_converged"]),
                                        default=math.nan)}
             for h in plan.fig26_heights}
    plot_fig26(rows, out.path("fig26-disagreement.png"))
    high = [r for r in rows if r["height"] >= PAPER["fig26"]["from_height"]]
    return {"links": plan.links, "per_height": per_h,
            "max_disagreement_from_4mm": worst(high),
            "valid_from_4mm": all(r["analytic_valid"] for r in high if r["lcp_force"] > 0),
            "midspan_only_from_4mm": all(r["lcp_midspan_only"] for r in high
                                         if r["lcp_force"] > 0),
            "fd_converged": sum(r["fd_converged"] for r in rows), "scenes": len(rows),
            "undamped_failures": [(r["theta"], r["height"], r["undamped_reason"]) for r in rows
                                  if not r["undamped_converged"]],
            "undamped_max_relative_difference": max(
                (abs(r["undamped_force"] - r["lcp_force"]) / r["lcp_force"] for r in rows
                 if r["undamped_converged"] and r["lcp_force"] > 0), default=0.0)}


def fig27_shapes(plan: Plan, out: Output) -> dict:
    """LCP and baseline shapes at θ = 150°, h = 3 and 1 mm (Fig. 27 a, b)."""
    panels, rows = [], []
    for h in (3.0, 1.0):
        scene = ActuatorScene(theta=150.0, height=h, links=plan.links)
        lcp = model_solve(scene)
        b = solve_baseline(scene)
        panels.append({"height": h, "lcp_x": lcp.x, "lcp_y": lcp.y, "nl_x": b.x, "nl_y": b.y,
                       "lcp_force": lcp.total_force, "nl_force": b.total_force,
                       "nl_status": b.status, "nl_valid": b.valid,
                       "nl_max_penetration": b.max_penetration,
                       "lcp_min_gap": float(lcp.certificate.min_gap),
                       "lcp_contact_nodes": (np.asarray(lcp.contact_nodes) + 2).tolist(),
                       "max_shape_difference": float(np.max(np.hypot(lcp.x - b.x,
                                                                     lcp.y - b.y)))})
        rows += [{"height": h, "node": i + 1, "x_lcp": lcp.x[i], "y_lcp": lcp.y[i],
                  "x_nonlinear": b.x[i], "y_nonlinear": b.y[i]} for i in range(lcp.x.size)]
    out.csv("fig27-shapes-baseline.csv", rows)
    plot_fig27(panels, out.path("fig27-shapes-baseline.png"))
    keep = ("height", "lcp_force", "nl_force", "nl_status", "nl_valid", "nl_max_penetration",
            "lcp_min_gap", "lcp_contact_nodes", "max_shape_difference")
    return {"links": plan.links, "panels": [{k: p[k] for k in keep} for p in panels]}


def table1(plan: Plan, out: Output) -> dict:
    """Table I: the baseline's equation count, 3N + 2, checked on the system we solve."""
    rows = []
    for n in sorted({plan.links, PAPER["table2"]["links"]}):
        system = BaselineSystem(ActuatorScene(links=n).chain(), 3.0)
        rows.append({"links": n, "nonlinear_equations": system.size, "formula": 3 * n + 2,
                     "lcp_unknowns": n - 1})
    data = {"paper": PAPER["table1"], "rows": rows,
            "breakdown": {"support reactions (q1, qn)": 2, "torques (summing moments)": "N-1",
                          "torques (constitutive)": "N-1", "relation phi-alpha": "N",
                          "constraining equations (44), (45)": 2, "total": "3N+2"}}
    out.json("table1-equations.json", data)
    return data


def _interleaved(calls: dict, repeats: int) -> dict:
    """Time every call ``repeats`` times, round-robin, so drift in the machine's load
    spreads over all of them; per key: (median s, min s, last result)."""
    times: dict = {k: [] for k in calls}
    last: dict = {}
    for _ in range(repeats):
        for k, fn in calls.items():
            t0 = time.perf_counter()
            last[k] = fn()
            times[k].append(time.perf_counter() - t0)
    return {k: (statistics.median(v), min(v), last[k]) for k, v in times.items()}


def table2_times(plan: Plan, out: Output) -> dict:
    """Table II: time per bend angle at h = 1 mm, over the fastest LCP solve.

    The LCP is ``lcpbench.solve(scene)`` as a user calls it (default
    back-end, the paper's 1e-3 rad), the wall time of the whole call, median
    of ``lcp_repeats`` after one untimed warm-up; also the paper's undamped
    iteration. The baselines are timed the same way (median of
    ``baseline_repeats``), with the analytic Jacobian and with MINPACK's
    forward differences (``fsolve``'s default, Powell hybrid), whether or not
    they find a valid answer (the paper timed its breakdown cases too); and
    once with forward differences and Levenberg–Marquardt, which, unlike the
    hybrid method, gets through with finite differences at N = 140. Repeats
    run round-robin over the bend angles, so a change in the machine's load
    is shared by all of them.
    """
    h = PAPER["table2"]["height"]
    n = plan.links if plan.quick else PAPER["table2"]["links"]
    scenes = {th: ActuatorScene(theta=th, height=h, links=n) for th in plan.table2_thetas}
    solve(ActuatorScene(theta=90.0, height=h, links=n))  # warm-up: imports, caches
    solve_baseline(ActuatorScene(theta=90.0, height=h, links=min(n, 20)))
    lcp = _interleaved({(th, "lcp"): (lambda s=sc: solve(s)) for th, sc in scenes.items()}
                       | {(th, "undamped"): (lambda s=sc: solve(s, method="undamped"))
                          for th, sc in scenes.items()}, plan.lcp_repeats)
    base = _interleaved({(th, "analytic"): (lambda s=sc: solve_baseline(s))
                         for th, sc in scenes.items()}
                        | {(th, "fd"): (lambda s=sc: solve_baseline(s, jacobian="fd"))
                           for th, sc in scenes.items()}, plan.baseline_repeats)
    lm = _interleaved({(th, "fdlm"): (lambda s=sc: solve_baseline(s, jacobian="fd",
                                                                  method="lm"))
                       for th, sc in scenes.items()}, 1)
    times = lcp | base | lm
    rows = []
    for th in plan.table2_thetas:
        row = {"theta": th, "height": h, "links": n}
        for k in ("lcp", "undamped", "analytic", "fd", "fdlm"):
            median, best, res = times[(th, k)]
            row[f"{k}_s"] = median
            row[f"{k}_min_s"] = best
            if k in ("lcp", "undamped"):
                row[f"{k}_converged"] = res.converged
                row[f"{k}_outer"] = res.outer_iterations
            else:
                row[f"{k}_status"] = res.status
                row[f"{k}_valid"] = res.valid
                row[f"{k}_nfev"] = res.iterations
        lcp_res = times[(th, "lcp")][2]
        row["lcp_backend"] = lcp_res.solver
        row["lcp_force"] = lcp_res.total_force
        rows.append(row)
    best = min(r["lcp_s"] for r in rows)
    for r in rows:
        for k in ("lcp", "undamped", "analytic", "fd", "fdlm"):
            r[f"{k}_norm"] = r[f"{k}_s"] / best
        if not r["undamped_converged"]:
            r["undamped_norm"] = math.nan
    paper = PAPER["table2"]
    no_contact = []
    for th in (10.0, 20.0, 30.0):
        res = model_solve(ActuatorScene(theta=th, height=h, links=n))
        no_contact.append({"theta": th, "total_force": res.total_force,
                           "arc_height": ActuatorScene(theta=th, height=h).arc_height})
    data = {"links": n, "height": h, "fastest_ms": 1e3 * best,
            "fastest_theta": min(rows, key=lambda r: r["lcp_s"])["theta"],
            "backend": rows[0]["lcp_backend"], "tol": PAPER_TOL,
            "lcp_repeats": plan.lcp_repeats, "baseline_repeats": plan.baseline_repeats,
            "paper": paper, "rows": rows, "below_40": no_contact,
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, "
                       f"python {platform.python_version()}",
            "load_average": os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan,
            "analytic_over_lcp": [r["analytic_norm"] / r["lcp_norm"] for r in rows],
            "fd_over_lcp": [r["fd_norm"] / r["lcp_norm"] for r in rows],
            "fdlm_over_lcp": [r["fdlm_norm"] / r["lcp_norm"] for r in rows]}
    out.csv("table2-times.csv", rows)
    out.json("table2-times.json", data)
    plot_table2(rows, paper, out.path("table2-times.png"))
    return data


# -- errata: what the eq. (13) misprint would change ------------------------------------------
def errata_gravity(plan: Plan, out: Output) -> dict:
    """The force with gravity as printed in eq. (13) (γ carries a stray a/2) against ours.

    docs/errata.md: the printed γ scales the gravity load by a/2 (in mm), i.e.
    it is the corrected model with w replaced by w·a/2. The paper does not say
    whether its code carried the misprint, so this bounds what it would change.
    """
    rows = []
    for th, h in ((150.0, 3.0), (150.0, 6.0), (60.0, 3.5), (180.0, 1.0)):
        scene = ActuatorScene(theta=th, height=h, links=plan.links)
        a = DEFAULT_LENGTH / plan.links
        ours = model_solve(scene).total_force
        printed = model_solve(replace(scene, weight=DEFAULT_WEIGHT * a / 2)).total_force
        none = model_solve(replace(scene, weight=0.0)).total_force
        rows.append({"theta": th, "height": h, "force": ours, "force_printed_gamma": printed,
                     "force_no_weight": none,
                     "relative_change": (printed - ours) / ours if ours else math.nan})
    data = {"links": plan.links, "rows": rows}
    out.json("errata-gravity.json", data)
    return data


