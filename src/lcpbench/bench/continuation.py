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

from ..api import solve
from ..errors import ProblemError
from ..model.result import ContactResult
from ..problems.scenes import ActuatorScene

PREDICTORS = ("secant", "previous", "none")


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


def predict(history: list[tuple[ActuatorScene, ContactResult]], scene: ActuatorScene,
            predictor: str = "secant") -> ContactResult | None:
    """A start for ``scene`` from the solved scenes before it (None: start cold)."""
    if predictor == "none" or not history:
        return None
    s1, r1 = history[-1]
    if not r1.converged or r1.links != scene.links or _step(s1, scene) is None:
        return None
    if predictor == "previous" or len(history) < 2:
        return r1
    s0, r0 = history[-2]
    d0, d1 = _step(s0, s1), _step(s1, scene)
    if not r0.converged or d0 is None or d0[0] != d1[0] or d0[1] == 0:
        return r1
    return replace(r1, alpha=r1.alpha + (r1.alpha - r0.alpha) * (d1[1] / d0[1]))


def solve_sequence(scenes: Sequence[ActuatorScene], *, predictor: str = "secant",
                   progress: Callable[[int, int], None] | None = None,
                   **solve_kw) -> list[ContactResult]:
    """Solve ``scenes`` in order, each started from its predecessors (``lcpbench.solve``
    keyword arguments in ``solve_kw``; the globalised driver).

    ``predictor``: "secant" (extrapolate through the previous two answers when
    one of θ or h moves along the line), "previous" (the last answer), or
    "none" (every scene cold).
    """
    if predictor not in PREDICTORS:
        raise ProblemError(f"predictor must be one of {', '.join(PREDICTORS)}, got "
                           f"{predictor!r}")
    if solve_kw.get("method", "globalised") != "globalised":
        raise ProblemError("continuation needs method='globalised'")
    history: list[tuple[ActuatorScene, ContactResult]] = []
    out = []
    for k, scene in enumerate(scenes):
        start = predict(history, scene, predictor)
        res = solve(scene, start=start, **solve_kw)
        if start is not None and not res.converged:  # never worse than a cold start
            res = solve(scene, **solve_kw)
        res.extra["continuation"] = "cold" if start is None else predictor
        history.append((scene, res))
        out.append(res)
        if progress is not None:
            progress(k + 1, len(scenes))
    return out


def total_outer(results: Sequence[ContactResult]) -> int:
    return int(sum(r.outer_iterations for r in results))


def largest_difference(a: Sequence[ContactResult], b: Sequence[ContactResult]) -> float:
    """max over scenes of |F_a − F_b| / max(F_a, EI/ℓ²)."""
    worst = 0.0
    for ra, rb in zip(a, b, strict=True):
        scale = max(abs(ra.total_force), ra.scene.EI / ra.scene.length ** 2)
        worst = max(worst, abs(ra.total_force - rb.total_force) / scale)
    return worst if math.isfinite(worst) else float("inf")


__all__ = ["PREDICTORS", "largest_difference", "predict", "solve_sequence", "total_outer"]
