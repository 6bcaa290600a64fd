"""The results of a line solved in one kernel call, built when they are read.

:class:`LineResult` is a :class:`~lcpbench.model.result.ContactResult` whose
cheap fields (the scene, α, the reactions R, F, the outer iterations, the
verdict ``converged``) are set from the kernel's arrays
(:mod:`lcpbench.model.batch_kernel`) when the batch returns, and whose other
fields (the step records, the reason, the certificate, the judgement, ``extra``,
the node positions) are built at the first access of any of them: from the same
arrays, by the same functions as a single solve (the DriverOutput as
:func:`lcpbench.model.compiled.run_compiled` builds it, the Judgement by
:func:`lcpbench.model.judge_compiled.verdict_from_stats` from the judge kernel's
numbers, the result by :func:`lcpbench.api.finish`). So a batch that is only
read for its forces builds no Python object per scene but the result itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from ..api import finish
from ..model.driver import DriverOutput, StepRecord, _fail
from ..model.judge_compiled import verdict_from_stats
from ..model.result import ContactResult
from ..solvers.base import Status, StepSolution
from ..solvers.registry import DEFAULT, get_settings

AUTO_WHY = "auto: the built-in active set (exact)"
_SOLVED = Status.SOLVED.value
_RESIDUALS = ("natural", "min_gap", "min_reaction", "complementarity", "term_size")
# ContactResult's fields built at their first access (the others are set at once)
LAZY = ("x", "y", "gaps", "gaps_lower", "steps", "reason", "certificate", "extra",
        "multipliers", "multipliers_lower", "judgement", "free_nodes", "indentation",
        "pressure")


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


class _Lazy:
    """A field of :class:`LineResult` built at first access (:data:`LAZY`)."""

    def __init__(self, name: str, inner=None):
        self.name, self.inner = name, inner

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        d = obj.__dict__
        if self.name not in d:
            if "_line" not in d:
                raise AttributeError(self.name)
            materialize(obj)
        if self.inner is not None:  # ContactResult's own lazy fields (x, y, gaps...)
            return self.inner.__get__(obj, owner)
        return d[self.name]

    def __set__(self, obj, value) -> None:
        obj.__dict__[self.name] = value


class LineResult(ContactResult):
    """A :class:`ContactResult` of a batch line (see the module)."""

    def __getstate__(self) -> dict:
        if "_line" in self.__dict__:
            materialize(self)
        return super().__getstate__()


for _name in LAZY:
    setattr(LineResult, _name, _Lazy(_name, ContactResult.__dict__.get(_name)))


def results(line: LineOutput) -> list[ContactResult]:
    """One :class:`LineResult` per scene of the line, in its order."""
    A = line.arrays
    kept = A["kept"]
    code = A["o_code"][kept]
    judged = code == line.kernel.CONVERGED
    settled = judged & (A["j_code"][kept] == line.kernel.SETTLED)
    # the reported reactions: the judge's (round-off set to zero), else the driver's R
    # (zero where the driver failed, as driver._fail)
    forces = np.where(settled[:, None], A["j_fu"][kept],
                      np.where(judged[:, None], A["o_R"][kept], 0.0))
    totals = forces.sum(axis=1).tolist()
    alphas = A["o_alpha"][kept]
    conv = A["conv"][kept].tolist()
    counts = A["o_count"][kept].tolist()
    out: list[ContactResult] = []
    new, links, tol, t = object.__new__, alphas.shape[1], line.tol, line.time_s
    for s, scene in enumerate(line.scenes):
        r = new(LineResult)
        r.__dict__ = {
            "scene": scene, "links": links, "alpha": alphas[s], "forces": forces[s],
            "forces_lower": None, "total_force": totals[s], "outer_iterations": counts[s],
            "converged": conv[s], "solver": DEFAULT, "method": "globalised", "tol": tol,
            "time_s": t, "pressure_limit": None, "_line": (line, s)}
        out.append(r)
    return out


def driver_output(line: LineOutput, row: int, chain) -> DriverOutput:
    """The DriverOutput of the attempt in ``row``, as run_compiled (and
    solve_without_contact) build it from the solve kernel's outputs."""
    A, k = line.arrays, line.kernel
    n = chain.free_nodes.size
    kind, code = int(A["o_kind"][row]), int(A["o_code"][row])
    if kind == k.ARC:
        return DriverOutput(A["o_alpha"][row], np.zeros(n), np.zeros(n), True,
                            "no contact: the unconstrained arc clears every wall and there "
                            "is no load")
    count, off = int(A["o_count"][row]), int(A["o_off"][row])
    share = line.time_s / max(count, 1)
    cols = A["records"][:, off:off + count].T.tolist()
    steps = [StepRecord(int(it), _SOLVED, share, 0.0, step, dalpha, energy)
             for it, step, dalpha, energy in cols]
    alpha = A["o_alpha"][row]
    if code == k.CONVERGED:
        R, r_up, r_lo, sigma = (A[f][row] for f in ("o_R", "o_rup", "o_rlo", "o_sig"))
        sol = StepSolution(A["o_u"][row], r_up, r_lo, Status.SOLVED,
                           iterations=steps[-1].iterations, solve_time=share,
                           active_upper=sigma > 0, active_lower=sigma < 0, time_source="wall",
                           backend=DEFAULT, settings=get_settings(line.settings).name,
                           residuals=dict(zip(_RESIDUALS, A["o_res"][row].tolist(),
                                              strict=True)), forces_net=R)
        reason = "converged" if kind == k.CONTACT else (
            "no contact: the equilibrium without walls clears every wall (found by banded "
            "solves, no LCP)")
        return DriverOutput(alpha, R.copy(), np.zeros(n), True, reason, steps, last_step=sol,
                            multipliers_upper=r_up, multipliers_lower=r_lo)
    if code == k.NO_FIT:
        return _fail(chain.rest_alpha.copy(), n, steps, "cannot fit the chain between the walls")
    if code == k.LINE_SEARCH:
        return _fail(alpha, n, steps, "line search failed: no decrease of the energy along "
                                      "the step")
    return _fail(alpha, n, steps, f"no convergence in {line.max_outer} outer iterations "
                                  f"(last max|Δα| = {steps[-1].max_dalpha:.2e} rad)")


