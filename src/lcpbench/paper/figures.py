"""Figure stages of the model alone: Figs. 5-8, Sec. III-G / Fig. 10 and Fig. 24.

Each stage takes a :class:`~lcpbench.paper.data.Plan` and an
:class:`~lcpbench.paper.output.Output`, computes the figure's numbers with
the model, writes them as CSV/JSON with the PNG beside them
(:mod:`lcpbench.paper.plots`) and returns the numbers the README quotes.

The figures are solved with the exact ``active-set`` back-end at 1e-8 rad
(:data:`~lcpbench.paper.data.SOLVER`, :data:`~lcpbench.paper.data.TOL`), so
that they show the model and not the driver's truncation at the paper's
1e-3 rad (eq. 32).
"""

from __future__ import annotations

import math
import statistics
from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from ..api import solve
from ..model.chain import node_positions
from ..model.result import ContactResult
from ..problems.calibrations import (
    COMPARISON_PRESSURE_RANGES,
    KPA_PER_PSI,
    PAPER_EI_RANGE,
    PAPER_PRESSURE_RANGE,
    PAPER_WEIGHT_RANGE,
    get_calibration,
    scene_from_pressure,
)
from ..problems.cantilever import CantileverScene
from ..problems.scenes import (
    DEFAULT_EI,
    DEFAULT_LENGTH,
    ActuatorScene,
    Chain,
)
from ..studies.batch import solve_many
from ..studies.discretisation import discretisation_study
from ..studies.validation import cantilever_validation, observed_order
from .data import PAPER, RULE_THRESHOLD, SOLVER, TOL, Plan
from .output import Output
from .plots import plot_cantilever, plot_fig5, plot_fig8, plot_fig24, plot_shapes


def model_solve(scene: ActuatorScene | CantileverScene, **kw) -> ContactResult:
    """A figure's solve: the exact back-end at the figures' tolerance (rows record
    ``converged``, and the tests require it)."""
    kw.setdefault("solver", SOLVER)
    kw.setdefault("tol", TOL)
    return solve(scene, **kw)


def model_solve_many(scenes: list, **kw) -> list[ContactResult]:
    """Many figure solves with the figures' back-end and tolerance, in one
    :func:`lcpbench.solve_many` call (continuation along θ or h; the default
    back-end's compiled batch loop), one result per scene in their order."""
    kw.setdefault("solver", SOLVER)
    kw.setdefault("tol", TOL)
    return solve_many(scenes, **kw)


def _touch_width(res: ContactResult, tol: float = 1e-9) -> float:
    """x-extent of the nodes lying on the (upper) wall (mm); 0 without contact."""
    on = np.flatnonzero(res.gaps < tol) + 1  # free nodes 2..N -> 0-based node indices
    return float(res.x[on.max()] - res.x[on.min()]) if on.size else 0.0


