"""The whole-actuator study: Fig. 24's scenes with all three sections (issue 17, item 1).

``lcpbench anchoring [--out DIR] [--quick]`` (or :func:`anchoring_study`)
solves the scenes of the ``fig24`` stage (actuators 1-3, h = 4.5, 5.5,
6.5 mm, 0-172.37 kPa, the paper's channel) twice: with the paper's
single-section model and with the whole 3-section actuator
(:mod:`lcpbench.studies.anchoring`), the weight both ways. It writes, into
``DIR`` (default ``results/anchoring-run``, not tracked; the committed copy is
regenerated only with ``--out results/anchoring``), through
:class:`~lcpbench.paper.output.Output` (a file is replaced only when its
numbers changed beyond round-off):

``anchoring.csv``               one row per (actuator, h, P, weight direction)
``anchoring-contact.csv``       per (actuator, h): the single model's contact
                                pressure, the whole actuator's all-touch pressure,
                                the paper's knee
``anchoring.json``              the summary the README quotes
``README.md``                   the tables and what they say
``anchoring-force-pressure.png`` force against pressure per h: single section,
                                whole actuator (both weights), the paper's knee
                                and its ~1 gf low-pressure forces
``anchoring-shapes.png``        the whole actuator in the channel, the single
                                section drawn over its middle section
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from ..api import solve
from ..problems.calibrations import (
    COMPARISON_PRESSURE_RANGES,
    PAPER_PRESSURE_RANGE,
    scene_from_pressure,
)
from ..problems.sections import anchoring_actuator
from ..studies.anchoring import GRAVITIES, TOL, all_touch_pressure, compare, single_contact_pressure
from .anchoring_plots import plot_force_pressure, plot_shapes
from .data import FULL, GF, PAPER, QUICK
from .markdown import md_table, num
from .output import Output

DEFAULT_OUT = Path("results") / "anchoring-run"
ACTUATORS = ("1", "2", "3")
#: the scene of the shape figure (the paper's illustrative sample, Fig. 22: actuator 1,
#: h = 5.5 mm) at these pressures (kPa)
SHAPE_SCENE = ("1", 5.5)
SHAPE_PRESSURES = (60.0, 100.0, 137.9, 172.37)


def _rows(plan) -> list[dict]:
    pressures = np.linspace(*PAPER_PRESSURE_RANGE, plan.fig24_pressures)
    rows = []
    for act in ACTUATORS:
        for h in sorted(COMPARISON_PRESSURE_RANGES):
            for p in pressures:
                for g in GRAVITIES:
                    rows.append(compare(act, h, float(p), links=plan.links, gravity=g))
    return rows


def _contact(plan) -> list[dict]:
    out = []
    for act in ACTUATORS:
        for h in sorted(COMPARISON_PRESSURE_RANGES):
            row = {"actuator": act, "height": h,
                   "paper_knee_kpa": PAPER["fig24"]["knee_kpa"][h],
                   "single_contact_kpa": single_contact_pressure(act, h, links=plan.links)}
            for g in GRAVITIES:
                row[f"all_touch_kpa_{g}"] = all_touch_pressure(act, h, links=plan.links,
                                                               gravity=g)
            out.append(row)
    return out


def _ends(plan) -> list[dict]:
    """The paper's comparison range per h (Sec. V-C): both ends, every actuator and weight."""
    rows = []
    for h, (lo, hi) in sorted(COMPARISON_PRESSURE_RANGES.items()):
        for end, p in (("low", lo), ("high", hi)):
            for act in ACTUATORS:
                for g in GRAVITIES:
                    r = compare(act, h, p, links=plan.links, gravity=g)
                    r["end"] = end
                    rows.append(r)
    return rows


