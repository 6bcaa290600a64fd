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
    evidence : per candidate: converged probes, worst error, mean time (or
        why it was ruled out or dropped, and at which stage).
    confidence : the choice against the fastest other back-end that qualified:
        ``versus``, ``ratio`` (how many times slower it is, geometric mean
        over the probes), ``se`` (its standard error from the scatter over
        the probes and the spread of the repeats), ``tied``.
    ties : the candidates within the noise of the fastest, the choice among
        them made by preferring the simpler profile, then an exact back-end.
    formulation : the form the chosen pair's contact steps were probed in
        (docs/formulations.md); None: the back-end's own. :func:`lcpbench.solve`
        runs a Selection in it.
    """

    backend: str | None
    settings: str | None
    force_tol: float
    driver_tol: float
    time_s: float
    error: float
    reason: str
    evidence: list[dict] = field(default_factory=list)
    confidence: dict | None = None
    ties: list[dict] = field(default_factory=list)
    formulation: str | None = None

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in
                ("backend", "settings", "force_tol", "driver_tol", "time_s", "error", "reason",
                 "evidence", "confidence", "ties", "formulation")}
