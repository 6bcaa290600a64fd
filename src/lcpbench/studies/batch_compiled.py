"""The default back-end's batch loop: continuation lines in the compiled kernels.

:func:`lcpbench.solve_many` hands each continuation line here when the scenes
use the default back-end (the dual active set) with the globalised driver and
the compiled engine: per scene, the chain, the wall-free search
(:func:`lcpbench.model.wall_free.solve_without_contact` in the kernel), one
call of the solve kernel (:func:`lcpbench.model.compiled.run_compiled`) and one
of the judge kernel (:func:`lcpbench.model.judge.judge`); the
checks of :func:`lcpbench.solve` are done once per batch, not per scene. A chain with
a wall of any profile runs the profile kernel as :func:`lcpbench.model.compiled.drive`
runs it; a line of scenes that all press one profiled wall (:func:`profile_line`) runs
each attempt's solve and judge in one call
(:func:`lcpbench.model.profile_line.profile_attempt`), its starts chosen by the same
:class:`~lcpbench.studies.continuation.Solved`, its results built when read (the same
answers, bit for bit, as the scene-by-scene loop's).

It is :func:`lcpbench.studies.continuation.solve_sequence` with the same
predictor (the polynomial through the line's last answers, the last answer's
contact set as the warm start, a failed warm start redone cold), so the
results are the ones :func:`lcpbench.studies.continuation.solve_sequence` gives
with :func:`lcpbench.solve`, to round-off (tests). Every result is judged by lcpbench's judge, as every result of
:func:`lcpbench.solve` is.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..model import large_n
from ..model.compiled import drive, heavy, reference
from ..model.finish import finish
from ..model.judge import chain_args
from ..model.kernel_call import (
    applies,
    kernel_args,
    kernel_settings,
    profile_applies,
    profile_args,
    run_compiled,
    run_profile_compiled,
)
from ..model.outer import DriverStart
from ..model.result import ContactResult
from ..model.step_solver import make_step_solver
from ..model.wall_free import arc_far, solve_without_contact
from ..problems.scenes import ActuatorScene
from ..solvers.registry import DEFAULT
from .batch_line import LINE_OUTPUTS
from .batch_result import AUTO_WHY, LineOutput, results
from .continuation import Solved, new_solved, warm_or_cold

#: the ``route`` of its results (a batch's, not a plan's: lcpbench.plan.ROUTES)
BATCH_SCENE = "batch scene"


def takes(solver, solve_kw: dict) -> bool:
    """Whether a batch with these :func:`lcpbench.solve` arguments runs here."""
    allowed = {"tol", "max_outer", "settings", "engine", "method"}
    return (solver in ("auto", DEFAULT) and set(solve_kw) <= allowed
            and solve_kw.get("method", "globalised") == "globalised"
            and solve_kw.get("engine", "auto") in ("auto", "compiled"))


def _predict(solved: Solved, scene: ActuatorScene) -> DriverStart | None:
    """The start of ``scene``, as :func:`lcpbench.studies.continuation.solve_sequence`
    chooses it (:meth:`Solved.predict`); None: start cold."""
    got = solved.predict(scene)
    return None if got is None else DriverStart(got[0], got[1].extra.get("last_step"))


def _solve_one(scene, tol: float, max_outer: int, settings: str,
               start: DriverStart | None, const: dict) -> ContactResult:
    """:func:`lcpbench.solve` for an already checked scene, in the kernels.

    ``const``: what the scenes of a line share (filled by the first): the arrays the
    chains have in common (N, ℓ, w and EI are the line's; walls may differ)."""
    t0 = time.perf_counter()
    chain = scene.chain()
    # not from LARGE_N links: those run in increments (model.large_driver, via drive)
    kernel = applies(DEFAULT, "globalised", chain) and not large_n.applies(chain)
    if kernel and not const:
        full = kernel_args(chain)
        const["arrays"] = full[2:4] + (full[7],)
    args = kernel_args(chain, const["arrays"]) if kernel else None
    out = solve_without_contact(chain, tol, max_outer, start, args=args)
    used = "compiled"  # (the wall-free tests and search are compiled)
    if out is None and not kernel and profile_applies(DEFAULT, "globalised", chain):
        # a wall of any profile: the profile kernel, as model.compiled.drive runs it for
        # this chain (no SQP steps: they take flat walls only), the step solver made only
        # for its fall-back
        args = kernel_args(chain)
        out, why = run_profile_compiled(chain, tol=tol, max_outer=max_outer, start=start,
                                        settings=settings)
        used = "compiled"
        if out is None:  # the kernel stopped: its compiled fall-back
            out, used = reference(chain, lambda: make_step_solver(DEFAULT, settings, True),
                                  why, tol=tol, max_outer=max_outer, method="globalised",
                                  start=start, settings=settings)
    elif out is None and (not kernel or heavy(chain)):
        # large N, a layout the kernel does not take, or a heavy chain (SQP steps in the
        # angles, first or as the rescue): solve()'s choice, in model.compiled.drive
        out, used = drive(chain, make_step_solver(DEFAULT, settings, True), backend=DEFAULT,
                          settings=settings, engine="auto", tol=tol,
                          max_outer=max_outer, method="globalised", start=start,
                          args=args)
    if out is None:
        used = "compiled"
        out, why = run_compiled(chain, tol=tol, max_outer=max_outer, start=start,
                                settings=settings, args=args)
        if out is None:  # the kernel stopped: its compiled fall-back
            out, used = reference(chain, lambda: make_step_solver(DEFAULT, settings, True),
                                  why, tol=tol, max_outer=max_outer, method="globalised",
                                  start=start, settings=settings)
    return finish(scene, chain, out, solver=DEFAULT, method="globalised", tol=tol,
                  elapsed=time.perf_counter() - t0, settings=settings, engine=used,
                  why=AUTO_WHY,
                  judge_args=None if args is None else chain_args(chain, args),
                  route=BATCH_SCENE)


def solve_line(scenes: list, *, tol: float, max_outer: int = 200, settings: str = "default",
               predictor: str = "adaptive") -> list[ContactResult]:
    """One continuation line (scenes of one group, in order), in the kernels: a plane
    against one wall of any profile in one call of the profile line kernel where it
    takes it (:func:`profile_line`), else scene by scene."""
    got = profile_line(scenes, tol=tol, max_outer=max_outer, settings=settings,
                       predictor=predictor)
    if got is not None:
        return got
    solved = new_solved(predictor)
    out = []
    const: dict = {}
    for scene in scenes:
        res = warm_or_cold(
            lambda s, sc=scene: _solve_one(sc, tol, max_outer, settings, s, const),
            _predict(solved, scene), predictor)
        solved.add(scene, res)
        out.append(res)
    return out


def _profile_kernel():
    from ..numba_cache import kernel_module  # numba at the first batch, not at import

    return kernel_module("lcpbench.model.profile_line", "profile_attempt")


def _takes_profile(chain, c0) -> bool:
    """Whether :func:`profile_line` takes ``chain`` in a line whose first chain is ``c0``:
    one wall of any profile that the profile kernel takes, the sizes of ``c0``'s, and an
    unconstrained arc far past the wall (the wall-free search returns at once)."""
    return (not chain.channel and profile_applies(DEFAULT, "globalised", chain)
            and arc_far(chain) and chain.links == c0.links
            and chain.free_nodes.size == c0.free_nodes.size
            and chain.joint_links.shape == c0.joint_links.shape)


@dataclass(frozen=True, eq=False)
class _Answer:
    """What :class:`~lcpbench.studies.continuation.Solved` reads of an answer of
    :func:`profile_line` (its result is built after the line): the verdict, α, the
    reactions; ``index``: the scene's in the line."""

    index: int
    converged: bool
    alpha: np.ndarray
    forces: np.ndarray
    forces_lower: None = None


def profile_line(scenes: list, *, tol: float, max_outer: int = 200,
                 settings: str = "default", predictor: str = "adaptive"
                 ) -> list[ContactResult] | None:
    """The results of a line of actuator scenes against one wall of any profile, each
    scene's start, solve, judge and a failed warm start's cold retry as the
    scene-by-scene loop below has them, the start by the same
    :class:`~lcpbench.studies.continuation.Solved`, the rest in one call of
    :func:`lcpbench.model.profile_line.profile_attempt` per attempt; the results built
    when read (:mod:`lcpbench.studies.batch_result`). None where it does not take the
    line or the profile kernel stopped on a scene (the caller solves the line scene by
    scene)."""
    if len(scenes) < 2 or not all(type(s) is ActuatorScene for s in scenes):
        return None
    chains = [s.chain() for s in scenes]
    c0 = chains[0]
    if not c0.profiled_walls or not all(_takes_profile(c, c0) for c in chains):
        return None
    m, n, nj = len(chains), c0.free_nodes.size, c0.joint_links.shape[0]
    kern = _profile_kernel()
    max_iter, request, _ = kernel_settings(settings, n)
    sizes = {"links": c0.links, "n": n, "nj": nj, "stats": len(kern.STATS)}
    A = {name: np.empty((2 * m, *(sizes.get(d, d) for d in shape)), dtype=dt)
         for name, dt, shape in LINE_OUTPUTS}  # (a spare row for each scene's cold retry)
    A["conv"][:] = False
    kept, failed, base = (np.empty(m, np.int64) for _ in range(3))
    A["kept"], A["failed"], A["base"] = kept, failed, base
    outs = tuple(A[name] for name, _, _ in LINE_OUTPUTS)
    conv, o_alpha, o_R, o_u, j_fu = A["conv"], A["o_alpha"], A["o_R"], A["o_u"], A["j_fu"]
    recs, used, retry, elapsed = np.empty((4, 2 * m + 8)), 0, m, 0.0
    solved = new_solved(predictor)
    for s, (scene, chain) in enumerate(zip(scenes, chains, strict=True)):
        args = (*kernel_args(chain)[:9], *profile_args(chain)[:8], float(chain.wall),
                float(tol), int(max_outer), int(max_iter), float(request))
        got = solved.predict(scene)
        start = net = u0 = _EMPTY
        b = -1
        if got is not None:  # (a warm start: the base's last step, its R and heights)
            b = got[1].index
            start = np.ascontiguousarray(got[0], dtype=float)
            net, u0 = o_R[kept[b]], o_u[kept[b]]
        base[s], failed[s], kept[s] = b, -1, s
        t0 = time.perf_counter()
        done, recs, used = kern.profile_attempt(s, start, net, u0, *args, *outs, recs, used)
        if done and b >= 0 and not conv[s]:  # the warm start failed: cold, in a spare row
            kept[s], failed[s] = retry, s
            done, recs, used = kern.profile_attempt(retry, _EMPTY, _EMPTY, _EMPTY, *args,
                                                    *outs, recs, used)
            retry += 1
        elapsed += time.perf_counter() - t0
        if not done:
            return None
        row = kept[s]
        solved.add(scene, _Answer(s, bool(conv[row]), o_alpha[row], j_fu[row]))
    A["records"] = recs
    return results(LineOutput(scenes, A, float(tol), int(max_outer), settings, predictor,
                              elapsed / m, kern, False))


_EMPTY = np.zeros(0)  # no start (never written)


__all__ = ["profile_line", "solve_line", "takes"]
