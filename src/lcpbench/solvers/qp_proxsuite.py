"""ProxSuite ProxQP (proximal augmented Lagrangian) on the box QP.

Two variants, chosen by ``variant=``:

``"dense"`` (default)
    ``proxqp.dense.QP(n, 0, 0, box_constraints=True)``: ProxQP's native box
    constraints, ``l_box <= x <= u_box`` on all ``n`` rows, with ``±inf`` on
    rows without a bound (0.8.0 accepts infinite bounds; no sentinel is
    needed). ``box=False`` uses the selection matrix ``C`` instead, as the
    sparse variant does.
``"sparse"``
    ``proxqp.sparse.QP(n, 0, m)`` with ``C`` the m x n selection matrix of
    the rows with a finite bound, and ``l <= C x <= u`` (again ±inf allowed).

A :class:`~lcpbench.solvers.base.LinearQP`'s equality rows are ProxQP's ``A``, its
other rows join ``C`` (after the bounds' rows in the sparse variant).

Multipliers: ProxQP's ``z`` obeys ``H x + g + Cᵀ z (+ z_box) = 0`` with
``z > 0`` at an upper bound: lcpbench's signed ``y`` (scattered back to full
length for ``C``). Times: ``info.setup_time`` and ``info.solve_time`` are
reported by ProxQP in MICROseconds when ``settings.compute_timings`` is on
(always switched on here) and converted to seconds.

Warm start: ``InitialGuess.WARM_START`` with ``x`` and ``z``. In 0.8.0 the
dense box variant checks a warm ``z`` against ``n_in`` (= 0) although its
result ``z`` has the ``n`` box entries, so with native box constraints only
``x`` is warm-started (``extra["warm_dual"] = False``); use ``box=False`` to
warm-start the multipliers too.
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from ..linalg import sparse as sp  # scipy.sparse, imported at the first QP
from .base import (
    BoxQP,
    QPResult,
    QPWarm,
    Settings,
    Status,
    dist_version,
    open_box_qp,
    prepare_rows,
)

DIST = "proxsuite"
VARIANTS = ("dense", "sparse")

#: ``QPSolverOutput`` name -> lcpbench Status (strict; ProxQP has no
#: "inaccurate" output).
STATUS_MAP = {
    "PROXQP_SOLVED": Status.SOLVED,
    "PROXQP_MAX_ITER_REACHED": Status.MAX_ITER,
    "PROXQP_PRIMAL_INFEASIBLE": Status.INFEASIBLE,
    "PROXQP_DUAL_INFEASIBLE": Status.INFEASIBLE,  # unbounded below
    # the problem was infeasible; x is the closest primal-feasible point
    "PROXQP_SOLVED_CLOSEST_PRIMAL_FEASIBLE": Status.INFEASIBLE,
    # PROXQP_NOT_RUN -> FAILED
}


def version() -> str | None:
    """Installed version of the ``proxsuite`` distribution, or None."""
    return dist_version(DIST)


def map_status(status) -> Status:
    """Strict map of a ProxQP ``QPSolverOutput`` (or its name) onto :class:`Status`."""
    name = getattr(status, "name", None) or str(status).rsplit(".", 1)[-1]
    return STATUS_MAP.get(name, Status.FAILED)


def translate(settings: Settings) -> dict:
    """ProxQP settings for a generic accuracy request.

    ``tol`` -> ``eps_abs = eps_rel = tol`` (ProxQP's own default is absolute
    only, eps_rel = 0; lcpbench's tolerance is absolute and relative alike,
    as for OSQP), and the duality gap is checked too:
    ``check_duality_gap=True``, ``eps_duality_gap_abs = eps_duality_gap_rel
    = tol``. ``tol=None`` leaves ProxQP's defaults (eps_abs 1e-5, no gap
    check, 10 000 iterations).
    """
    opts: dict = {}
    if settings.eps is not None:
        tol = float(settings.eps)
        opts.update(eps_abs=tol, eps_rel=tol, check_duality_gap=True,
                    eps_duality_gap_abs=tol, eps_duality_gap_rel=tol)
    if settings.max_iter is not None:
        opts["max_iter"] = int(settings.max_iter)
    return opts


def solve_qp(qp: BoxQP, settings: Settings, warm: QPWarm | None = None, *,
             variant: str = "dense", box: bool = True, **options) -> QPResult:
    """Solve ``qp`` with ProxQP.

    Parameters
    ----------
    qp : BoxQP
    settings : Settings
        Translated by :func:`translate`.
    warm : QPWarm, optional
        Warm start (``InitialGuess.WARM_START``); see the module note on ``z``.
    variant : {"dense", "sparse"}
    box : bool
        Dense variant only: native box constraints (True) or selection ``C``.
    **options
        Raw ProxQP settings (attributes of ``qp.settings``), applied last.
    """
    if variant not in VARIANTS:
        raise ProblemError(f"variant must be one of {VARIANTS}, got {variant!r}")
    opened, early = open_box_qp(qp, "proxsuite.proxqp")
    if early is not None:
        return early
    P, c, lower, upper, proxqp = opened
    n = c.size

    native_box = variant == "dense" and box
    rows = np.arange(n) if native_box else qp.constrained_rows()
    m = rows.size
    opts = {"verbose": False, **translate(settings), **options, "compute_timings": True}
    warm_dual = False
    Ar, lr, ur = prepare_rows(qp, n)  # a LinearQP: its equalities as A, the rest in C
    eq, ri = np.zeros(0, int), np.zeros(0, int)
    if Ar is not None:
        eq, ru, rl = qp.row_kinds()
        ri = np.union1d(ru, rl)
    Ae, be = (Ar[eq], ur[eq]) if eq.size else (None, None)
    ne, ni = eq.size, ri.size
    try:
        if variant == "dense":
            H = P.toarray()
            Ae = None if Ae is None else Ae.toarray()
            Ci = Ar[ri].toarray() if ni else np.zeros((0, n))
            if native_box:
                solver = proxqp.dense.QP(n, ne, ni, True)
                init_args = (H, c, Ae, be, Ci if ni else None, lr[ri] if ni else None,
                             ur[ri] if ni else None, lower, upper)
            else:
                C = np.vstack([np.eye(n)[rows], Ci])
                solver = proxqp.dense.QP(n, ne, m + ni)
                init_args = (H, c, Ae, be, C if m + ni else None,
                             np.r_[lower[rows], lr[ri] if ni else []] if m + ni else None,
                             np.r_[upper[rows], ur[ri] if ni else []] if m + ni else None)
        else:
            C = sp.csc_matrix((np.ones(m), (np.arange(m), rows)), shape=(m, n))
            if ni:
                C = sp.vstack([C, Ar[ri]], format="csc")
            solver = proxqp.sparse.QP(n, ne, m + ni)
            init_args = (P, c, None if Ae is None else sp.csc_matrix(Ae), be,
                         C if m + ni else None,
                         np.r_[lower[rows], lr[ri] if ni else []] if m + ni else None,
                         np.r_[upper[rows], ur[ri] if ni else []] if m + ni else None)
        for key, value in opts.items():
            setattr(solver.settings, key, value)
        if warm is not None:
            solver.settings.initial_guess = proxqp.InitialGuess.WARM_START
        solver.init(*init_args)
        if warm is None:
            solver.solve()
        else:
            z0 = None
            if warm.y is not None and not native_box and m and Ar is None:
                z0 = np.asarray(warm.y, dtype=float)[rows]
                warm_dual = True
            solver.solve(np.asarray(warm.x, dtype=float), None, z0)
    except Exception as exc:  # noqa: BLE001 - never raise on solver trouble (C++ checks)
        return QPResult.failure(n, Status.FAILED, f"ProxQP raised {type(exc).__name__}: {exc}",
                                time_source="wall")
    res = solver.results
    info = res.info
    status = map_status(info.status)
    x = np.array(res.x, dtype=float)
    y = np.zeros(n)
    zall = np.asarray(res.z, dtype=float)
    if m:
        y[rows] = zall[-m:] if native_box else zall[:m]
    y_rows = None
    if Ar is not None:
        y_rows = np.zeros(Ar.shape[0])
        if ne:
            y_rows[eq] = np.asarray(res.y, dtype=float)
        if ni:
            y_rows[ri] = zall[:ni] if native_box else zall[m:m + ni]
    if status in (Status.INFEASIBLE, Status.FAILED) or not np.all(np.isfinite(x)):
        x = np.full(n, np.nan)
        y = np.full(n, np.nan)
        y_rows = None if y_rows is None else np.full(y_rows.size, np.nan)
        if status is Status.SOLVED:
            status = Status.FAILED
    name = info.status.name
    return QPResult(
        x=x, y=y, status=status, iterations=int(info.iter),
        solve_time=float(info.solve_time) * 1e-6, setup_time=float(info.setup_time) * 1e-6,
        message="" if status is Status.SOLVED else f"ProxQP: {name}", time_source="solver",
        extra={"solver_status": name, "variant": variant, "native_box": native_box,
               "objective": float(info.objValue), "iter_ext": int(info.iter_ext),
               "pri_res": float(info.pri_res), "dua_res": float(info.dua_res),
               "duality_gap": float(info.duality_gap), "warm_dual": warm_dual,
               "settings": opts},
        y_rows=y_rows,
    )
