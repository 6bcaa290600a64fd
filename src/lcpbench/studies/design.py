"""Inverse queries: the bend angle (or pressure) for a force, the height of first touch.

Issue 38, item 2. :func:`design` answers one of

- ``max_force=F``: the largest θ (or pressure, with a calibration) in the searched range
  whose total force (``peak=True``: peak contact pressure per length) stays ≤ F;
- ``min_force=F``: the smallest θ whose force reaches at least F (anchoring);
- ``touch=True``: the wall height at which the actuator, at its θ, first touches the
  wall (the highest node of its wall-free equilibrium).

The force queries are a root of q(θ) − F, q the total force (or peak pressure) of a
forward solve at θ (tol 1e-10 by default, each solve started from the nearest answer
so far), found by safeguarded Newton with bracketing: the scene's θ is solved first,
and the range's far end only where the crossing lies beyond it; then a Newton step
from the solved end of the bracket nearest the target, with dq/dθ from
:func:`lcpbench.sensitivities` (one face solve), taken where it lands strictly inside
the bracket and the derivative is positive, else the secant through both ends, else
the bracket is bisected. It is robust across contact-set changes
(the derivative is one-sided there, and the bracket holds) and force plateaus (no
contact: q = 0, dq/dθ = 0, a bisection). q is assumed to cross F once in the range
(it grows with θ for an actuator pressed against a wall); the answer is the crossing
found, checked by its own forward solve, and a solve 0.01° beyond it shows the limit
passed. The result says how many forward solves it took.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..api import check_tol, solve
from ..errors import ProblemError
from ..model.result import ContactResult
from ..model.sensitivity import sensitivities
from ..problems.calibrations import Calibration
from ..problems.scenes import ActuatorScene

#: the bend angles searched without a calibration (deg): lcpbench's cold start converges
#: up to 180° (past it the loading path answers, at many solves)
THETA_RANGE = (1.0, 180.0)
#: relative accuracy of the force at the answer (of the target F)
FORCE_RTOL = 1e-6
#: the step beyond the answer that shows the limit passed (deg)
BEYOND_DEG = 0.01
MAX_SOLVES = 40
#: the wall height of a wall-free solve (mm): no node of an actuator reaches it
FAR = 1e6


@dataclass
class DesignResult:
    """The answer of an inverse query.

    ``query``: "max_force", "min_force" or "touch"; ``theta_deg``: the bend angle found
    (the scene's, for touch); ``pressure``: the pressure (the calibration's unit) when a
    calibration was given, else None; ``value``: the total force (N) or, with ``peak``,
    the peak contact pressure (N/mm) at the answer; for touch, ``height_mm`` the
    height of first contact; ``result``: the forward solve at the answer; ``beyond``:
    the value one step of :data:`BEYOND_DEG` further (max_force: up; min_force: down;
    touch: the force with the wall 1e-6 of the height lower); ``solves``: forward solves
    taken (the check beyond included)."""

    query: str
    theta_deg: float
    pressure: float | None
    value: float
    result: ContactResult
    beyond: float
    solves: int
    peak: bool = False
    height_mm: float | None = None

    def as_json(self) -> dict:
        out = {"query": self.query, "theta_deg": self.theta_deg,
               "total_force": self.result.total_force, "solves": self.solves,
               "converged": self.result.converged}
        if self.pressure is not None:
            out["pressure_kpa"] = self.pressure
        if self.peak:
            out["peak_pressure"] = self.value
        if self.height_mm is not None:
            out["height_mm"] = self.height_mm
        out["beyond"] = self.beyond
        return out


def design(scene: ActuatorScene, *, max_force: float | None = None,
           min_force: float | None = None, touch: bool = False, peak: bool = False,
           calibration: Calibration | None = None, tol: float = 1e-10) -> DesignResult:
    """One inverse query on ``scene`` (its walls, N, EI, w, ℓ; its θ is the start, or the
    bend angle for ``touch``). ``calibration``: search the pressure over its range
    (θ = slope P + intercept) and report it; else θ over :data:`THETA_RANGE`."""
    asked = [q for q, on in (("max_force", max_force is not None),
                             ("min_force", min_force is not None), ("touch", touch)) if on]
    if len(asked) != 1:
        raise ProblemError("design needs exactly one of max_force, min_force or touch; got "
                           + (", ".join(asked) if asked else "none"))
    if not isinstance(scene, ActuatorScene):
        raise ProblemError(f"design covers actuator scenes (flat walls, one wall or a "
                           f"channel, rigid or elastic, or a wall profile); got "
                           f"{type(scene).__name__}")
    if touch and scene.wall_profile is not None:
        raise ProblemError("design --touch finds the height of a flat wall; this scene has "
                           "a wall profile (its max_force and min_force queries are covered)")
    tol = check_tol(tol)
    if touch:
        return _touch(scene, tol, calibration)
    target = float(max_force if max_force is not None else min_force)
    if not (math.isfinite(target) and target > 0):
        name = "max_force" if max_force is not None else "min_force"
        raise ProblemError(f"{name} must be a force > 0 N (finite), got {target!r}")
    lo, hi = calibration.theta_range if calibration is not None else THETA_RANGE
    lo, hi = max(lo, THETA_RANGE[0] / 10), min(hi, 360.0)
    return _crossing(scene, target, asked[0], peak, calibration, tol, lo, hi)


class _Forward:
    """q(θ) by forward solves, each started from the nearest answer so far."""

    def __init__(self, scene, peak: bool, tol: float):
        self.scene, self.peak, self.tol = scene, peak, tol
        self.done: dict[float, ContactResult] = {}

    def __call__(self, theta: float) -> tuple[float, ContactResult]:
        if theta in self.done:
            return self.value(self.done[theta]), self.done[theta]
        near = min(self.done, key=lambda t: abs(t - theta), default=None)
        start = self.done[near] if near is not None and self.done[near].converged else None
        res = solve(dataclasses.replace(self.scene, theta=theta), tol=self.tol, start=start)
        if not res.converged:
            raise ProblemError(f"design: the forward solve at theta = {theta:.6g} deg did not "
                               f"converge ({res.reason})")
        self.done[theta] = res
        return self.value(res), res

    def value(self, res: ContactResult) -> float:
        return float(res.max_pressure if self.peak else res.total_force)

    def slope(self, res: ContactResult) -> float:
        s = sensitivities(res, wrt=("theta_deg",))
        return s.peak_pressure["theta_deg"] if self.peak else s.total_force["theta_deg"]


def _crossing(scene, target: float, query: str, peak: bool, calibration, tol: float,
              lo: float, hi: float) -> DesignResult:
    q = _Forward(scene, peak, tol)
    what = "peak contact pressure" if peak else "total force"
    unit = "N/mm" if peak else "N"
    upper = query == "max_force"  # the answer: a (q ≤ F) for max_force, b (q ≥ F) for min
    aim = target * (1 - 0.5 * FORCE_RTOL if upper else 1 + 0.5 * FORCE_RTOL)
    # the bracket [a, b], q(a) ≤ F < q(b); a value None: not solved yet (q crosses F once,
    # so an end is only solved where it is needed)
    t0 = min(max(scene.theta, lo), hi)
    q0, _ = q(t0)
    if q0 <= target:
        a, qa, b, qb = t0, q0, hi, None
        if t0 != hi:
            qb, _ = q(hi)
        if qb is None or qb <= target:
            if query == "min_force":
                raise ProblemError(f"min_force {target:g} {unit}: no bend angle in [{lo:g}, "
                                   f"{hi:g}] deg reaches it (the largest {what} found is "
                                   f"{q.value(q.done[hi]):.6g} {unit} at {hi:g} deg)")
            return _answer(q, query, hi, q.done[hi], q.value(q.done[hi]), calibration, peak,
                           beyond=math.nan)
    else:
        a, qa, b, qb = lo, None, t0, q0
    for _ in range(MAX_SOLVES):
        near = (target - qa) if upper and qa is not None else \
            (qb - target) if not upper and qb is not None else math.inf
        if near <= FORCE_RTOL * target:  # the answer's own end, within 1e-6 of F
            break
        if b - a <= 1e-12 * max(1.0, b):  # a jump of q across F: the bracket is the answer
            if qa is None:
                qa, _ = q(a)
            break
        new = _next(q, aim, a, qa, b, qb)
        qn, _ = q(new)
        if qn <= target:
            a, qa = new, qn
        else:
            b, qb = new, qn
    else:
        raise ProblemError(f"design: no answer to 1e-6 in {MAX_SOLVES} solves")
    if qa is not None and qa > target:  # (the bracket closed on lo: q(lo) > F)
        raise ProblemError(f"{query} {target:g} {unit}: the {what} is already {qa:.6g} "
                           f"{unit} at the smallest bend angle searched, {lo:g} deg")
    theta = a if query == "max_force" else b
    res = q.done[theta]
    step = BEYOND_DEG if query == "max_force" else -BEYOND_DEG
    beyond, _ = q(theta + step)
    return _answer(q, query, theta, res, q.value(res), calibration, peak, beyond)


def _next(q, aim: float, a: float, qa, b: float, qb) -> float:
    """The next θ inside (a, b): a Newton step (dq/dθ from the sensitivities) from the
    solved end nearest the target whose slope is positive, where it lands strictly
    inside (where it lands beyond a not yet solved: a itself); else the secant through
    both ends; else the bracket's midpoint."""
    ends = sorted(((abs(v - aim), t, v) for t, v in ((a, qa), (b, qb)) if v is not None))
    for _, t, v in ends:
        slope = q.slope(q.done[t])
        new = t - (v - aim) / slope if slope > 0 else math.nan
        if math.isfinite(new) and a < new < b:
            return new
        if qa is None and math.isfinite(new) and new <= a:  # beyond the unsolved end
            return a
        if v > 0:  # a slope at a contact point that overshoots: the secant next
            break
    if qa is not None and qb is not None and qb > qa:
        new = a + (aim - qa) * (b - a) / (qb - qa)
        if a < new < b:
            return new
    return 0.5 * (a + b)