# -- Fig. 5, Sec. III-D ---------------------------------------------------------------------------
def fig5_discretisation(plan: Plan, out: Output) -> dict:
    """The Sec. III-D rule over the paper's grid, and the force change against N (Fig. 5).

    For every scene: the force at N = 10, 20, …, ``fig5_max_links`` (the curve,
    :func:`discretisation_study` run with a vanishing threshold) and the N
    the rule picks (:func:`discretisation_study` at 0.01 %). The grid's N is
    the largest pick (the paper's "conservative estimate"); also reported,
    the largest change at N = 140 over the grid and the decay rate of the
    change (the paper: "about three").
    """
    rows, scenes = [], []
    for h in plan.fig5_heights:
        for th in plan.fig5_thetas:
            scene = ActuatorScene(theta=th, height=h, links=10)
            curve = discretisation_study(scene, threshold=1e-300, max_links=plan.fig5_max_links,
                                         solver=SOLVER, tol=TOL)
            rule = discretisation_study(scene, threshold=RULE_THRESHOLD, max_links=2000,
                                        solver=SOLVER, tol=TOL)
            change = [math.nan] + list(curve.percent_change)
            for n, f, c in zip(curve.links, curve.total_force, change):
                rows.append({"theta": th, "height": h, "links": n, "total_force": f,
                             "percent_change": c})
            contact = any(f > 0 for f in curve.total_force)
            links = np.array(curve.links[1:], float)
            ch = np.array(curve.percent_change)
            keep = (links >= 40) & (ch > 0)
            rate = (float(-np.polyfit(np.log(links[keep]), np.log(ch[keep]), 1)[0])
                    if contact and keep.sum() >= 3 else math.nan)
            at = {n: c for n, c in zip(curve.links[1:], curve.percent_change)}
            scenes.append({"theta": th, "height": h, "contact": contact,
                           "arc_height": scene.arc_height,
                           "chosen": rule.chosen, "rate": rate,
                           "change_at_140": at.get(140, math.nan),
                           "max_change_from_140": max(
                               (c for n, c in at.items() if n >= 140), default=math.nan)})
    picks = [s["chosen"] for s in scenes if s["chosen"] is not None]
    contact = [s for s in scenes if s["contact"]]
    rates = [s["rate"] for s in contact if math.isfinite(s["rate"])]
    # smallest N from which every scene's change stays below the threshold (up to the curve end)
    by_n: dict[int, float] = {}
    for r in rows:
        if math.isfinite(r["percent_change"]):
            by_n[r["links"]] = max(by_n.get(r["links"], 0.0), r["percent_change"])
    settled = None
    for n in sorted(by_n, reverse=True):
        if by_n[n] >= RULE_THRESHOLD:
            break
        settled = n
    at_once = min((n for n, c in by_n.items() if c < RULE_THRESHOLD), default=None)
    smooth = [s["rate"] for s in contact if s["height"] == plan.fig5_plot_height
              and math.isfinite(s["rate"])]
    data = {
        "threshold_percent": RULE_THRESHOLD, "step": 10, "start": 10,
        "curve_max_links": plan.fig5_max_links, "plot_height": plan.fig5_plot_height,
        "grid_links": max(picks) if picks else None,
        "unsettled": [(s["theta"], s["height"]) for s in scenes if s["chosen"] is None],
        "all_changes_below_threshold_at": at_once,
        "all_changes_below_threshold_from": settled,
        "max_change_at_140": max((s["change_at_140"] for s in contact), default=math.nan),
        "max_change_from_140": max((s["max_change_from_140"] for s in contact),
                                   default=math.nan),
        "rate_median": statistics.median(rates) if rates else math.nan,
        "rate_min": min(rates) if rates else math.nan,
        "rate_max": max(rates) if rates else math.nan,
        "rate_median_plot_height": statistics.median(smooth) if smooth else math.nan,
        "scenes": scenes,
    }
    out.csv("fig5-discretisation.csv", rows)
    out.json("fig5-discretisation.json", data)
    plot_fig5(rows, data, out.path("fig5-discretisation.png"))
    return data


# -- Figs. 6 and 7 --------------------------------------------------------------------------------
def _shape(scene: ActuatorScene) -> dict:
    res = model_solve(scene)
    chain = scene.chain()
    x0, y0 = node_positions(chain, chain.rest_alpha)
    forces = np.zeros(res.x.size)
    forces[chain.free_nodes] = res.forces
    return {"theta": scene.theta, "height": scene.height, "links": res.links,
            "converged": res.converged, "total_force": res.total_force,
            "span": res.span, "free_span": float(x0[-1] - x0[0]),
            "touch_width": _touch_width(res), "x": res.x, "y": res.y, "forces": forces,
            "x0": x0, "y0": y0, "max_y": float(res.y.max()),
            "min_gap": float(res.certificate.min_gap)}


def _shape_rows(shapes: list[dict]) -> list[dict]:
    return [{"theta": s["theta"], "height": s["height"], "node": i + 1, "x": x, "y": y,
             "force": f, "x_unconstrained": x0, "y_unconstrained": y0}
            for s in shapes
            for i, (x, y, f, x0, y0) in enumerate(zip(s["x"], s["y"], s["forces"], s["x0"],
                                                      s["y0"]))]


def fig6_7_shapes(plan: Plan, out: Output) -> dict:
    """Constrained shapes against θ at h = 2 mm (Fig. 6) and against h at θ = 150° (Fig. 7)."""
    f6 = [_shape(ActuatorScene(theta=t, height=2.0, links=plan.links))
          for t in plan.fig6_thetas]
    f7 = [_shape(ActuatorScene(theta=150.0, height=h, links=plan.links))
          for h in plan.fig7_heights]
    out.csv("fig6-shapes-theta.csv", _shape_rows(f6))
    out.csv("fig7-shapes-height.csv", _shape_rows(f7))
    plot_shapes(f6, "theta", out.path("fig6-shapes-theta.png"),
                "Fig. 6: constrained shape against θ (h = 2 mm, "
                f"N = {plan.links})")
    plot_shapes(f7, "height", out.path("fig7-shapes-height.png"),
                f"Fig. 7: constrained shape against h (θ = 150°, N = {plan.links})")
    keep = ("theta", "height", "converged", "total_force", "span", "free_span",
            "touch_width", "max_y", "min_gap")
    return {"fig6": [{k: s[k] for k in keep} for s in f6],
            "fig7": [{k: s[k] for k in keep} for s in f7]}


