"""Many scenes in one call: ``lcpbench.solve_many(scenes, tol=..., solver=...)``.

With ``continuation=True`` (default) the actuator scenes are put in an order
that continuation can use: grouped by everything but θ and h (N, ℓ, EI, w,
channel), and within a group by h, then θ, so consecutive scenes are
neighbours on a line in θ; each line is solved by
:func:`lcpbench.studies.continuation.solve_sequence` (a scene whose warm
start fails is solved again cold). Other scenes (the cantilever) are solved
cold. The results come back in the caller's order, one per scene.
"""

from __future__ import annotations

from collections.abc import Iterable

from ..api import solve
from ..errors import ProblemError
from ..model.result import ContactResult
from ..problems.scenes import ActuatorScene
from .continuation import solve_sequence


def _group_key(scene: ActuatorScene) -> tuple:
    return (scene.links, scene.length, scene.EI, scene.weight, scene.channel)


def continuation_order(scenes: list) -> list[list[int]]:
    """Indices of ``scenes`` as lines to solve in order (actuator scenes grouped
    and sorted by h then θ); every other scene is a line of its own."""
    groups: dict[tuple, list[int]] = {}
    lines = []
    for i, s in enumerate(scenes):
        if isinstance(s, ActuatorScene) and isinstance(s.links, int):
            groups.setdefault(_group_key(s), []).append(i)
        else:
            lines.append([i])
    for idx in groups.values():
        lines.append(sorted(idx, key=lambda i: (scenes[i].height, scenes[i].theta)))
    return lines


def solve_many(scenes: Iterable, tol: float | None = None, solver="auto", *,
               continuation: bool = True, predictor: str = "quadratic",
               **solve_kw) -> list[ContactResult]:
    """Solve every scene; one :class:`ContactResult` per scene, in the caller's order.

    ``tol``, ``solver`` and ``solve_kw`` are :func:`lcpbench.solve`'s.
    ``continuation``: start each scene from its solved neighbours (the
    globalised driver only; a failed warm start is redone cold, so the answer
    is the cold one's to the tolerance); ``predictor`` as in
    :func:`~lcpbench.studies.continuation.solve_sequence`. False: every scene
    cold, in the given order.
    """
    if isinstance(scenes, (str, bytes)) or not isinstance(scenes, Iterable):
        raise ProblemError(f"scenes must be a sequence of scenes, got {type(scenes).__name__}")
    scenes = list(scenes)
    if not isinstance(continuation, bool):
        raise ProblemError(f"continuation must be True or False, got {continuation!r}")
    kw = dict(solve_kw, tol=tol, solver=solver)
    if not continuation:
        return [solve(s, **kw) for s in scenes]
    out: list[ContactResult | None] = [None] * len(scenes)
    for line in continuation_order(scenes):
        for i, res in zip(line, solve_sequence([scenes[i] for i in line], predictor=predictor,
                                               **kw), strict=True):
            out[i] = res
    return out  # type: ignore[return-value]  # every index was filled


__all__ = ["continuation_order", "solve_many"]