def _summary(rows: list[dict], contact: list[dict], ends: list[dict]) -> dict:
    touching = [r for r in rows if r["all_touch"]]
    below = [r for r in rows if not r["all_touch"] and r["gravity"] == "+y"]
    offsets = {g: [r["difference"] for r in touching if r["gravity"] == g] for g in GRAVITIES}
    same = {g: [r["difference_same_weight"] for r in touching if r["gravity"] == g]
            for g in GRAVITIES}

    def err(end: str, g: str) -> dict:
        """Mean |single − whole| / single over the range end (%), where the single model
        has a force (the paper's error was (theory − experiment) / theory)."""
        vals = [abs(r["single_force"] - r["middle_force"]) / r["single_force"]
                for r in ends if r["end"] == end and r["gravity"] == g and r["single_force"] > 0]
        return {"percent": 100 * float(np.mean(vals)) if vals else math.nan,
                "scenes": len(vals)}

    return {
        "scenes": len(rows), "all_converged": all(r["converged"] for r in rows),
        "above_all_touch": {
            "inflection_height_max_mm": max(abs(r["inflection_height"]) for r in touching),
            "inflection_moment_max_Nmm": max(abs(r["inflection_moment"]) for r in touching),
            "shape_distance_max_percent": max(r["shape_distance_percent"] for r in touching),
            "middle_minus_single_mN": {g: [1e3 * min(v), 1e3 * max(v)]
                                       for g, v in offsets.items()},
            "middle_minus_single_same_weight_mN": {g: [1e3 * min(v), 1e3 * max(v)]
                                                   for g, v in same.items()},
        },
        "below_all_touch_gravity_+y": {
            "middle_force_mN": [1e3 * min(r["middle_force"] for r in below),
                                1e3 * max(r["middle_force"] for r in below)] if below else None,
            "single_force_max_mN": 1e3 * max((r["single_force"] for r in below), default=0.0),
        },
        "contact_pressures": contact,
        "range_ends_error_percent": {g: {"low": err("low", g), "high": err("high", g)}
                                     for g in GRAVITIES},
        "paper_error_percent": {"low": PAPER["fig24"]["error_low_percent"],
                                "high": PAPER["fig24"]["error_high_percent"]},
        "gram_force_N": GF,
    }


def anchoring_study(out_dir: str | os.PathLike = DEFAULT_OUT, *, quick: bool = False) -> dict:
    """Run the study and write its files into ``out_dir``; returns the summary and file lists.

    ``quick``: the reproduce run's coarse plan (6 pressures, N = 40 per section),
    for the tests.
    """
    plan = QUICK if quick else FULL
    out = Output(Path(out_dir))
    try:
        rows = _rows(plan)
        contact = _contact(plan)
        ends = _ends(plan)
        summary = _summary(rows, contact, ends)
        summary["links_per_section"] = plan.links
        summary["quick"] = quick
        out.csv("anchoring.csv", rows)
        out.csv("anchoring-contact.csv", contact)
        out.csv("anchoring-range-ends.csv", ends)
        out.json("anchoring.json", summary)
        plot_force_pressure(rows, contact, out.path("anchoring-force-pressure.png"))
        plot_shapes(_shape_cases(plan.links), out.path("anchoring-shapes.png"))
        out.path("README.md").write_text(_readme(summary, ends))
    finally:
        out.finish()
    return {"out": str(out_dir), "written": out.written, "unchanged": out.unchanged,
            "summary": summary}


def _shape_cases(links: int) -> list[dict]:
    act, h = SHAPE_SCENE
    cases = []
    for p in SHAPE_PRESSURES:
        single = scene_from_pressure(p, act, h, channel=True, links=links)
        whole = anchoring_actuator(single.theta, h, links=3 * links)
        rs, rw = solve(single, tol=TOL), solve(whole, tol=TOL)
        cases.append({"pressure": p, "theta": single.theta, "height": h, "actuator": act,
                      "whole_x": rw.x, "whole_y": rw.y, "single_x": rs.x, "single_y": rs.y,
                      "nodes": whole.section_nodes(), "single_force": rs.total_force,
                      "whole_force": float(np.sum(rw.forces[links - 1:2 * links]))})
    return cases


