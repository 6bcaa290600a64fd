"""The library call: ``lcpbench.solve(scene) -> ContactResult``."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np
from scipy.linalg import LinAlgError

from .errors import ProblemError
from .model.chain import heights
from .model.driver import METHODS, DriverOutput, DriverStart, run_driver
from .model.result import ContactResult, build_result
from .model.step import assemble_step
from .problems.scenes import ActuatorScene
from .solvers import make_step_solver
from .solvers.base import Status, StepSolution


def _check_tol(tol) -> float:
    try:
        tol = float(tol)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"tol must be a number in [1e-14, 1) rad, got {tol!r}") from exc
    if not (math.isfinite(tol) and 1e-14 <= tol < 1):
        raise ProblemError(f"tol must be in [1e-14, 1) rad, got {tol:g}")
    return tol


def solve(
    scene,
    solver: str = "auto",
    tol: float = 1e-3,
    *,
    method: str = "globalised",
    max_outer: int = 200,
    settings: str = "default",
    scaled: bool = True,
    start: ContactResult | None = None,
) -> ContactResult:
    """Find the constrained equilibrium of a scene.

    Parameters
    ----------
    scene : ActuatorScene or CantileverScene
    solver : name of the contact-step back-end (``lcpbench solvers`` lists them
        all), or "auto": the back-end :func:`lcpbench.select_backend` chose for
        this kind of scene at the force accuracy that ``tol`` gives
        (min(1e-3, 100·tol)), read from the probes cached in the store
        (``$LCPBENCH_STORE`` or ``results/lcpbench.sqlite``) and never probing;
        with nothing cached, the built-in active set.
    tol : convergence threshold on max|α̂ − α| (rad), eq. (32); paper: 1e-3.
    method : "globalised" (line search on the exact energy; default) or
        "undamped" (the paper's Fig. 3 iteration, for comparison).
    max_outer : limit on contact steps.
    settings : accuracy profile of the back-end: "default" (its own defaults),
        "low" (1e-3), "mid" (1e-6) or "high" (1e-9).
    scaled : hand the back-end the nondimensionalised step (default) or the
        raw one (mm, N), to see what scaling does.
    start : a neighbouring scene's result (same N and length) to start from:
        continuation along θ or h. Its shape, clipped to this scene's walls, is
        the first iterate and its last contact step warm-starts back-ends that
        take one. Globalised scheme only; the answer is the same equilibrium
        to the tolerance (tests check 1e-8 at tight tol).

    Returns
    -------
    ContactResult
        Never raises on non-convergence: ``converged`` is False with a reason.
    """
    tol = _check_tol(tol)
    if method not in METHODS:
        raise ProblemError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if not (isinstance(max_outer, (int, np.integer)) and max_outer >= 1):
        raise ProblemError(f"max_outer must be an integer >= 1, got {max_outer!r}")
    step = make_step_solver(solver, settings, bool(scaled))  # validates them first
    if isinstance(scene, ActuatorScene) and scene.links == "auto":
        from .model.discretisation import auto_links

        scene = scene.with_links(auto_links(scene, solver=solver))
    name, why = solver, None
    if solver == "auto":
        name = "active-set"
        if isinstance(scene, ActuatorScene):
            from .bench.select import auto_backend

            name, chosen, why = auto_backend(scene, tol)
            if settings == "default":
                settings = chosen
            step = make_step_solver(name, settings, bool(scaled))
    t0 = time.perf_counter()
    chain = scene.chain()
    begin = _driver_start(start, chain, method)
    out = _without_contact(chain, tol, max_outer, begin)
    if out is None:
        out = run_driver(chain, step, tol=tol, max_outer=max_outer, method=method,
                         start=begin)
        if not out.converged and getattr(scene, "theta", 0) > 180:
            out.reason = ("theta > 180 deg: the end links start beyond the vertical, where the "
                          "linearisation of eq. (20) is singular; lcpbench converges for "
                          f"theta <= 180 deg ({out.reason})")
    elapsed = time.perf_counter() - t0
    res = build_result(scene, chain, out, solver=name, method=method, tol=tol, time_s=elapsed)
    res.extra["last_step"] = out.last_step  # what a continuation hands the next scene
    res.extra["settings"] = settings if isinstance(settings, str) else "custom"
    if why is not None:
        res.extra["auto"] = why
    _audit(res, chain)
    return res


def _driver_start(start, chain, method: str):
    if start is None:
        return None
    if not isinstance(start, ContactResult):
        raise ProblemError(f"start must be a ContactResult of a neighbouring scene, got "
                           f"{type(start).__name__}")
    if method != "globalised":
        raise ProblemError("start (continuation) needs method='globalised'")
    if start.links != chain.links or \
            not math.isclose(getattr(start.scene, "length", chain.length), chain.length):
        raise ProblemError(f"start must have the same links and length as the scene "
                           f"(start: N = {start.links}; scene: N = {chain.links})")
    return DriverStart(np.asarray(start.alpha, float), start.extra.get("last_step"))


def _audit(res: ContactResult, chain) -> None:
    """Never call an answer converged that the exact-geometry certificate rejects."""
    if not res.converged:
        return
    c = res.certificate
    problems = []
    if c.relative_torque_residual > max(10 * res.tol, 1e-6):
        problems.append(f"torque residual {c.relative_torque_residual:.1e} (relative)")
    if c.min_gap < -1e-6 * chain.length:
        problems.append(f"penetration {c.min_gap:.1e} mm")
    if c.closure > 1e-6 * chain.length:
        problems.append(f"chain not closed by {c.closure:.1e} mm")
    if problems:
        res.converged = False
        res.reason = "the certificate rejects the answer: " + ", ".join(problems)


def _overlap(chain, u) -> float:
    """How far free-node heights ``u`` cross the walls (mm; < 0: strictly between
    them; NaN if u has a NaN)."""
    return float(max(np.max(u - chain.upper), np.max(chain.lower - u)))


#: Skip the wall-free search when the arc crosses a wall by more than this many
#: times the mid-span sag of a straight pinned beam under the same load
#: (5 w ℓ⁴ / 384 EI): the arc will not sag off it. A heuristic that only saves
#: time: a scene it sends to the contact solve still gets the right answer.
_SAG_BOUND = 10.0


def _beam_sag(chain) -> float:
    """5 w ℓ⁴ / (384 EI) for the chain's total load (EI = force_scale · ℓ²)."""
    load = float(np.sum(np.abs(chain.link_load)))
    return 5.0 / 384.0 * load * chain.length / chain.force_scale


def _free_step(step, warm) -> StepSolution:
    """The step of a chain with no walls: its unconstrained minimiser (a banded
    solve; no LCP)."""
    t0 = time.perf_counter()
    n = step.size
    try:
        u, status = step.unconstrained_minimiser(), Status.SOLVED
    except (LinAlgError, ValueError):  # not positive definite: no minimiser
        u, status = np.full(n, np.nan), Status.FAILED
    return StepSolution(u, np.zeros(n), np.zeros(n), status, 0, time.perf_counter() - t0)


def _without_contact(chain, tol: float, max_outer: int,
                     start: DriverStart | None = None) -> DriverOutput | None:
    """The answer of a scene that touches no wall, found without any LCP (or None).

    With no load, the unconstrained arc is the answer when it clears every
    wall. With a load (gravity) the unconstrained shape is the equilibrium of
    the chain without walls, found by the same globalised driver with each
    step a banded solve; if it clears every wall it is the answer, otherwise
    None (the scene is solved with its walls). A continuation's ``start``
    (a neighbour's shape) starts that search too. It is looked for when the arc
    clears the walls, or when the first step of that search (one banded solve
    at the arc, ~0.1 ms at N = 140) already does: a heavy chain can sag off a
    wall its arc crosses.
    """
    n = chain.free_nodes.size
    loaded = bool(np.any(chain.link_load != 0))
    overlap = _overlap(chain, heights(chain, chain.rest_alpha))
    if overlap >= 0:  # the arc touches or crosses a wall
        if not loaded or overlap > _SAG_BOUND * _beam_sag(chain):
            return None
        first = _free_step(assemble_step(chain, chain.rest_alpha), None).u
        if not _overlap(chain, first) < 0:  # NaN (no minimiser) included
            return None
    elif not loaded:
        return DriverOutput(chain.rest_alpha.copy(), np.zeros(n), np.zeros(n), True,
                            "no contact: the unconstrained arc clears every wall and there "
                            "is no load")
    free = replace(chain, upper=np.full(n, np.inf), lower=np.full(n, -np.inf))
    if start is not None:  # a neighbour's shape (its contact set means nothing here)
        start = DriverStart(start.alpha, None)
    out = run_driver(free, _free_step, tol=tol, max_outer=max_outer, start=start)
    if not (out.converged and _overlap(chain, heights(chain, out.alpha)) < 0):
        return None
    out.reason = ("no contact: the equilibrium without walls clears every wall (found by "
                  "banded solves, no LCP)")
    return out
