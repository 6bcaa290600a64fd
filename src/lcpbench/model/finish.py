"""The judged result of a driver run: the end of every solve (:func:`lcpbench.solve`,
its escalations and a batch's lines)."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

from .judge import judge, judged_in
from .result import ContactResult, build_result


def finish(scene, chain, out, *, solver: str, method: str, tol: float, elapsed: float,
           settings, engine: str, why: str | None,
           judge_args: tuple | None = None,
           pressure_limit: float | None = None,
           judged_by: Callable | None = None, route: str = "") -> ContactResult:
    """The judged result of a driver run.

    Judged by :func:`lcpbench.model.judge.judge` whichever back-end and engine solved
    the steps (the judge kernel, independent of the solve kernel; in increments from
    ``LARGE_N`` links). ``judge_args``: the chain's arrays for the judge kernel, when the
    caller has them (:func:`lcpbench.model.judge.chain_args`). ``judged_by``:
    the judgement already made (a batch line's, from the judge kernel's numbers), in
    place of the judge call. ``engine`` (what produced ``out``), the judge that ran and
    ``route`` are the result's typed fields of the same names."""
    if not out.converged and getattr(scene, "theta", 0) > 180:
        out.reason = ("theta > 180 deg: the end links start beyond the vertical, where the "
                      "linearisation of eq. (20) is singular for a cold start; start='ramp' "
                      f"follows the load from zero instead ({out.reason})")
    where = judged_in(chain)
    if judged_by is None:
        judged_by = judge
        if judge_args is not None and where == "heights":
            judged_by = partial(judge, args=judge_args)
    res = build_result(scene, chain, out, solver=solver, method=method, tol=tol,
                       time_s=elapsed, judged_by=judged_by, route=route, engine=engine,
                       judge=where)
    res.extra["last_step"] = out.last_step  # what a continuation hands the next scene
    res.extra["settings"] = settings if isinstance(settings, str) else "custom"
    res.pressure_limit = pressure_limit
    if why is not None:
        res.extra["auto"] = why
    return res


__all__ = ["finish"]