def _readme(s: dict, ends: list[dict]) -> str:
    above = s["above_all_touch"]
    head = ["h (mm)", "actuator", "single model touches (kPa)",
            "all 3 sections touch, w away / toward (kPa)", "paper's knee (kPa)"]
    contact = [[f"{c['height']:g}", c["actuator"], num(c["single_contact_kpa"], ".4g"),
                f"{num(c['all_touch_kpa_-y'], '.4g')} / {num(c['all_touch_kpa_+y'], '.4g')}",
                f"{c['paper_knee_kpa']:g}"] for c in s["contact_pressures"]]
    ehead = ["h (mm)", "end", "P (kPa)", "actuator", "θ (°)", "single (mN)",
             "whole, w away (mN)", "whole, w toward (mN)", "all touch"]
    erows = []
    for r in ends:
        if r["gravity"] != "-y":
            continue
        twin = next(q for q in ends if q["gravity"] == "+y" and q["end"] == r["end"]
                    and q["actuator"] == r["actuator"] and q["height"] == r["height"])
        erows.append([f"{r['height']:g}", r["end"], f"{r['pressure_kpa']:g}", r["actuator"],
                      f"{r['theta']:.1f}", f"{1e3 * r['single_force']:.2f}",
                      f"{1e3 * r['middle_force']:.2f}", f"{1e3 * twin['middle_force']:.2f}",
                      "yes" if r["all_touch"] else "no"])
    off = above["middle_minus_single_mN"]
    same = above["middle_minus_single_same_weight_mN"]
    err = s["range_ends_error_percent"]
    below = s["below_all_touch_gravity_+y"]
    low = (f"{below['middle_force_mN'][0]:.1f}-{below['middle_force_mN'][1]:.1f} mN"
           if below["middle_force_mN"] else "none")
    return f"""# The whole anchoring actuator beside the paper's single-section model

Written by `lcpbench anchoring --out results/anchoring` ({s['scenes']} rows: Fig. 24's
scenes, actuators 1-3, h = 4.5/5.5/6.5 mm, 0-172.37 kPa, each solved with the
single-section model and with the whole 3-section actuator, the weight acting
away from the load cell (the paper's model, "w away") and toward it ("w toward");
N = {s['links_per_section']} per section; all converged: {s['all_converged']}).
The fixture's reading is in docs/sections.md.

![force against pressure](anchoring-force-pressure.png)

## When do the sections touch?

{md_table(head, contact)}

## Where the pinned-pinned assumption holds: once all three sections touch

- the inflection nodes (the single model's pins) stay within
  {above['inflection_height_max_mm']:.3g} mm of the mid-line, with a bending moment of at most
  {above['inflection_moment_max_Nmm']:.3g} N·mm there (0 at a pin);
- the middle section's shape is the single section's to
  {above['shape_distance_max_percent']:.3g} % of 30 mm (largest node distance);
- its force is the single model's plus a near-constant offset:
  {off['-y'][0]:.2f} to {off['-y'][1]:.2f} mN with the weight away from the load cell,
  {off['+y'][0]:.2f} to {off['+y'][1]:.2f} mN with the weight toward it
  (1 gf = 9.81 mN). Against a single section with the same weight direction
  the offset is {same['-y'][0]:.2f} to {same['-y'][1]:.2f} mN (away) and
  {same['+y'][0]:.2f} to {same['+y'][1]:.2f} mN (toward): the share of the end
  sections' weight that the middle section carries. The rest of the "toward"
  offset is the direction of the weight alone (the paper's model pulls away
  from the load cell; its Sec. V-C text says gravity pushed the actuator onto it).

## Where it does not: below the knee

The 90 mm actuator sags under its own weight onto one wall before its
sections reach the walls by bending: with the weight toward the load cell the
middle section presses on it with {low} where the single model
gives at most {below['single_force_max_mN']:.2f} mN, the paper's "nonzero forces ... below the
knee point" of about 1 gf; with the weight away from it the middle section
does not touch at all and the end sections lie on the lower wall.

## The paper's comparison range (Sec. V-C), at its two ends

{md_table(ehead, erows)}

Mean |single − whole| / single over the scenes where the single model has a
force: {_err(err['-y']['low'])} at the low ends and {_err(err['-y']['high'])} at the high
ends (weight away), {_err(err['+y']['low'])} and {_err(err['+y']['high'])} (weight toward); the
paper's force error was {s['paper_error_percent']['low']:g} % and
{s['paper_error_percent']['high']:g} % (model against experiment). At the low ends the
calibrated single model of most actuators does not touch yet, so few scenes count there.

"""


def _err(e: dict) -> str:
    return f"{e['percent']:.1f} % ({e['scenes']} scenes)"
