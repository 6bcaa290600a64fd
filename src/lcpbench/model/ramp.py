"""Follow the load from zero: the driver through a sequence of bend angles.

The paper's actuator is loaded by pressure from zero: its bend angle θ grows from a
straight tube. A cold start instead begins at the free arc of the full θ, which past
θ = 180° has end links beyond the vertical, where the height step's linearisation
(eq. 20) is singular; rows of sections with large signed angles start in the same
trouble. Their equilibria, pressed flat by the walls, often have no link near the
vertical at all: only the start is bad.

:func:`follow_load` solves the scene at the fractions s = d, 2d, …, 1 of its rest
curvature (every section's θ times s: the scene's ``chain_at(s)``), each started from
the previous answer (a continuation, as ``start=`` of :func:`lcpbench.solve`), with d
such that no section's θ moves by more than :data:`STEP_DEG` degrees a step (at most
:data:`MAX_STEPS` steps). The answer at s = 1 is judged by the caller like every
answer. It is also the state the loading path reaches, where a scene has several
stable states.

Along the path of a row of sections with large signed angles, links pass the
vertical: the equilibrium at the next s has links at 91°–98° while the last one had
them at 82°–90°. The height step's linearisation divides by a cos α_i, so its steps
there are inaccurate or rejected, and the height driver stalls (max|Δα| stuck at
0.03–1.3 rad for 200 outer steps; every refusal of ``benchmarks/saddle_audit.py``'s
rows of sections). Where the chain is in reach of the SQP in the link angles
(:func:`lcpbench.model.angle_step.in_reach`: rigid flat walls) and the built-in
back-end solves, a step that starts with a link within
:data:`~lcpbench.thresholds.NEAR_VERTICAL_DEG` of the vertical (|cos α_i| ≤ sin 10°), or whose height steps did not converge and left
one there, takes outer steps in α instead (:func:`lcpbench.model.heavy_driver.run_heavy`, the same
SQP as a heavy chain's), where every angle is regular; its answer is judged as every
answer. The SQP starts from the last step's angles and, where the SQP found that
answer, its multipliers (wall reactions and closure λ), so its first QP starts from the
last active set (the ±174° row: 0–1 active-set changes); where height steps found it,
their reactions on the walls in contact in the judge's sense (:func:`_multipliers`;
the others, tol-accurate, are small but positive on many walls: 71 where the SQP's
answer presses on 1, 69 changes), which cuts the first SQP of the mixed batch's rows
from 34 active-set changes (1.6–1.8 ms) to none (0.55 ms). The SQP converges to
10⁻⁹ rad whatever its first active set, so the answer is the same to round-off
(345 rows of sections, benchmarks/cold_sqp_states.py's and the mixed batch's).

The rest shapes of a row of sections at every s come in one pass (the scene's
``rest_shapes``; nothing else of its chain depends on s), and the SQP's arrays but φ*
once a path (:func:`lcpbench.model.angle_step.sqp_arrays`, kept with the whole chain and
handed to the chains of the steps; an actuator scene builds its chain at s·θ whole, so
its SQP arrays are built a step). Where the solve kernel takes
the chain (the built-in back-end, the globalised or Newton scheme, the kernel's layout,
neither large nor heavy), a run of height steps is one kernel call
(:func:`lcpbench.model.path_kernel.walk_heights`: the solve kernel step after step, each
warm-started from the last answer as :func:`lcpbench.model.compiled.drive` would), up to
an answer with a link near the vertical or a step that does not converge; the loop below
runs those steps, as it runs every step of another back-end, one :func:`drive` (or SQP)
a step, the chain at s·θ built only there. One step solver serves every step.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..errors import ProblemError
from ..solvers.registry import DEFAULT
from ..thresholds import NEAR_VERTICAL_DEG, NODE_SHARE
from . import large_n
from .angle_step import in_reach, sqp_arrays
from .compiled import drive, heavy
from .heavy_driver import run_heavy
from .judge import force_tol
from .kernel_call import applies, kernel_args, kernel_output, kernel_settings, warm_args
from .outer import DriverOutput, DriverStart

#: the largest change of a section's bend angle between two steps (degrees)
STEP_DEG = 10.0
#: the longest path
MAX_STEPS = 72
#: the SQP steps a step of the path may take: a step of 10° from the last answer takes
#: 5-8 (rows of 3-4 sections, N = 420); one that does not converge in 12 gives way to
#: the height steps
PATH_ANGLE_STEPS = 12


def rest_angles(scene) -> list[float] | None:
    """The signed bend angles θ (degrees) that the load scales, None where the scene
    has none to scale (a cantilever)."""
    if hasattr(scene, "sections"):
        return [s.theta for s in scene.sections]
    theta = getattr(scene, "theta", None)
    return None if theta is None else [theta]


def fractions(scene) -> list[float]:
    """The load fractions of the path, the last one 1; [] where nothing is scaled."""
    angles = rest_angles(scene)
    if not angles:
        return []
    largest = max(abs(t) for t in angles)
    steps = min(MAX_STEPS, max(2, math.ceil(largest / STEP_DEG)))
    return [k / steps for k in range(1, steps + 1)]


def near_vertical(alpha) -> bool:
    """Whether a link of ``alpha`` (rad) is within
    :data:`~lcpbench.thresholds.NEAR_VERTICAL_DEG` of the vertical, where the height step's linearisation divides by a cos α_i ≈ 0 (compiled:
    :func:`lcpbench.model.path_kernel.near_vertical`, which the walk of height steps
    stops on)."""
    return bool(_kernel().near_vertical(np.ascontiguousarray(alpha, dtype=float), _NEAR))


_NEAR = math.sin(math.radians(NEAR_VERTICAL_DEG))


def _kernel():
    from ..numba_cache import kernel_module  # numba at the first path, not at import

    return kernel_module("lcpbench.model.path_kernel", "walk_heights")


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
    whole = scene.chain()
    # the SQP's reactions stand in for the built-in back-end's steps only; its reach
    # (walls, layout, N) is the same at every s
    angles_ok = backend == DEFAULT and method != "undamped" and in_reach(whole)
    shapes = _rest_shapes(scene, path)
    walk = _walk_args(whole, backend, method, shapes)
    step_solver = make_step()  # (a step solver keeps no state between steps)
    kw = dict(backend=backend, settings=settings, engine=engine, tol=tol,
              max_outer=max_outer, method=method)
    start, used, out, in_angles = None, engine, None, 0
    last = None  # the DriverOutput the start was taken from
    k, walked_to = 0, -1  # walked_to: where the last walk stopped (its next step failed)
    while k < len(path):
        s = path[k]
        angles = angles_ok and start is not None
        to_sqp = angles and start is not None and near_vertical(start.alpha)
        if walk is not None and not to_sqp and k != walked_to:  # height steps in one call
            done, walked = _walked(whole, shapes, walk, k, start, settings=settings,
                                   tol=tol, max_outer=max_outer, newton=method == "newton",
                                   limit=_NEAR if angles_ok else -1.0)
            if done:
                k += done
                walked_to = k  # (that step, from the same start, would fail again)
                out, used, start, last = walked, "compiled", DriverStart(
                    walked.alpha, walked.last_step), walked
                continue  # (a step that did not converge: run below, as for any back-end)
        if to_sqp and shapes is not None:  # its arrays but φ*, once: the steps' chains
            sqp_arrays(whole)  # are ``whole`` with another rest shape (_chain_at)
        chain = _chain_at(scene, whole, shapes, k)
        sqp = _in_angles(chain, start, last, tol, max_outer) if to_sqp else None
        if sqp is None:
            out, used = drive(chain, step_solver, start=start, **kw)
            if not out.converged and angles and near_vertical(out.alpha):
                sqp = _in_angles(chain, start, last, tol, max_outer)
        if sqp is not None:
            out, in_angles = sqp, in_angles + 1
            used = f"compiled SQP (SQP steps in the link angles: {_WHY})"
        if not out.converged and start is not None:
            out, used = drive(chain, step_solver, start=None, **kw)
        if not out.converged:
            if k == len(path) - 1:
                return out, used, (f"followed the load from zero in {len(path)} steps"
                                   f"{_told(in_angles)}; the last did not converge")
            return None, used, (f"the loading path stopped at {s:.3g} of the bend angles "
                                f"(step {k + 1} of {len(path)}{_told(in_angles)}): "
                                f"{out.reason}")
        # the SQP's own multipliers start the next SQP's QP (a heavy chain's, in drive)
        sqp_made = out.closure_multiplier is not None
        start, last = DriverStart(out.alpha, out.last_step, (
            out.closure_multiplier, out.forces_upper, out.forces_lower) if sqp_made else None), out
        k += 1
    return out, used, f"followed the load from zero in {len(path)} steps{_told(in_angles)}"


_WHY = "a step of the loading path with a link near the vertical"


def _multipliers(out: DriverOutput, tol: float, force_scale: float) -> tuple:
    """The first multipliers of the next step's SQP (:class:`DriverStart`'s
    ``multipliers``): the SQP's own (λ, R upper, R lower) where it found ``out``; after
    height steps, :func:`first_multipliers` of their reactions."""
    if out.closure_multiplier is not None:
        return out.closure_multiplier, out.forces_upper, out.forces_lower
    return first_multipliers(out.forces_upper, out.forces_lower, tol, force_scale)


def first_multipliers(up: np.ndarray, lo: np.ndarray, tol: float, force_scale: float) -> tuple:
    """An SQP's first multipliers (λ, R upper, R lower) from an answer of height steps:
    its reactions on the walls in contact in the judge's sense
    (R_i > NODE_SHARE·τ·F₀, F₀ = max(F_upper, F_lower, EI/ℓ² = ``force_scale``): the
    threshold of its check "contact", :func:`lcpbench.model.judge_checks.units`), λ = 0. The rest of the height steps'
    reactions, tol-accurate, are small but positive on many walls (67 of 68 below
    1e-10 N on the (168.6°, −168.6°) row, where the SQP's answer presses on 1): handed
    on, they would start the QP on walls it then drops one by one; none handed on, the
    first QP builds its set from empty (34 active-set changes there, 1.6 ms a call)."""
    F0 = max(abs(float(np.sum(up))), abs(float(np.sum(lo))), float(force_scale))
    line = NODE_SHARE * force_tol(tol) * F0
    return 0.0, np.where(up > line, up, 0.0), np.where(lo > line, lo, 0.0)


def _in_angles(chain, start: DriverStart, last: DriverOutput, tol: float,
               max_outer: int) -> DriverOutput | None:
    """The SQP's answer from ``start`` (:func:`lcpbench.model.heavy_driver.run_heavy`), the
    first multipliers those of ``last``, the answer ``start`` was taken from
    (:func:`_multipliers`), or None where it did not converge."""
    first = DriverStart(start.alpha, start.warm, _multipliers(last, tol, chain.force_scale))
    return run_heavy(chain, first, tol, min(max_outer, PATH_ANGLE_STEPS), why=_WHY)


def _rest_shapes(scene, path: list[float]) -> tuple | None:
    """The rest shapes (α*, φ*) of ``scene`` at the load fractions ``path`` in one pass,
    a row per step (a row of sections' ``rest_shapes``), or None: the scene builds its
    chain at s·θ whole (an actuator scene: a wall profile's rows follow the arc), or a
    rest shape closes on itself at some s (raised by ``chain_at`` at that step, where
    the path gets there)."""
    at_once = getattr(scene, "rest_shapes", None)
    if at_once is None:
        return None
    try:
        return at_once(path)
    except ProblemError:
        return None


def _chain_at(scene, whole, shapes: tuple | None, k: int):
    """The chain of step ``k`` of the path: ``whole`` with the k-th rest shape of
    ``shapes`` (``whole`` itself at s = 1), else the scene's ``chain_at``."""
    if shapes is None:
        return scene.chain_at(fractions(scene)[k])
    alpha, joint = shapes
    return whole if k == len(alpha) - 1 else whole.with_rest_shape(alpha[k], joint[k])


def _walk_args(whole, backend: str, method: str, shapes: tuple | None) -> tuple | None:
    """The solve kernel's arguments for :func:`lcpbench.model.path_kernel.walk_heights`
    (the rest shapes a row per step, the rest the scene's chain's), where the solve kernel
    runs each step of the path as :func:`lcpbench.model.compiled.drive` would: the
    default back-end, the globalised or Newton scheme, a chain of its layout, neither
    large nor loaded enough for SQP steps (:func:`lcpbench.model.compiled.heavy`); else
    None (each step by ``drive``)."""
    if shapes is None or not (applies(backend, method, whole) and not large_n.applies(whole)
                              and not heavy(whole)):
        return None
    args = kernel_args(whole)
    return (shapes[0], *args[1:5], shapes[1], *args[6:])


def _walked(whole, shapes: tuple, args: tuple, begin: int, start: DriverStart | None, *,
            settings, tol: float, max_outer: int, newton: bool,
            limit: float) -> tuple[int, DriverOutput | None]:
    """(steps, output): the run of height steps from step ``begin`` in one kernel call
    (:func:`lcpbench.model.path_kernel.walk_heights`), from ``start``, and the
    DriverOutput of its last step (:func:`lcpbench.model.kernel_call.kernel_output`, as
    the solve kernel's answer of that step by ``drive``); (0, None) where the first step
    did not converge."""
    n = whole.free_nodes.size
    max_iter, request, name = kernel_settings(settings, n)
    t0 = time.perf_counter()
    done, got = _kernel().walk_heights(*args, float(tol), int(max_outer), int(begin),
                                       *warm_args(start, n), int(max_iter), float(request),
                                       bool(newton), float(limit))
    if not done:
        return 0, None
    chain = _chain_at(None, whole, shapes, begin + done - 1)
    return done, kernel_output(chain, *got, elapsed=(time.perf_counter() - t0) / done,
                               settings=name, max_outer=max_outer, tol=tol)


def _told(in_angles: int) -> str:
    return (f", {in_angles} of them in the link angles (a link near the vertical)"
            if in_angles else "")
