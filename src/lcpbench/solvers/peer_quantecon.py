"""QuantEcon's Lemke (``quantecon.optimize.lcp_lemke``) as an LCP back-end: a peer.

A public numba implementation of Lemke's complementary pivoting with the
lexicographic rule (covering vector of ones), on a dense tableau of shape
(n, 2n + 2). Install with ``pip install 'lcpbench[peer]'``.

Its status codes map onto lcpbench's: 0 (solution found) → SOLVED,
1 (iteration limit) → MAX_ITER, 2 (secondary ray) → RAY. As for every
back-end, lcpbench's judge (:mod:`lcpbench.solvers.judge`) then recomputes
the natural residual from ``z`` alone and demotes a SOLVED whose residual is
too large; ``w`` is recomputed as ``M z + q`` (lcp_lemke returns z only).

Settings: Lemke is exact, so the accuracy profile does not change its
pivots; ``settings.max_iter`` is its pivot budget, otherwise the budget of
lcpbench's own Lemke, max(100, 50 n), rather than QuantEcon's 10⁶ (on
Siconos' ``lcp_tobenna``, n = 40, it had not ended after 10⁶ pivots, 8.7 s,
where lcpbench's Lemke takes 127: same rule, same budget for both). Its pivot tolerances (``PivOptions``) stay at QuantEcon's
defaults. A warm start is ignored. The first call in a process compiles the
numba code (seconds); the sweep's warm-up solve takes that cost, not a
timed run.
"""

from __future__ import annotations

import time

import numpy as np

from .base import LCPSolution, Status

#: lcp_lemke's status codes
_STATUS = {0: (Status.SOLVED, ""), 1: (Status.MAX_ITER, "iteration limit reached"),
           2: (Status.RAY, "secondary ray termination")}


def solve_lcp(M, q, settings, warm=None, **options) -> LCPSolution:
    """The back-end interface (see the module docstring)."""
    from quantecon.optimize import lcp_lemke

    t0 = time.perf_counter()
    M = np.ascontiguousarray(M.toarray() if hasattr(M, "toarray") else M, dtype=float)
    q = np.ascontiguousarray(q, dtype=float)
    kw = dict(options)
    kw.setdefault("max_iter", int(settings.max_iter) if settings.max_iter
                  else max(100, 50 * q.size))
    t1 = time.perf_counter()
    res = lcp_lemke(M, q, **kw)
    t2 = time.perf_counter()
    z = np.asarray(res.z, float).copy()
    status, msg = _STATUS.get(int(res.status),
                              (Status.FAILED, f"unknown lcp_lemke status {res.status}"))
    if msg:
        msg = f"quantecon lcp_lemke: {msg} after {int(res.num_iter)} pivots"
    return LCPSolution(z=z, w=M @ z + q, status=status, iterations=int(res.num_iter),
                       solve_time=t2 - t1, setup_time=t1 - t0, message=msg,
                       extra={"time_source": "wall"})
