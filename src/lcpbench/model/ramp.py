"""Follow the load from zero: the driver through a sequence of bend angles.

The paper's actuator is loaded by pressure from zero: its bend angle θ grows from a
straight tube. A cold start instead begins at the free arc of the full θ, which past
θ = 180° has end links beyond the vertical, where the height step's linearisation
(eq. 20) is singular; rows of sections with large signed angles start in the same
trouble. Their equilibria, pressed flat by the walls, often have no link near the
vertical at all: only the start is bad.

:func:`follow_load` solves the scene at the fractions s = d, 2d, …, 1 of its rest
curvature (every section's θ times s), each started from the previous answer (a
continuation, as ``start=`` of :func:`lcpbench.solve`), with d such that no
section's θ moves by more than :data:`STEP_DEG` degrees a step (at most
:data:`MAX_STEPS` steps). The answer at s = 1 is judged by the caller like every
answer. It is also the state the loading path reaches, where a scene has several
stable states.
"""

from __future__ import annotations

import math
from dataclasses import replace

from .compiled import drive
from .outer import DriverOutput, DriverStart

#: the largest change of a section's bend angle between two steps (degrees)
STEP_DEG = 10.0
#: the longest path
MAX_STEPS = 72


def rest_angles(scene) -> list[float] | None:
    """The signed bend angles θ (degrees) that the load scales, None where the scene
    has none to scale (a cantilever)."""
    if hasattr(scene, "sections"):
        return [s.theta for s in scene.sections]
    theta = getattr(scene, "theta", None)
    return None if theta is None else [theta]


def at_fraction(scene, s: float):
    """The scene with every bend angle θ scaled to s·θ."""
    if hasattr(scene, "sections"):
        return replace(scene, sections=tuple(replace(x, theta=s * x.theta)
                                             for x in scene.sections))
    return replace(scene, theta=s * scene.theta)


def fractions(scene) -> list[float]:
    """The load fractions of the path, the last one 1; [] where nothing is scaled."""
    angles = rest_angles(scene)
    if not angles:
        return []
    largest = max(abs(t) for t in angles)
    steps = min(MAX_STEPS, max(2, math.ceil(largest / STEP_DEG)))
    return [k / steps for k in range(1, steps + 1)]


def follow_load(scene, make_step, *, backend: str, settings, engine: str, tol: float,
                max_outer: int, method: str) -> tuple[DriverOutput | None, str, str]:
    """The driver's answer for ``scene`` at the end of the loading path.

    Returns ``(output, engine used, what happened)``; ``output`` is None where a step
    of the path did not converge, warm or cold (``what happened`` says at which θ).
    Each step has ``max_outer`` outer iterations of its own.
    """
    path = fractions(scene)
    if not path:
        return None, engine, "the scene has no bend angle to follow from zero"
    start, used, out = None, engine, None
    for k, s in enumerate(path):
        step_scene = scene if k == len(path) - 1 else at_fraction(scene, s)
        chain = step_scene.chain()
        kw = dict(backend=backend, settings=settings, engine=engine, tol=tol,
                  max_outer=max_outer, method=method)
        out, used = drive(chain, make_step(), start=start, **kw)
        if not out.converged and start is not None:
            out, used = drive(chain, make_step(), start=None, **kw)
        if not out.converged:
            if k == len(path) - 1:
                return out, used, (f"followed the load from zero in {len(path)} steps; "
                                   f"the last did not converge")
            return None, used, (f"the loading path stopped at {s:.3g} of the bend angles "
                                f"(step {k + 1} of {len(path)}): {out.reason}")
        start = DriverStart(out.alpha, out.last_step)
    return out, used, f"followed the load from zero in {len(path)} steps"
