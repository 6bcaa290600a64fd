"""Continuation: solve scenes in order, each starting from its neighbours' answers.

Along a line in θ the equilibrium moves smoothly, so a polynomial through
the nearest answers is a much closer first iterate than the clipped
unconstrained arc; across lines (in h) a scene that touches no wall has the
same answer as its neighbour that touches none (:class:`Solved` has the
rules). The globalised and Newton drivers clip the prediction to the walls
and line-search on the exact energy from there, so the answer is the same
equilibrium; only the path to it is shorter.

Measured on the paper grid (``benchmarks/perf_targets.py`` → results/perf.md,
``benchmarks/warm_sweep.py``; docs/performance.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import fields, replace
from operator import attrgetter

import numpy as np

from ..api import solve_internal
from ..errors import ProblemError
from ..model.result import ContactResult
from ..problems.scenes import ActuatorScene

PREDICTORS = ("adaptive", "quadratic", "secant", "previous", "none")
#: answers each predictor extrapolates through (polynomial degree + 1; "adaptive": at most)
POINTS = {"adaptive": 6, "quadratic": 3, "secant": 2, "previous": 1}


def touches(res: ContactResult) -> bool:
    """Whether an answer presses on a wall (any reaction > 0)."""
    lower = res.forces_lower
    return bool(np.any(res.forces > 0) or (lower is not None and np.any(lower > 0)))


class Solved:
    """The solved scenes of a batch, indexed for the predictor.

    Scenes that differ only in θ and h form one plane; in it a scene's
    neighbours are the solved scenes at the same h (its line in θ) and at the
    same θ (the other lines). :meth:`predict` starts a scene from:

    1. a neighbour at the same θ that touches no wall, as it is, when the
       line's nearest answer touches no wall either (or there is none): it is
       the chain's equilibrium without walls, which no wall enters, so it is
       this scene's answer too if the scene touches nothing (to the driver's
       tolerance; else a start clipped to the walls, as any);
    2. just after the line starts to touch (fewer than ``most`` answers on it
       that touch): the neighbouring line's answer at θ plus the polynomial in
       θ of the difference between the two lines, through the θ where both
       touch (a 2-D predictor);
    3. else the polynomial in θ through the line's nearest converged answers
       (at most ``most``; only answers that touch a wall as the nearest does,
       or all that do not: a polynomial through a change of contact
       extrapolates neither shape). ``adaptive``: of the degree where two
       successive degrees agree best (the difference estimates the error of
       the lower one; through the answers' own truncation the higher degrees
       amplify it, which stops the choice at loose tolerances);
    4. with no answer on the line, the nearest answer at the same θ; with none
       at all, a cold start.
    """

    def __init__(self, most: int = 3, adaptive: bool = False) -> None:
        self.most = most
        self.adaptive = adaptive
        # per plane (the scene's fields but θ and h): its converged answers in order
        self._planes: dict = {}

    def _plane(self, scene, make: bool = False) -> _Plane | None:
        if not isinstance(scene, ActuatorScene):
            return None
        key = _plane_key(scene)
        if not _hashable(key):  # a field that does not hash: the planes compared one by one
            key = next((k for k in self._planes if isinstance(k, _Unhashed) and k.key == key),
                       _Unhashed(key))
        plane = self._planes.get(key)
        if plane is None and make:
            plane = self._planes[key] = _Plane()
        return plane

    def add(self, scene: ActuatorScene, res: ContactResult) -> None:
        """Record the answer ``res`` of ``scene`` (not converged, or not an actuator
        scene: ignored)."""
        plane = self._plane(scene, make=True) if res.converged else None
        if plane is not None:
            plane.add(scene.theta, scene.height, res)

    def predict(self, scene: ActuatorScene) -> tuple[np.ndarray, ContactResult] | None:
        """(α to start ``scene`` from, the answer whose last contact step warm-starts
        it), or None: start cold. The rules above are
        :func:`lcpbench.model.predictor_kernel.predict_start` (compiled, the line
        kernel's too) on the arrays of the scene's plane, whose spare row it writes (a
        Solved is not for two threads at once)."""
        plane = self._plane(scene) if self.most else None
        if plane is None or not plane.results:
            return None
        return plane.predict(scene.theta, scene.height, self.most, self.adaptive)


class _Plane:
    """The converged answers of one plane, in the order added: their θ, h, whether
    each touches a wall and α (a row each, grown by doubling), as
    :func:`~lcpbench.model.predictor_kernel.predict_start` reads them (one plane: the
    plane indices all 0, no kin), and a spare row for the scene to predict."""

    def __init__(self) -> None:
        self.results: list[ContactResult] = []
        self.rows = 0

    def _room(self, links: int) -> None:
        """A row for one more answer and a spare row past it (the scene predicted)."""
        count = len(self.results)
        if count + 2 <= self.rows:
            return
        rows = max(8, 2 * (count + 2))
        grown = (np.empty(rows), np.empty(rows), np.zeros(rows, np.bool_),
                 np.empty((rows, links)))
        if count:
            for new, old in zip(grown, (self.theta, self.height, self.touch, self.alphas),
                                strict=True):
                new[:count] = old[:count]
        self.theta, self.height, self.touch, self.alphas = grown
        self.plane, self.kin = np.zeros(rows, np.int64), np.full(rows, -1, np.int64)
        self.ok, self.where = np.ones(rows, np.bool_), np.zeros((rows, 0))
        self.rows = rows

    def add(self, theta: float, height: float, res: ContactResult) -> None:
        self._room(res.alpha.size)
        i = len(self.results)
        self.theta[i], self.height[i], self.touch[i] = theta, height, touches(res)
        self.alphas[i] = res.alpha
        self.results.append(res)

    def predict(self, theta: float, height: float, most: int,
                adaptive: bool) -> tuple[np.ndarray, ContactResult] | None:
        from ..numba_cache import kernel_module  # (not at import: numba, or the AOT module)

        s = len(self.results)
        self.theta[s], self.height[s] = theta, height
        k = kernel_module("lcpbench.model.predictor_kernel", "predict_start")
        start, base = k.predict_start(s, self.theta, self.height, self.plane, self.kin,
                                      self.where, self.ok, self.touch, self.alphas,
                                      int(most), bool(adaptive))
        return None if base < 0 else (start, self.results[base])


#: what makes two actuator scenes lie in one plane of θ and h
PLANE_FIELDS = tuple(f.name for f in fields(ActuatorScene) if f.name not in ("theta", "height"))
_plane_key = attrgetter(*PLANE_FIELDS)  # a scene's plane: the tuple of those fields


class _Unhashed:
    """A plane's key with a field that does not hash (by identity in the dict)."""

    def __init__(self, key: tuple) -> None:
        self.key = key


def _hashable(key) -> bool:
    try:
        hash(key)
    except TypeError:
        return False
    return True


def predict(history: list[tuple[ActuatorScene, ContactResult]], scene: ActuatorScene,
            predictor: str = "adaptive") -> ContactResult | None:
    """A start for ``scene`` from the solved scenes ``history`` (None: start cold), as
    :class:`Solved` chooses it: ``base`` with the predicted α, where ``base`` is
    the answer whose last contact step warm-starts the scene."""
    if predictor == "none" or not history:
        return None
    solved = Solved(POINTS[predictor], predictor == "adaptive")
    for s, r in history:
        solved.add(s, r)
    got = solved.predict(scene)
    return None if got is None else replace(got[1], alpha=got[0])


def new_solved(predictor: str) -> Solved:
    """The index of solved scenes that ``predictor`` predicts from."""
    return Solved(POINTS.get(predictor, 0), predictor == "adaptive")


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


def solve_sequence(scenes: Sequence[ActuatorScene], *, predictor: str = "adaptive",
                   progress: Callable[[int, int], None] | None = None,
                   **solve_kw) -> list[ContactResult]:
    """Solve ``scenes`` in order, each started from the answers solved before it
    (``lcpbench.solve`` keyword arguments in ``solve_kw``; the globalised or
    Newton driver), as :class:`Solved` predicts it.

    ``predictor``: the polynomial in θ through the nearest answers on the
    scene's line: "adaptive" (up to six, of the degree where successive
    degrees agree best; default), "quadratic" (three), "secant" (two),
    "previous" (one, the nearest answer); or "none" (every scene cold).
    """
    if predictor not in PREDICTORS:
        raise ProblemError(f"predictor must be one of {', '.join(PREDICTORS)}, got "
                           f"{predictor!r}")
    if solve_kw.get("method", "globalised") not in ("globalised", "newton"):
        raise ProblemError("continuation needs method='globalised' or 'newton' (the undamped "
                           "scheme has no line search to fall back on)")
    solved = new_solved(predictor)
    out = []
    for k, scene in enumerate(scenes):
        got = solved.predict(scene)
        start = None if got is None else replace(got[1], alpha=got[0])
        res = warm_or_cold(lambda s, sc=scene: solve_internal(sc, start=s, **solve_kw), start,
                           predictor)
        solved.add(scene, res)
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
