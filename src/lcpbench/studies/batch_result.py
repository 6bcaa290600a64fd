"""The results of a line solved in one kernel call, built when they are read.

:class:`LineResult` is a :class:`~lcpbench.model.lazy_result.LazyResult` whose
cheap fields (the scene, α, the reactions R, F, the outer iterations, the
verdict ``converged``) are set from the kernel's arrays
(:mod:`lcpbench.model.batch_kernel`; :mod:`lcpbench.model.profile_line` for a line
against a wall of any profile) when the batch returns, and whose other
fields (the step records, the reason, the certificate, the judgement, ``extra``,
the node positions) are built at the first access of any of them: from the same
arrays, by the same functions as a single solve (the DriverOutput by
:func:`lcpbench.model.kernel_call.kernel_output`, the Judgement by
:func:`lcpbench.model.judge.verdict_from_stats` from the judge kernel's
numbers, the result by :func:`lcpbench.model.finish.finish`). So a batch that is only
read for its forces builds no Python object per scene but the result itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ..model.finish import finish
from ..model.kernel_call import kernel_output
from ..model.lazy_result import LAZY, LazyResult, lazy_result, materialize, stats_judge
from ..model.outer import DriverOutput
from ..model.profile import split_reactions
from ..model.result import ContactResult
from ..solvers.registry import DEFAULT, get_settings

AUTO_WHY = "auto: the built-in active set (exact)"
#: the ``route`` of a line's results (a batch's, not a plan's: lcpbench.plan.ROUTES)
LINE_KERNEL = "line kernel"


@dataclass
class LineOutput:
    """What the line kernel wrote (the arrays of :func:`batch_kernel.solve_line`,
    by name) and how it was called."""

    scenes: list
    arrays: dict
    tol: float
    max_outer: int
    settings: str
    predictor: str
    time_s: float  # the kernel's wall time per scene (the line's, shared evenly)
    kernel: object  # the batch kernel module (its constants)
    channel: bool = False  # the line's scenes are in a channel (a lower wall too)


class LineResult(LazyResult):
    """A :class:`ContactResult` of a batch line (see the module)."""


@dataclass(frozen=True)
class Stopped:
    """A scene the line kernel left to the caller: it stopped on it, the scene alone in
    its plane. ``bail``: the solve kernel's bail code of its contact solve (the cold one,
    but for a scene started from its kin: :func:`lcpbench.studies.batch._kin`; a row of
    sections has none) (:data:`lcpbench.model.kernel_call.BAIL_REASONS`), where the
    kernel stopped there;
    None where the wall-free search stopped."""

    bail: int | None


def results(line: LineOutput) -> list[ContactResult | Stopped]:
    """One :class:`LineResult` per scene of the line, in its order; :class:`Stopped` for a
    scene the kernel left to the caller (``kept`` −1: it stopped on a scene alone in its
    plane)."""
    A = line.arrays
    left = A["kept"] < 0
    kept = np.where(left, 0, A["kept"])  # (the rows of the left scenes are not read)
    code = A["o_code"][kept]
    judged = code == line.kernel.CONVERGED
    settled = judged & (A["j_code"][kept] == line.kernel.SETTLED)
    # the reported reactions: the judge's (round-off set to zero), else the driver's R
    # (zero where the driver failed, as outer.failed_output)
    forces = np.where(settled[:, None], A["j_fu"][kept],
                      np.where(judged[:, None], A["o_R"][kept], 0.0))
    lower = [None] * len(line.scenes)
    if line.channel:  # the lower wall's too; a driver's answer the judge did not settle:
        # its net R split as the single solve's driver output splits it
        lower = np.where(settled[:, None], A["j_fl"][kept], 0.0)
        for s in np.flatnonzero(judged & ~settled & ~left):
            row = kept[s]
            forces[s], lower[s] = split_reactions(line.scenes[s].chain(), A["o_R"][row],
                                                  A["o_u"][row])
    totals = forces.sum(axis=1).tolist()
    alphas = A["o_alpha"][kept]
    conv = A["conv"][kept].tolist()
    counts = A["o_count"][kept].tolist()
    links, tol, t = alphas.shape[1], line.tol, line.time_s
    return [lazy_result(LineResult, {
        "scene": scene, "links": links, "alpha": alphas[s], "forces": forces[s],
        "forces_lower": lower[s], "total_force": totals[s], "outer_iterations": counts[s],
        "converged": conv[s], "solver": DEFAULT, "method": "globalised", "tol": tol,
        "time_s": t, "pressure_limit": None, "route": LINE_KERNEL, "engine": "compiled",
        "judge": "heights", "retries": ()}, partial(_built, line, s))
        if not left[s] else _stopped(line, s) for s, scene in enumerate(line.scenes)]


def _stopped(line: LineOutput, s: int) -> Stopped:
    code = int(line.arrays["o_code"][s])  # (row s: the scene's cold attempt)
    return Stopped(None if code == line.kernel.STOPPED_FREE else code)


def driver_output(line: LineOutput, row: int, chain) -> DriverOutput:
    """The DriverOutput of the attempt in ``row``: the unconstrained arc's, else the
    solve kernel's outputs as a single solve builds them
    (:func:`lcpbench.model.kernel_call.kernel_output`), with the wall-free search's reason."""
    A, k = line.arrays, line.kernel
    kind = int(A["o_kind"][row])
    if kind == k.ARC:
        n = chain.free_nodes.size
        return DriverOutput(A["o_alpha"][row], np.zeros(n), np.zeros(n), True,
                            "no contact: the unconstrained arc clears every wall and there "
                            "is no load")
    count, off = int(A["o_count"][row]), int(A["o_off"][row])
    reason = "converged" if kind == k.CONTACT else (
        "no contact: the equilibrium without walls clears every wall (found by banded "
        "solves, no LCP)")
    return kernel_output(chain, int(A["o_code"][row]), A["o_alpha"][row], A["o_rup"][row],
                         A["o_rlo"][row], A["o_u"][row], A["o_sig"][row],
                         A["records"][:, off:off + count], count, A["o_res"][row],
                         A["o_R"][row], elapsed=line.time_s,
                         settings=get_settings(line.settings).name,
                         max_outer=line.max_outer, reason=reason, tol=line.tol)


