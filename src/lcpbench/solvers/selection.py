"""A chosen back-end: what :func:`lcpbench.select_backend` returns and
:func:`lcpbench.solve` accepts as ``solver=``.

It lives with the solvers (not with the benchmark that measures it) so the
library call can take one without importing the harness or reading a store.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Selection:
    """The chosen back-end and why.

    Attributes
    ----------
    backend, settings : the choice (None when no candidate qualifies).
    force_tol : the force accuracy asked for: the largest relative error of the
        total reaction F = ΣR (eq. 30) over the probes.
    driver_tol : the driver tolerance the probes ran at (rad).
    time_s : geometric-mean wall time of one solve over the probes (s).
    error : largest force error over the probes.
    reason : one line saying why.
    evidence : per candidate: converged probes, worst error, mean time.
    """

    backend: str | None
    settings: str | None
    force_tol: float
    driver_tol: float
    time_s: float
    error: float
    reason: str
    evidence: list[dict] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in
                ("backend", "settings", "force_tol", "driver_tol", "time_s", "error", "reason",
                 "evidence")}
