"""Continuation: solve a line of scenes, each starting from its neighbours' answers.

Along a line in θ (or in h) the equilibrium moves smoothly, so the answer of
the previous scene, or better the straight-line extrapolation through the
previous two (a secant predictor), is a much closer first iterate than the
clipped unconstrained arc. The globalised driver clips the prediction to the
walls and line-searches on the exact energy from there, so the answer is the
same equilibrium; only the path to it is shorter.

Measured on the paper grid with the active set (``benchmarks/warm_sweep.py``,
``results/warm-sweep.md``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from ..api import solve
from ..errors import ProblemError
from ..model.result import ContactResult
from ..problems.scenes import ActuatorScene

PREDICTORS = ("quadratic", "secant", "previous", "none")
#: answers each predictor extrapolates through (polynomial degree + 1)
_POINTS = {"quadratic": 3, "secant": 2, "previous": 1}


def _step(a: ActuatorScene, b: ActuatorScene) -> tuple[str, float] | None:
    """The one parameter (theta or height) that changes from a to b, and by how much."""
    same = replace(b, theta=a.theta, height=a.height) == a
    if not same:
        return None
    if a.theta != b.theta and a.height == b.height:
        return "theta", b.theta - a.theta
    if a.height != b.height and a.theta == b.theta:
        return "height", b.height - a.height
    return None


def _line_points(history, scene, most: int):
    """The last solved scenes on the same line as ``scene`` (newest first, at most
    ``most``, all converged, the same parameter moving between each), and that
    parameter (None: only the newest, or nothing)."""
    s1, r1 = history[-1]
    d = _step(s1, scene)
    if not r1.converged or r1.links != scene.links or d is None:
        return [], None
    param, pts = d[0], [(s1, r1)]
    for s, r in reversed(history[:-1]):
        if len(pts) == most:
            break
        d = _step(s, pts[-1][0])
        if not r.converged or d is None or d[0] != param or d[1] == 0:
            break
        pts.append((s, r))
    return pts, param


def predict(history: list[tuple[ActuatorScene, ContactResult]], scene: ActuatorScene,
            predictor: str = "quadratic") -> ContactResult | None:
    """A start for ``scene`` from the solved scenes before it (None: start cold).

    "previous": the last answer. "secant" and "quadratic": the polynomial
    through the last two or three answers on the line (Lagrange, in the
    moving parameter, unequal steps allowed), evaluated at ``scene``; fewer
    points where the line has fewer.
    """
    if predictor == "none" or not history:
        return None
    pts, param = _line_points(history, scene, _POINTS[predictor])
    if not pts:
        return None
    r1 = pts[0][1]
    if len(pts) == 1:
        return r1
    return replace(r1, alpha=extrapolated_alpha(scene, param, pts))


def warm_or_cold(solve_from: Callable, start, predictor: str) -> ContactResult:
    """``solve_from(start)``, redone cold (``solve_from(None)``) where the warm start
    fails, so a continuation is never worse than a cold start; the result's
    ``extra["continuation"]`` says which, ``extra["discarded"]`` what a failed warm
    attempt cost (for honest totals)."""
    res = solve_from(start)
    label = "cold" if start is None else predictor
    if start is not None and not res.converged:
        failed = res
        res = solve_from(None)
        label = f"{predictor}, failed; cold"
        res.extra["discarded"] = {
            "outer_iterations": failed.outer_iterations,
            "inner_iterations": failed.inner_iterations,
            "time_s": failed.time_s, "reason": failed.reason}
    res.extra["continuation"] = label
    return res


def extrapolated_alpha(scene, param: str, pts: Sequence) -> np.ndarray:
    """α at ``scene`` by Lagrange extrapolation along ``param`` ("theta" or "height")
    through the (scene, result) points ``pts`` of one line (distinct values)."""
    t = getattr(scene, param)
    ts = [getattr(s, param) for s, _ in pts]
    alpha = np.zeros_like(pts[0][1].alpha, dtype=float)
    for i, (_, r) in enumerate(pts):
        w = math.prod((t - ts[j]) / (ts[i] - ts[j]) for j in range(len(pts)) if j != i)
        alpha = alpha + w * r.alpha
    return alpha


def solve_sequence(scenes: Sequence[ActuatorScene], *, predictor: str = "quadratic",
                   progress: Callable[[int, int], None] | None = None,
                   **solve_kw) -> list[ContactResult]:
    """Solve ``scenes`` in order, each started from its predecessors (``lcpbench.solve``
    keyword arguments in ``solve_kw``; the globalised driver).

    ``predictor``: "quadratic" (the parabola through the previous three
    answers when one of θ or h moves along the line; default), "secant" (the
    straight line through the previous two), "previous" (the last answer),
    or "none" (every scene cold).
    """
    if predictor not in PREDICTORS:
        raise ProblemError(f"predictor must be one of {', '.join(PREDICTORS)}, got "
                           f"{predictor!r}")
    if solve_kw.get("method", "globalised") not in ("globalised", "newton"):
        raise ProblemError("continuation needs method='globalised' or 'newton' (the undamped "
                           "scheme has no line search to fall back on)")
    history: list[tuple[ActuatorScene, ContactResult]] = []
    out = []
    for k, scene in enumerate(scenes):
        res = warm_or_cold(lambda s, sc=scene: solve(sc, start=s, **solve_kw),
                           predict(history, scene, predictor), predictor)
        history.append((scene, res))
        out.append(res)
        if progress is not None:
            progress(k + 1, len(scenes))
    return out


def total_outer(results: Sequence[ContactResult]) -> int:
    """Outer iterations of a line, failed warm starts (redone cold) included."""
    return int(sum(r.outer_iterations + r.extra.get("discarded", {}).get("outer_iterations", 0)
                   for r in results))


def largest_difference(a: Sequence[ContactResult], b: Sequence[ContactResult]) -> float:
    """max over scenes of |F_a − F_b| / max(F_a, EI/ℓ²)."""
    worst = 0.0
    for ra, rb in zip(a, b, strict=True):
        scale = max(abs(ra.total_force), ra.scene.EI / ra.scene.length ** 2)
        worst = max(worst, abs(ra.total_force - rb.total_force) / scale)
    return worst if math.isfinite(worst) else float("inf")


__all__ = ["PREDICTORS", "largest_difference", "predict", "solve_sequence", "total_outer"]