def _judged(line: LineOutput, row: int):
    """The ``judged_by`` of the attempt in ``row``: the judge kernel's numbers of the
    batch (:func:`lcpbench.model.lazy_result.stats_judge`)."""
    A, k = line.arrays, line.kernel
    return stats_judge(int(A["j_code"][row]) == k.SETTLED, k.STATS, A["j_stats"][row],
                       A["j_fu"][row].copy(), A["j_fl"][row].copy(), A["j_tres"][row].copy())


def _attempt(line: LineOutput, s: int, row: int) -> ContactResult:
    scene = line.scenes[s]
    chain = scene.chain()
    out = driver_output(line, row, chain)
    return finish(scene, chain, out, solver=DEFAULT, method="globalised", tol=line.tol,
                  elapsed=line.time_s, settings=line.settings, engine="compiled",
                  why=AUTO_WHY,
                  judged_by=_judged(line, row), route=LINE_KERNEL)


def _built(line: LineOutput, s: int) -> ContactResult:
    """The complete result of scene ``s`` of the line (its LineResult's ``_build``)."""
    A = line.arrays
    full = _attempt(line, s, int(A["kept"][s]))
    label = "cold" if A["base"][s] < 0 else line.predictor
    if A["failed"][s] >= 0:  # the warm start failed: the cold answer, with what it cost
        failed = _attempt(line, s, int(A["failed"][s]))
        label = f"{line.predictor}, failed; cold"
        full.extra["discarded"] = {
            "outer_iterations": failed.outer_iterations,
            "inner_iterations": failed.inner_iterations,
            "time_s": failed.time_s, "reason": failed.reason}
    full.extra["continuation"] = label
    return full


__all__ = ["AUTO_WHY", "LAZY", "LineOutput", "LineResult", "Stopped", "materialize", "results"]
