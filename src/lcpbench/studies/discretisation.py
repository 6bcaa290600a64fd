"""The discretisation study of Sec. III-D and the ``links="auto"`` rule.

The paper refines N in steps of 10 until the total reaction force changes by
less than 0.01 % between successive N, over a grid of scenes, and keeps the
largest N needed (140 for θ = 10°–180°, h = 2–7 mm). Here the same rule is a
function of one scene (used by ``links="auto"``) or of several (the grid).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from ..api import solve
from ..errors import ProblemError


@dataclass
class DiscretisationStudy:
    """Forces against N for one scene, and the N the rule picks."""

    links: list[int] = field(default_factory=list)
    total_force: list[float] = field(default_factory=list)
    percent_change: list[float] = field(default_factory=list)
    chosen: int | None = None


def discretisation_study(
    scene,
    *,
    start: int = 10,
    step: int = 10,
    threshold: float = 0.01,
    max_links: int = 2000,
    solver: str = "auto",
    tol: float = 1e-8,
    total_force: Callable[[object], float] | None = None,
) -> DiscretisationStudy:
    """Refine N by ``step`` until |ΔF|/F < ``threshold`` percent (Sec. III-D).

    A scene without contact (F = 0 at two successive N) stops at once.
    ``total_force(scene)`` gives the model's total reaction F (N) at the N of
    ``scene`` or raises ProblemError; by default the LCP model
    (:func:`lcpbench.solve` with ``solver`` at ``tol``). The root-finding
    baseline passes its own, so each model picks its own N.
    """
    if total_force is None:
        def total_force(s):
            res = solve(s, solver=solver, tol=tol)
            if not res.converged:
                raise ProblemError(f"discretisation study: no convergence at links={s.links}: "
                                   f"{res.reason}")
            return res.total_force

    if not (step >= 1 and start >= 4 and threshold > 0):
        raise ProblemError("start must be >= 4, step >= 1 and threshold > 0")
    study = DiscretisationStudy()
    prev = None
    for n in range(start, max_links + 1, step):
        force = total_force(scene.with_links(n))
        study.links.append(n)
        study.total_force.append(force)
        if prev is not None:
            denom = max(abs(force), abs(prev))
            change = 0.0 if denom == 0 else 100.0 * abs(force - prev) / denom
            study.percent_change.append(change)
            if change < threshold:
                study.chosen = n
                return study
        prev = force
    return study


def auto_links(scene, *, solver: str = "auto", threshold: float = 0.01,
               total_force: Callable[[object], float] | None = None) -> int:
    """The smallest N (in steps of 10) meeting the Sec. III-D force tolerance."""
    study = discretisation_study(scene, solver=solver, threshold=threshold,
                                 total_force=total_force)
    if study.chosen is None:
        raise ProblemError(
            f"links='auto': the force did not settle to {threshold}% by N = {study.links[-1]}"
        )
    return study.chosen


def grid_links(scenes, *, solver: str = "auto", threshold: float = 0.01) -> int:
    """The paper's conservative rule: the largest N any scene of the grid needs."""
    return max(auto_links(s, solver=solver, threshold=threshold) for s in scenes)
