"""The whole anchoring actuator against the paper's single-section model (issue 17, item 1).

The paper models only the middle section of its 3-section actuator, pinned
at both ends on the mid-line of the channel (Sec. IV-C: "the two end bending
sections created a symmetric environment for the middle bending section").
This study solves the whole actuator
(:func:`~lcpbench.problems.sections.anchoring_actuator`: three sections,
pins at the two barbed fittings) at the paper's heights and pressures and
sets the middle section beside the single-section model:

* the middle section's force on the upper wall (the load cell) against the
  single section's total force (the paper's model, weight away from the wall)
  and against the single section with the same weight direction;
* its shape against the single section's (node for node: both have 140 links
  over 30 mm), and where its ends are: the heights of the two inflection
  nodes (the single model holds them on y = 0) and the bending moment there
  (zero at a pin);
* whether each section touches its wall: the knee points of Sec. V-C are,
  in the paper's reading, where all three sections are in contact.

The self-weight is taken both ways: away from the load cell (``gravity="-y"``,
the paper's eqs. 3 and 8) and toward it (``gravity="+y"``, what the paper's
Sec. V-C text suggests happened in the fixture: "gravity causing the actuator
to contact the load cell").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..api import solve
from ..model.chain import joint_angles
from ..problems.calibrations import scene_from_pressure
from ..problems.sections import Section, SectionedScene, anchoring_actuator

#: driver tolerance of the study (rad): the comparison is of models, not of truncation
TOL = 1e-8
#: a wall "is touched" when its reaction exceeds this (N): 1e-3 gf, far below any measurement
TOUCH = 1e-8
GRAVITIES = ("-y", "+y")


@dataclass(frozen=True)
class SectionState:
    """One section of a solved row: its wall force and whether it touches a wall."""

    upper: float  # reaction of the upper wall on the section's nodes (N)
    lower: float  # reaction of the lower wall (N)

    @property
    def touches(self) -> bool:
        return self.upper > TOUCH or self.lower > TOUCH


def section_states(scene: SectionedScene, res) -> list[SectionState]:
    """The wall forces on each section's nodes, boundary nodes included in both neighbours."""
    up = np.concatenate(([0.0], res.forces, [0.0]))
    lo = (np.concatenate(([0.0], res.forces_lower, [0.0])) if res.forces_lower is not None
          else np.zeros_like(up))
    return [SectionState(float(up[a:b + 1].sum()), float(lo[a:b + 1].sum()))
            for a, b in scene.section_nodes()]


def _boundary_moments(scene: SectionedScene, res) -> tuple[float, float]:
    """The spring moments k(φ − φ*) at the two inflection nodes (N·mm; 0 at a pin)."""
    chain = scene.chain()
    m = chain.joint_stiffness * (joint_angles(chain, np.asarray(res.alpha)) - chain.rest_joint)
    (_, b0), (_, b1), _ = scene.section_nodes()
    return float(m[b0 - 1]), float(m[b1 - 1])  # joint j sits at node j + 1


def compare(actuator: str, height: float, pressure: float, *, links: int = 140,
            gravity: str = "-y") -> dict:
    """One row: the single-section model and the whole actuator at one pressure.

    ``links`` per section (the paper's 140). Forces in N, lengths in mm.
    """
    single_scene = scene_from_pressure(pressure, actuator, height, channel=True, links=links)
    single = solve(single_scene, tol=TOL)
    scene = anchoring_actuator(single_scene.theta, height, links=3 * links, gravity=gravity)
    whole = solve(scene, tol=TOL)
    states = section_states(scene, whole)
    (_, b0), (_, b1), _ = scene.section_nodes()
    x, y = np.asarray(whole.x), np.asarray(whole.y)
    xm, ym = x[b0:b1 + 1], y[b0:b1 + 1]
    xs, ys = np.asarray(single.x), np.asarray(single.y)
    # align the section centres in x (the walls fix y): node-for-node distance
    dx = (xm - 0.5 * (xm[0] + xm[-1])) - (xs - 0.5 * (xs[0] + xs[-1]))
    distance = np.hypot(dx, ym - ys)
    m0, m1 = _boundary_moments(scene, whole)
    mid = states[1].upper
    same = single.total_force  # the single section with the same weight direction
    if gravity != "-y":  # (one section: the ActuatorScene's chain for "-y", tests)
        one = SectionedScene(sections=[Section(single_scene.theta)], height=height,
                             links=links, channel=True, gravity=gravity)
        same = solve(one, tol=TOL).total_force
    return {
        "actuator": actuator, "height": height, "pressure_kpa": pressure,
        "theta": single_scene.theta, "gravity": gravity,
        "single_force": single.total_force,
        "middle_force": mid,
        "difference": mid - single.total_force,
        "relative_difference": (mid - single.total_force) / mid if mid > 0 else math.nan,
        "single_force_same_weight": same,
        "difference_same_weight": mid - same,
        "end_forces": states[0].lower + states[2].lower,
        "middle_touches": states[1].upper > TOUCH,
        "ends_touch": states[0].lower > TOUCH and states[2].lower > TOUCH,
        "all_touch": states[1].upper > TOUCH and states[0].lower > TOUCH
        and states[2].lower > TOUCH,
        "inflection_height": 0.5 * (ym[0] + ym[-1]),
        "inflection_moment": 0.5 * (m0 + m1),
        "middle_span": float(xm[-1] - xm[0]), "single_span": float(xs[-1] - xs[0]),
        "shape_distance_max": float(distance.max()),
        "shape_distance_percent": float(100 * distance.max() / single_scene.length),
        "converged": bool(single.converged and whole.converged),
        "whole_force_upper": whole.total_force,
    }


def all_touch_pressure(actuator: str, height: float, *, links: int = 140, gravity: str = "-y",
                       xtol: float = 0.05) -> float:
    """The smallest pressure (kPa) at which all three sections touch their walls.

    Bisection in pressure over the calibration's range (0-172.37 kPa); NaN if
    they never all touch in it, 0 if they already do at 0 kPa.
    """
    def state(p: float) -> float:
        return 1.0 if compare(actuator, height, p, links=links, gravity=gravity)["all_touch"] \
            else -1.0

    lo, hi = 0.0, 172.37
    if state(hi) < 0:
        return math.nan
    if state(lo) > 0:
        return 0.0
    while hi - lo > xtol:
        mid = 0.5 * (lo + hi)
        if state(mid) > 0:
            hi = mid
        else:
            lo = mid
    return hi


def single_contact_pressure(actuator: str, height: float, *, links: int = 140) -> float:
    """The pressure (kPa) at which the single-section model first pushes on the wall."""
    def force(p: float) -> float:
        scene = scene_from_pressure(p, actuator, height, channel=True, links=links)
        return solve(scene, tol=TOL).total_force - TOUCH

    lo, hi = 0.0, 172.37
    if force(hi) <= 0:
        return math.nan
    if force(lo) > 0:
        return 0.0
    return float(brentq(force, lo, hi, xtol=0.05))