# -- Fig. 8 ---------------------------------------------------------------------------------------
def _linear_fit(xs: list[float], ys: list[float]) -> dict:
    xs_a, ys_a = np.asarray(xs, float), np.asarray(ys, float)
    slope, icpt = np.polyfit(xs_a, ys_a, 1)
    dev = np.max(np.abs(ys_a - (slope * xs_a + icpt))) / max(np.max(np.abs(ys_a)), 1e-300)
    return {"slope": float(slope), "intercept": float(icpt), "max_deviation": float(dev)}


def fig8_forces(plan: Plan, out: Output) -> dict:
    """Total force against θ for h = 2–7 mm (a), against EI at θ = 150° (b) and at h = 3 mm (c).

    (a) also runs the paper's undamped iteration (Fig. 3) on every scene, to
    show where it fails and that it lands on the same equilibrium elsewhere.
    """
    a = []
    grid = [ActuatorScene(theta=th, height=h, links=plan.links) for h in plan.fig8_heights
            for th in plan.fig8a_thetas]
    for scene, g in zip(grid, model_solve_many(grid), strict=True):  # globalised: one batch
        u = model_solve(scene, method="undamped")
        a.append({"theta": scene.theta, "height": scene.height, "EI": DEFAULT_EI,
                  "total_force": g.total_force, "converged": g.converged,
                  "outer_iterations": g.outer_iterations, "arc_height": scene.arc_height,
                  "undamped_converged": u.converged,
                  "undamped_total_force": u.total_force if u.converged else math.nan,
                  "undamped_reason": "" if u.converged else u.reason})
    grid_b = [ActuatorScene(theta=150.0, height=h, EI=e, links=plan.links)
              for h in plan.fig8_heights for e in plan.fig8_EIs]
    b = [{"theta": 150.0, "height": s.height, "EI": s.EI, "total_force": r.total_force,
          "converged": r.converged} for s, r in zip(grid_b, model_solve_many(grid_b),
                                                    strict=True)]
    grid_c = [ActuatorScene(theta=th, height=3.0, EI=e, links=plan.links)
              for th in plan.fig8c_thetas for e in plan.fig8_EIs]
    c = [{"theta": s.theta, "height": 3.0, "EI": s.EI, "total_force": r.total_force,
          "converged": r.converged} for s, r in zip(grid_c, model_solve_many(grid_c),
                                                    strict=True)]
    out.csv("fig8a-force-theta.csv", a)
    out.csv("fig8b-force-EI-theta150.csv", b)
    out.csv("fig8c-force-EI-h3.csv", c)

    def fits(rows, key):
        res = {}
        for v in sorted({r[key] for r in rows}):
            sel = [r for r in rows if r[key] == v and r["total_force"] > 0]
            if len(sel) >= 3 and len(sel) == sum(r[key] == v for r in rows):
                res[v] = _linear_fit([r["EI"] for r in sel], [r["total_force"] for r in sel])
        return res

    both = [r for r in a if r["undamped_converged"] and r["converged"]]
    data = {
        "links": plan.links,
        "all_converged": all(r["converged"] for r in a + b + c),
        "undamped_failures": [(r["theta"], r["height"], r["undamped_reason"]) for r in a
                              if not r["undamped_converged"]],
        "undamped_max_relative_difference": max(
            (abs(r["undamped_total_force"] - r["total_force"]) / max(r["total_force"], 1e-300)
             for r in both if r["total_force"] > 0), default=0.0),
        "fits_b": fits(b, "height"), "fits_c": fits(c, "theta"),
        "first_contact_theta": {h: min((r["theta"] for r in a
                                        if r["height"] == h and r["total_force"] > 0),
                                       default=None) for h in plan.fig8_heights},
        "force_at_150_h2_mN": next((1e3 * r["total_force"] for r in a
                                    if r["theta"] == 150 and r["height"] == 2), None),
    }
    out.json("fig8.json", {**data, "a": a, "b": b, "c": c})
    plot_fig8(a, b, c, out.path("fig8-forces.png"))
    return data


