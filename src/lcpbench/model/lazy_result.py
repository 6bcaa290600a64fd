"""Results built when they are read: the fields a caller rarely reads, made at first access.

A :class:`LazyResult` is a :class:`~lcpbench.model.result.ContactResult` whose cheap
fields (the scene, α, the reactions R, F, the outer iterations, the verdict
``converged``) are set at once from the kernels' arrays, and whose other fields
(:data:`LAZY`: the step records, the reason, the certificate, the judgement,
``extra``, the node positions...) are built at the first access of any of them, by
the callable kept in its ``_build``: the complete result, made by the same functions
as before (the DriverOutput by :func:`lcpbench.model.kernel_call.kernel_output`, the
Judgement by :func:`lcpbench.model.judge.verdict_from_stats` from the judge
kernel's numbers, the result by :func:`lcpbench.model.finish.finish`). Its fields fill those
not set (a field set by hand keeps its value); the verdict set at once must be the
one built (else RuntimeError: the compiled verdict and the judge's reasons disagree).

Used by the one-wall route of :func:`lcpbench.solve` (the default back-end) and by a
batch line (:mod:`lcpbench.studies.batch_result`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .judge import Judgement
from .result import ContactResult

# ContactResult's fields built at their first access (the others are set at once)
LAZY = ("x", "y", "gaps", "gaps_lower", "steps", "reason", "certificate", "extra",
        "multipliers", "multipliers_lower", "judgement", "free_nodes", "indentation",
        "pressure")


class _Lazy:
    """A field of :class:`LazyResult` built at first access (:data:`LAZY`)."""

    def __init__(self, name: str, inner=None):
        self.name, self.inner = name, inner

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        d = obj.__dict__
        if self.name not in d and "_build" in d:  # not built yet (materialize sets the
            materialize(obj)  # fields before it drops _build: another thread's build
        if self.inner is not None:  # is seen whole); ContactResult's lazy fields (x, y...)
            return self.inner.__get__(obj, owner)
        if self.name not in d:
            raise AttributeError(self.name)
        return d[self.name]

    def __set__(self, obj, value) -> None:
        obj.__dict__[self.name] = value


class LazyResult(ContactResult):
    """A :class:`ContactResult` with the fields of :data:`LAZY` built when read (see
    the module)."""

    def __getstate__(self) -> dict:
        if "_build" in self.__dict__:
            materialize(self)
        return super().__getstate__()


for _name in LAZY:
    setattr(LazyResult, _name, _Lazy(_name, ContactResult.__dict__.get(_name)))


def lazy_result(cls: type, values: dict, build: Callable[[], ContactResult]) -> ContactResult:
    """A ``cls`` (:class:`LazyResult` or a subclass) with the fields ``values`` set and
    the others built by ``build()`` at the first access of any of them."""
    res = object.__new__(cls)
    values["_build"] = (build, values["converged"])  # (the verdict set, to check)
    res.__dict__ = values
    return res


def materialize(res: ContactResult) -> None:
    """Build every field of ``res`` (those set already keep their values)."""
    d = res.__dict__
    source = d.get("_build")
    if source is None:
        return
    build, verdict = source
    full = build()
    if full.converged != verdict:  # the two must agree
        raise RuntimeError(f"the kernel's verdict ({verdict}) is not the judge's "
                           f"({full.converged}: {full.reason}); please report this scene: "
                           f"{d.get('scene')!r}")
    for key, value in full.__dict__.items():
        d.setdefault(key, value)
    d.pop("_build", None)


def stats_judge(settled: bool, names: tuple, stats: np.ndarray, forces_upper: np.ndarray,
                forces_lower: np.ndarray, torque_residual: np.ndarray) -> Callable:
    """The ``judged_by`` of :func:`lcpbench.model.result.build_result` whose judgement is
    already made by the judge kernel (``settled``, its ``stats`` array with their
    ``names``, its reactions and torque residual):
    :func:`~lcpbench.model.judge.verdict_from_stats`;
    an answer whose driver did not converge goes to :func:`~lcpbench.model.judge.judge`
    (check 1 fails, nothing is computed)."""

    def judged(chain, alpha, fu, fl, *, tol, driver_converged, driver_reason,
               step_statuses, step_sizes, certificate) -> Judgement:
        from .judge import judge, verdict_from_stats

        if not driver_converged:
            return judge(chain, alpha, fu, fl, tol=tol, driver_converged=False,
                         driver_reason=driver_reason, step_statuses=step_statuses,
                         step_sizes=step_sizes, certificate=certificate)
        return verdict_from_stats(settled, dict(zip(names, stats.tolist(), strict=True)),
                                  forces_upper, forces_lower, torque_residual, tol=tol,
                                  driver_reason=driver_reason, step_statuses=step_statuses)

    return judged


__all__ = ["LAZY", "LazyResult", "lazy_result", "materialize", "stats_judge"]
