"""OSQP 1.x (ADMM, sparse) on the box QP, through its native Python API.

The box ``lower <= x <= upper`` becomes ``l <= A x <= u`` with ``A`` the
*selection matrix* of the constrained rows (rows with at least one finite
bound), not the identity. Rows without any bound would be dead rows of the
ADMM iteration (OSQP gives them the minimum rho) that still enlarge the KKT
factorisation and every iterate; dropping them costs nothing, and with no
constrained row at all OSQP accepts a 0 x n ``A``. In the contact step every
row carries the wall bound, so there ``A = I`` anyway. A
:class:`~lcpbench.solvers.base.LinearQP`'s rows follow the bounds' rows in ``A``.

Multipliers: OSQP's ``y`` obeys ``P x + q + Aᵀ y = 0`` with ``y_i > 0`` where
the upper bound is active, which is exactly lcpbench's signed ``y`` once
scattered back to full length (zeros on unbounded rows).

Times: ``info.setup_time`` (setup, factorisation) and ``info.solve_time +
info.polish_time`` (OSQP books polishing apart from the ADMM solve; both are
part of answering the QP) -- seconds, reported by OSQP itself.
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
    c_stdout_to_stderr,
    dist_version,
    iteration_limits,
    open_box_qp,
    prepare_rows,
)

DIST = "osqp"

#: Iteration limits when a tolerance is requested but no ``max_iter``
#: (OSQP's default 4000 is meant for its default 1e-3 accuracy).
MAX_ITER_FOR_TOL = {1e-3: 4000, 1e-6: 25_000, 1e-9: 100_000}

#: OSQP ``info.status`` -> lcpbench Status (strict: anything else is FAILED).
STATUS_MAP = {
    "solved": Status.SOLVED,
    "solved inaccurate": Status.INACCURATE,
    "maximum iterations reached": Status.MAX_ITER,
    "run time limit reached": Status.MAX_ITER,
    "primal infeasible": Status.INFEASIBLE,
    "dual infeasible": Status.INFEASIBLE,  # unbounded below: no minimiser
}


def version() -> str | None:
    """Installed version of the ``osqp`` distribution, or None."""
    return dist_version(DIST)


def map_status(status: str) -> Status:
    """Strict map of OSQP's status string onto :class:`Status`."""
    return STATUS_MAP.get(str(status).strip().lower(), Status.FAILED)


def _max_iter_for(tol: float) -> int:
    for bound in sorted(MAX_ITER_FOR_TOL, reverse=True):
        if tol >= bound:
            return MAX_ITER_FOR_TOL[bound]
    return MAX_ITER_FOR_TOL[min(MAX_ITER_FOR_TOL)]


def translate(settings: Settings) -> dict:
    """OSQP settings for a generic accuracy request.

    ``tol`` -> ``eps_abs = eps_rel = tol`` (OSQP also checks the duality gap
    against these, ``check_dualgap`` is on by default), ``polishing`` when
    ``tol <= 1e-6``, and a raised ``max_iter`` (25 000 at 1e-6, 100 000 at
    1e-9) unless ``settings.max_iter`` is given. ``tol=None`` leaves OSQP's
    defaults (eps 1e-3, 4000 iterations, no polishing).
    """
    opts: dict = {}
    if settings.eps is not None:
        tol = float(settings.eps)
        opts.update(eps_abs=tol, eps_rel=tol, polishing=tol <= 1e-6,
                    max_iter=_max_iter_for(tol))
    opts.update(iteration_limits(settings))
    return opts


def solve_qp(qp: BoxQP, settings: Settings, warm: QPWarm | None = None,
             **options) -> QPResult:
    """Solve ``qp`` with OSQP.

    Parameters
    ----------
    qp : BoxQP
    settings : Settings
        Translated by :func:`translate`.
    warm : QPWarm, optional
        ``x`` and (if given) the signed ``y``, passed to ``warm_start``.
    **options
        Raw OSQP settings, applied after the translation (they win).

    Returns
    -------
    QPResult
        Never raises on solver trouble; ``status`` says what happened.
    """
    opened, early = open_box_qp(qp, "osqp")
    if early is not None:
        return early
    P, c, lower, upper, osqp = opened
    n = c.size

    rows = qp.constrained_rows()
    m = rows.size
    A = sp.csc_matrix((np.ones(m), (np.arange(m), rows)), shape=(m, n))
    l_all, u_all = lower[rows], upper[rows]
    Ar, lr, ur = prepare_rows(qp, n)  # a LinearQP's rows, after the bounds
    if Ar is not None:
        A = sp.vstack([A, Ar], format="csc")
        l_all, u_all = np.r_[l_all, lr], np.r_[u_all, ur]
    opts = {"verbose": False, **translate(settings), **options}
    t_wall = time.perf_counter()
    try:
        solver = osqp.OSQP()
        solver.setup(P=sp.triu(P, format="csc"), q=c, A=A, l=l_all, u=u_all, **opts)
        if warm is not None:
            wy = None if warm.y is None or Ar is not None \
                else np.asarray(warm.y, dtype=float)[rows]
            solver.warm_start(x=np.asarray(warm.x, dtype=float), y=wy)
        with c_stdout_to_stderr():  # OSQP 1.1 prints "Polishing not needed" regardless
            res = solver.solve(raise_error=False)
    except Exception as exc:  # noqa: BLE001 - never raise on solver trouble (OSQPException, ...)
        return QPResult.failure(n, Status.FAILED, f"OSQP raised {type(exc).__name__}: {exc}",
                                setup_time=time.perf_counter() - t_wall, time_source="wall")
    info = res.info
    status = map_status(info.status)
    x = np.array(res.x, dtype=float)
    y = np.zeros(n)
    y_all = np.asarray(res.y, dtype=float)
    if m:
        y[rows] = y_all[:m]
    y_rows = None if Ar is None else y_all[m:].copy()
    if status in (Status.INFEASIBLE, Status.FAILED) or not np.all(np.isfinite(x)):
        # x and y hold certificates or garbage: do not pass them on as an answer
        x = np.full(n, np.nan)
        y = np.full(n, np.nan)
        y_rows = None if y_rows is None else np.full(y_rows.size, np.nan)
        if status is Status.SOLVED:
            status = Status.FAILED
    message = "" if status is Status.SOLVED else f"OSQP: {info.status}"
    return QPResult(
        x=x, y=y, status=status, iterations=int(info.iter),
        solve_time=float(info.solve_time) + float(info.polish_time),
        setup_time=float(info.setup_time), message=message, time_source="solver",
        extra={"solver_status": str(info.status), "status_polish": int(info.status_polish),
               "objective": float(info.obj_val), "prim_res": float(info.prim_res),
               "dual_res": float(info.dual_res), "duality_gap": float(info.duality_gap),
               "polish_time": float(info.polish_time), "rho_updates": int(info.rho_updates),
               "settings": opts},
        y_rows=y_rows,
    )
