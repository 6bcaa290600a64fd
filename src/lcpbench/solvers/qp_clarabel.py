"""Clarabel (interior point, sparse) on the box QP, through its native API.

Clarabel solves ``min ½xᵀPx + qᵀx  s.t.  A x + s = b, s ∈ K``. Each finite
upper bound is a row ``x_i + s = u_i`` and each finite lower bound a row
``-x_i + s = -l_i``, all in one ``NonnegativeConeT``. Its dual ``z >= 0``
satisfies ``P x + q + Aᵀ z = 0``, so the signed multiplier is
``y_i = z_upper,i - z_lower,i`` (zero on rows without a bound). A
:class:`~lcpbench.solvers.base.LinearQP`'s equality rows go in a ``ZeroConeT``, its
other rows' finite sides beside the bounds in the ``NonnegativeConeT``.

Times: ``solve_time`` is Clarabel's own (seconds; it covers equilibration,
factorisation and the iterations). Clarabel reports no setup time, so
``setup_time`` is wall time around building the solver object and
``extra["setup_time_source"] == "wall"``. Warm starts are not supported by
Clarabel; ``warm`` is accepted and ignored.
"""

from __future__ import annotations

import time

import numpy as np

from ..linalg import sparse as sp  # scipy.sparse, imported at the first QP
from .base import (
    BoxQP,
    QPResult,
    QPWarm,
    Settings,
    Status,
    dist_version,
    iteration_limits,
    open_box_qp,
    prepare_rows,
)

DIST = "clarabel"

#: Smallest tolerance handed to Clarabel. Below ~1e-10 a double-precision IPM
#: stalls on badly conditioned problems (AlmostSolved / InsufficientProgress)
#: without gaining accuracy; lcpbench's tightest profile (1e-9) is above it.
MIN_TOL = 1e-10

#: Clarabel ``SolverStatus`` name -> lcpbench Status (strict).
STATUS_MAP = {
    "Solved": Status.SOLVED,
    "AlmostSolved": Status.INACCURATE,
    "MaxIterations": Status.MAX_ITER,
    "MaxTime": Status.MAX_ITER,
    "PrimalInfeasible": Status.INFEASIBLE,
    "DualInfeasible": Status.INFEASIBLE,  # unbounded below
    # AlmostPrimalInfeasible, AlmostDualInfeasible, NumericalError,
    # InsufficientProgress, CallbackTerminated, Unsolved -> FAILED
}


def version() -> str | None:
    """Installed version of the ``clarabel`` distribution, or None."""
    return dist_version(DIST)


def map_status(status) -> Status:
    """Strict map of a Clarabel status (enum or its name) onto :class:`Status`."""
    name = str(status).rsplit(".", 1)[-1]
    return STATUS_MAP.get(name, Status.FAILED)


def translate(settings: Settings) -> dict:
    """Clarabel settings for a generic accuracy request.

    ``tol`` -> ``tol_gap_abs = tol_gap_rel = tol_feas = max(tol, MIN_TOL)``.
    ``tol_ktratio`` and the infeasibility tolerances keep their defaults (they
    only decide infeasibility certificates, not optimality). ``tol=None``
    leaves Clarabel's defaults (1e-8 everywhere, 200 iterations).
    """
    opts: dict = {}
    if settings.eps is not None:
        tol = max(float(settings.eps), MIN_TOL)
        opts.update(tol_gap_abs=tol, tol_gap_rel=tol, tol_feas=tol)
    opts.update(iteration_limits(settings))
    return opts


def solve_qp(qp: BoxQP, settings: Settings, warm: QPWarm | None = None,
             **options) -> QPResult:
    """Solve ``qp`` with Clarabel.

    Parameters
    ----------
    qp : BoxQP
    settings : Settings
        Translated by :func:`translate`.
    warm : QPWarm, optional
        Ignored (Clarabel has no warm start).
    **options
        Raw Clarabel settings (attributes of ``DefaultSettings``), applied after
        the translation.
    """
    opened, early = open_box_qp(qp, "clarabel")
    if early is not None:
        return early
    P, c, lower, upper, clarabel = opened
    n = c.size

    iu = np.flatnonzero(np.isfinite(upper))
    il = np.flatnonzero(np.isfinite(lower))
    mu, ml = iu.size, il.size
    A = sp.csc_matrix(
        (np.r_[np.ones(mu), -np.ones(ml)], (np.arange(mu + ml), np.r_[iu, il])),
        shape=(mu + ml, n))
    b = np.r_[upper[iu], -lower[il]]
    cones = [clarabel.NonnegativeConeT(mu + ml)] if mu + ml else []
    Ar, lr, ur = prepare_rows(qp, n)
    if Ar is not None:  # a LinearQP: equalities (a zero cone) first, then its sides
        eq, ru, rl = qp.row_kinds()
        A = sp.vstack([Ar[eq], A, Ar[ru], -Ar[rl]], format="csc")
        b = np.r_[ur[eq], b, ur[ru], -lr[rl]]
        cones = ([clarabel.ZeroConeT(eq.size)] if eq.size else []) + \
            ([clarabel.NonnegativeConeT(mu + ml + ru.size + rl.size)]
             if mu + ml + ru.size + rl.size else [])
    opts = {"verbose": False, **translate(settings), **options}
    t0 = time.perf_counter()
    try:
        cset = clarabel.DefaultSettings()
        for key, value in opts.items():
            setattr(cset, key, value)
        solver = clarabel.DefaultSolver(sp.triu(P, format="csc"), c, A, b, cones, cset)
        setup = time.perf_counter() - t0
        res = solver.solve()
    except BaseException as exc:  # pyo3 PanicException derives from BaseException
        if isinstance(exc, (KeyboardInterrupt, SystemExit)):
            raise
        return QPResult.failure(n, Status.FAILED, f"Clarabel raised {type(exc).__name__}: {exc}",
                                setup_time=time.perf_counter() - t0, time_source="wall")
    status = map_status(res.status)
    x = np.array(res.x, dtype=float)
    z = np.array(res.z, dtype=float)
    y = np.zeros(n)
    y_rows = None
    if Ar is not None:
        y_rows = np.zeros(Ar.shape[0])
        y_rows[eq] = z[:eq.size]
        z = z[eq.size:]
        y_rows[ru] += z[mu + ml: mu + ml + ru.size]
        y_rows[rl] -= z[mu + ml + ru.size:]
    y[iu] += z[:mu]
    y[il] -= z[mu:mu + ml]
    if status in (Status.INFEASIBLE, Status.FAILED) or not np.all(np.isfinite(x)):
        x = np.full(n, np.nan)
        y = np.full(n, np.nan)
        y_rows = None if y_rows is None else np.full(y_rows.size, np.nan)
        if status is Status.SOLVED:
            status = Status.FAILED
    name = str(res.status).rsplit(".", 1)[-1]
    return QPResult(
        x=x, y=y, status=status, iterations=int(res.iterations),
        solve_time=float(res.solve_time), setup_time=setup,
        message="" if status is Status.SOLVED else f"Clarabel: {name}",
        time_source="solver",
        extra={"solver_status": name, "objective": float(res.obj_val),
               "objective_dual": float(res.obj_val_dual), "r_prim": float(res.r_prim),
               "r_dual": float(res.r_dual), "setup_time_source": "wall", "settings": opts},
        y_rows=y_rows,
    )