# -- Sec. III-G, Fig. 10 --------------------------------------------------------------------------
class PaperLikeCantilever(CantileverScene):
    """The cantilever discretised as we read Fig. 9(b): what the paper most likely ran.

    Two changes from :class:`~lcpbench.problems.cantilever.CantileverScene`: the
    clamp spring is EI/a (a joint like any other) instead of 2EI/a, and the
    load ω = Fℓ/N of Fig. 9(b) acts at each of the nodes 2..N+1 instead of
    at the link centres. Loads enter the chain only through the node heights,
    so ω at every node is the link loads 2ω, 0, 2ω, … counted from the tip.
    """

    def chain(self) -> Chain:
        chain = super().chain()
        stiffness = chain.joint_stiffness.copy()
        stiffness[0] = self.EI / chain.link_length
        load = np.zeros(chain.links)
        load[::-1][::2] = 2 * self.load * chain.link_length
        return replace(chain, joint_stiffness=stiffness, link_load=load)


def _beam_distance(res: ContactResult, sc: CantileverScene, tip_force: float = 0.0
                   ) -> np.ndarray:
    """|node − the same node of linear theory| / ℓ; theory nodes at x = s (no shortening)."""
    s = np.arange(res.x.size) * sc.length / sc.links
    y = sc.theory_deflection(s) - tip_force * s**2 * (3 * sc.length - s) / (6 * sc.EI)
    return np.hypot(res.x - s, res.y - y) / sc.length


def cantilever(plan: Plan, out: Output) -> dict:
    """Sec. III-G: the tip reaction and the deflection against beam theory (eqs. 33–37)."""
    n = PAPER["cantilever"]["links"]  # cheap: the paper's N in both modes
    ours = cantilever_validation(n, tol=1e-10)
    sc = CantileverScene(links=n)
    theory = sc.theory_force()
    paper_like = solve(PaperLikeCantilever(links=n), tol=1e-10)
    free_sc = CantileverScene(links=n, height=1e3)  # a wall no node can reach: Fig. 10(a)
    free = solve(free_sc, tol=1e-10)
    free_pl = solve(PaperLikeCantilever(links=n, height=1e3), tol=1e-10)
    held = solve(sc, tol=1e-10)
    forces = [solve(CantileverScene(links=k), tol=1e-11).total_force
              for k in plan.cantilever_links]
    forces_pl = [solve(PaperLikeCantilever(links=k), tol=1e-11).total_force
                 for k in plan.cantilever_links]
    d_free, d_free_pl = _beam_distance(free, free_sc), _beam_distance(free_pl, free_sc)
    d_held = _beam_distance(held, sc, theory)
    data = {
        "links": n, "load": sc.load, "height": sc.height, "EI": sc.EI, "length": sc.length,
        "theory_force": theory, "model_force": ours["model_force"],
        "relative_error": ours["relative_error"], "contact_nodes": ours["contact_nodes"],
        "converged": ours["converged"] and paper_like.converged and free.converged,
        "paper_like_force": paper_like.total_force,
        "paper_like_relative_error": (paper_like.total_force - theory) / theory,
        "paper_rounded_difference": (round(1e3 * paper_like.total_force, 1)
                                     - round(1e3 * theory, 1)) / round(1e3 * theory, 1),
        "free_tip_deflection": float(free.y[-1]),
        "free_tip_theory": float(sc.theory_deflection(np.array(sc.length))),
        "free_max_distance": float(d_free.max()),
        "free_max_distance_paper_like": float(d_free_pl.max()),
        "held_max_distance": float(d_held.max()),
        "held_max_y": float(held.y.max()),
        "order_links": list(plan.cantilever_links), "order_forces": forces,
        "order": observed_order(list(plan.cantilever_links), forces),
        "order_forces_paper_like": forces_pl,
        "order_paper_like": observed_order(list(plan.cantilever_links), forces_pl),
    }
    s = np.arange(n + 1) * sc.length / n
    rows = [{"node": i + 1, "s": s[i], "x_free": free.x[i], "y_free": free.y[i],
             "y_free_theory": sc.theory_deflection(s[i]), "distance_free": d_free[i],
             "x_free_paper_like": free_pl.x[i], "y_free_paper_like": free_pl.y[i],
             "x_held": held.x[i], "y_held": held.y[i],
             "y_held_theory": float(sc.theory_deflection(s[i])
                                    - theory * s[i] ** 2 * (3 * sc.length - s[i]) / (6 * sc.EI)),
             "distance_held": d_held[i]}
            for i in range(n + 1)]
    out.csv("fig10-cantilever.csv", rows)
    out.json("fig10-cantilever.json", data)
    plot_cantilever(rows, data, out.path("fig10-cantilever.png"))
    return data