def _answer(q, query, theta, res, value, calibration, peak, beyond) -> DesignResult:
    pressure = float(calibration.pressure(theta)) if calibration is not None else None
    return DesignResult(query, float(theta), pressure, float(value), res, float(beyond),
                        len(q.done), peak)


def _touch(scene: ActuatorScene, tol: float, calibration) -> DesignResult:
    """The highest node of the wall-free equilibrium, checked by solves just below it."""
    free = solve(dataclasses.replace(scene, height=FAR, channel=False), tol=tol)
    if not free.converged:
        raise ProblemError(f"design --touch: the wall-free solve did not converge "
                           f"({free.reason})")
    nodes = scene.chain().free_nodes
    top = float(max(free.y[i] for i in nodes))
    if not top > 0:
        raise ProblemError(f"design --touch: the actuator at theta = {scene.theta:g} deg "
                           f"does not rise above its pins (highest node {top:.3g} mm)")
    at = solve(dataclasses.replace(scene, height=top * (1 + 1e-9)), tol=tol, start=free)
    below = solve(dataclasses.replace(scene, height=top * (1 - 1e-6)), tol=tol, start=free)
    pressure = float(calibration.pressure(scene.theta)) if calibration is not None else None
    return DesignResult("touch", float(scene.theta), pressure, float(at.total_force), at,
                        float(below.total_force), 3, False, top)


__all__ = ["DesignResult", "design"]
