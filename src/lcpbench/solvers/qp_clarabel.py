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

#: Clarabel's gap and feasibility tolerances per unit of lcpbench's ``eps``. lcpbench's
#: eps bounds the natural residual min(g, R) row by row; an interior point stops on its
#: duality gap, and on the contact step's near-degenerate rows (nodes within 1e-9 ℓ of
#: the wall with no reaction, beside the contact) it leaves reactions of order gap / g
#: there. On the N = 140 step (θ 150°, h 3 mm) at `high` its tolerance 1e-9 left node
#: forces 1e-2 off and lcpbench's residuals refused it in every form; 1e-12 gives 7.8e-9
#: in heights+ruiz, as close as Lemke comes (docs/formulations.md, "Interior points").
#: Where it cannot reach that (it ends AlmostSolved, say, on a badly scaled QP),
#: :func:`solve_qp` solves again at eps itself, the old contract.
GAP_FACTOR = 1e-3
#: Smallest tolerance handed to Clarabel: below it a double-precision IPM ends
#: AlmostSolved (the plain height QP from 1e-12 on) without gaining accuracy.
MIN_TOL = 1e-13
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


def translate(settings: Settings, factor: float = GAP_FACTOR) -> dict:
    """Clarabel settings for a generic accuracy request.

    ``eps`` -> ``tol_gap_abs = tol_gap_rel = tol_feas = max(factor · eps, MIN_TOL)``
    (:data:`GAP_FACTOR`; qpsolvers and cvxpy, which keep no answer of a run that does
    not reach it, ask ``factor = 1``). ``tol_ktratio`` and the infeasibility
    tolerances keep their defaults (they only decide infeasibility certificates, not
    optimality). ``eps=None`` leaves Clarabel's defaults (1e-8 everywhere, 200
    iterations).
    """
    opts: dict = {}
    if settings.eps is not None:
        tol = max(factor * float(settings.eps), MIN_TOL)
        opts.update(tol_gap_abs=tol, tol_gap_rel=tol, tol_feas=tol)
    opts.update(iteration_limits(settings))
    return opts


def _solve(clarabel, P, c, A, b, cones, opts):
    """(Clarabel's result, its setup wall time) with settings ``opts``."""
    t0 = time.perf_counter()
    cset = clarabel.DefaultSettings()
    for key, value in opts.items():
        setattr(cset, key, value)
    solver = clarabel.DefaultSolver(sp.triu(P, format="csc"), c, A, b, cones, cset)
    setup = time.perf_counter() - t0
    return solver.solve(), setup


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
    asked = {"verbose": False, **translate(settings, 1.0), **options}  # eps itself
    t0 = time.perf_counter()
    try:
        res, setup = _solve(clarabel, P, c, A, b, cones, opts)
        first = res
        if map_status(res.status) is not Status.SOLVED and asked != opts:
            # the tighter tolerance was out of reach: eps, as asked
            res, setup2 = _solve(clarabel, P, c, A, b, cones, asked)
            setup += setup2
            opts = asked
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
        x=x, y=y, status=status,
        iterations=int(res.iterations) + (int(first.iterations) if first is not res else 0),
        solve_time=float(res.solve_time) + (float(first.solve_time) if first is not res
                                            else 0.0), setup_time=setup,
        message="" if status is Status.SOLVED else f"Clarabel: {name}",
        time_source="solver",
        extra={"solver_status": name, "objective": float(res.obj_val),
               "objective_dual": float(res.obj_val_dual), "r_prim": float(res.r_prim),
               "r_dual": float(res.r_dual), "setup_time_source": "wall", "settings": opts,
               "tight_status": str(first.status).rsplit(".", 1)[-1]},
        y_rows=y_rows,
    )