def _judged(line: LineOutput, row: int, chain, alpha, forces_upper, forces_lower, *,
            tol, driver_converged, driver_reason, step_statuses, step_sizes, certificate):
    """The Judgement from the judge kernel's numbers of the batch (build_result's
    ``judged_by``); an answer whose driver did not converge: the numpy judge, as
    judge_fast hands it on."""
    from ..model.judge_compiled import judge_fast

    if not driver_converged:
        return judge_fast(chain, alpha, forces_upper, forces_lower, tol=tol,
                          driver_converged=False, driver_reason=driver_reason,
                          step_statuses=step_statuses, step_sizes=step_sizes,
                          certificate=certificate)
    A, k = line.arrays, line.kernel
    stats = dict(zip(k.STATS, A["j_stats"][row].tolist(), strict=True))
    return verdict_from_stats(int(A["j_code"][row]) == k.SETTLED, stats,
                              A["j_fu"][row].copy(), A["j_fl"][row].copy(),
                              A["j_tres"][row].copy(), tol=tol, driver_reason=driver_reason,
                              step_statuses=step_statuses)


def _attempt(line: LineOutput, s: int, row: int) -> ContactResult:
    scene = line.scenes[s]
    chain = scene.chain()
    out = driver_output(line, row, chain)
    return finish(scene, chain, out, solver=DEFAULT, method="globalised", tol=line.tol,
                  elapsed=line.time_s, settings=line.settings, engine="compiled",
                  compiled_judge=True, why=AUTO_WHY,
                  judged_by=partial(_judged, line, row))


def materialize(res: LineResult) -> None:
    """Build every field of ``res`` (those set already keep their values)."""
    d = res.__dict__
    source = d.pop("_line", None)
    if source is None:
        return
    line, s = source
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
    full.extra["batch"] = "line kernel"
    if full.converged != d.get("converged", full.converged):  # the two must agree
        raise RuntimeError(f"the line kernel's verdict ({d['converged']}) is not the judge's "
                           f"({full.converged}: {full.reason}); please report this scene: "
                           f"{line.scenes[s]!r}")
    for key, value in full.__dict__.items():
        d.setdefault(key, value)


__all__ = ["LAZY", "LineOutput", "LineResult", "materialize", "results"]
