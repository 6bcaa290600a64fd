"""The default back-end's batch loop: continuation lines in the compiled kernels.

:func:`lcpbench.solve_many` hands each continuation line here when the scenes
use the default back-end (the dual active set) with the globalised driver and
the compiled engine: per scene, the chain, the wall-free search
(:func:`lcpbench.model.wall_free.solve_without_contact` in the kernel), one
call of the solve kernel (:func:`lcpbench.model.compiled.run_compiled`) and one
of the judge kernel (:func:`lcpbench.model.judge.judge`); the
checks of :func:`lcpbench.solve` are done once per batch, not per scene.

It is :func:`lcpbench.studies.continuation.solve_sequence` with the same
predictor (the polynomial through the line's last answers, the last answer's
contact set as the warm start, a failed warm start redone cold), so the
results are the ones :func:`lcpbench.studies.continuation.solve_sequence` gives
with :func:`lcpbench.solve`, to round-off (tests). Every result is judged by lcpbench's judge, as every result of
:func:`lcpbench.solve` is.
"""

from __future__ import annotations

import time

from ..model import large_n
from ..model.compiled import drive, heavy, reference
from ..model.finish import finish
from ..model.judge import chain_args
from ..model.kernel_call import (
    applies,
    kernel_args,
    profile_applies,
    run_compiled,
    run_profile_compiled,
)
from ..model.outer import DriverStart
from ..model.result import ContactResult
from ..model.step_solver import make_step_solver
from ..model.wall_free import solve_without_contact
from ..problems.scenes import ActuatorScene
from ..solvers.registry import DEFAULT
from .continuation import Solved, new_solved, warm_or_cold

AUTO_WHY = "auto: the built-in active set (exact)"
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
    out = solve_without_contact(chain, tol, max_outer, start,
                                engine="compiled" if kernel else "numpy", args=args)
    used = "compiled" if kernel else "compiled driver"
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
    """One continuation line (scenes of one group, in order), in the kernels."""
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


__all__ = ["solve_line", "takes"]