# -- Fig. 24 --------------------------------------------------------------------------------------
def onset_theta(height: float, length: float = DEFAULT_LENGTH) -> float:
    """θ (deg) at which the weightless continuous arc first reaches the wall: r(1 − cos θ/2) = h."""
    def rise(t):
        return length / t * (1 - math.cos(t / 2)) - height

    return math.degrees(brentq(rise, 1e-6, math.pi))


def fig24_pressure(plan: Plan, out: Output) -> dict:
    """Model force against pressure for actuators 1–3 in the paper's channel (Fig. 24, top).

    The fixture holds the actuator between two plates 2h apart (Sec. IV-C, Fig.
    14(b) H), so the scene is a channel. The band is bounded by the measured
    extremes of Sec. V-E: force rises with EI and falls with w (the weight
    pulls away from the wall), so (EI_min, w_max) and (EI_max, w_min) are the
    lower and upper edges; the four corners are in the CSV to show it.
    """
    pressures = np.linspace(*PAPER_PRESSURE_RANGE, plan.fig24_pressures)
    corners = {"lo": (PAPER_EI_RANGE[0], PAPER_WEIGHT_RANGE[1]),
               "hi": (PAPER_EI_RANGE[1], PAPER_WEIGHT_RANGE[0]),
               "min_min": (PAPER_EI_RANGE[0], PAPER_WEIGHT_RANGE[0]),
               "max_max": (PAPER_EI_RANGE[1], PAPER_WEIGHT_RANGE[1])}
    rows, onset = [], []
    for act in ("1", "2", "3"):
        cal = get_calibration(act)
        for h in sorted(COMPARISON_PRESSURE_RANGES):
            for p in pressures:
                scene = scene_from_pressure(float(p), act, h, channel=True, links=plan.links)
                res = model_solve(scene)
                row = {"actuator": act, "height": h, "pressure_kpa": float(p),
                       "pressure_psi": float(p) / KPA_PER_PSI, "theta": scene.theta,
                       "total_force": res.total_force,
                       "lower_wall_force": float(np.sum(res.forces_lower)),
                       "converged": res.converged}
                for name, (ei, w) in corners.items():
                    r = model_solve(replace(scene, EI=ei, weight=w))
                    row[f"force_{name}"] = r.total_force
                    row["converged"] = row["converged"] and r.converged
                rows.append(row)
            th = onset_theta(h)
            p_on = (th - cal.intercept) / cal.slope
            mine = [r for r in rows if r["actuator"] == act and r["height"] == h]
            first = next((r["pressure_kpa"] for r in mine if r["total_force"] > 0), None)
            top = mine[-1]
            knee = COMPARISON_PRESSURE_RANGES[h][0]
            at_knee = model_solve(scene_from_pressure(knee, act, h, channel=True, links=plan.links))
            t_knee = math.radians(at_knee.scene.theta)
            onset.append({"actuator": act, "height": h, "onset_theta": th,
                          "length_for_contact_at_knee": h * t_knee / (1 - math.cos(t_knee / 2)),
                          "onset_pressure_kpa": p_on, "first_contact_on_grid_kpa": first,
                          "knee_kpa": knee, "force_at_knee": at_knee.total_force,
                          "theta_at_knee": at_knee.scene.theta,
                          "force_at_max_pressure": top["total_force"],
                          "band_at_max_pressure": (top["force_lo"], top["force_hi"]),
                          "theta_at_max_pressure": top["theta"]})
    data = {"links": plan.links, "length": DEFAULT_LENGTH, "channel": True,
            "corners": corners, "onset": onset,
            "all_converged": all(r["converged"] for r in rows),
            "lower_wall_touched": any(r["lower_wall_force"] > 0 for r in rows),
            "max_force": max(r["total_force"] for r in rows)}
    out.csv("fig24-force-pressure.csv", rows)
    out.json("fig24-force-pressure.json", data)
    plot_fig24(rows, data, out.path("fig24-force-pressure.png"))
    return data


