"""The box QP as a cvxpy user writes it, solved by whatever cvxpy picks.

::

    x = cp.Variable(n)
    cp.Minimize(0.5 * cp.quad_form(x, cp.psd_wrap(P)) + c @ x)
    [x[iu] <= upper[iu], x[il] >= lower[il]]    # rows with a finite bound

``options["solver"]`` names a cvxpy solver (``"OSQP"``, ``"CLARABEL"``, ...);
without it cvxpy chooses, and lcpbench asks cvxpy which one it will be (the
solving chain) so the tolerance can be translated for it.

Multipliers: cvxpy's ``dual_value`` of an inequality constraint is ``>= 0``
for both ``x <= u`` and ``x >= l``; the signed ``y`` is
``y[iu] += dual(upper)``, ``y[il] -= dual(lower)``, so that
``P x + c + y = 0``.

Times: ``setup_time`` is cvxpy's ``compilation_time`` (wall, measured by
cvxpy: canonicalisation into the solver's format). ``solve_time`` is
``solver_stats.solve_time`` when the solver reports a positive one
(``time_source="solver"``), else cvxpy's own wall time around the solver
call, interface included (``time_source="wall"``). Warm starts are ignored
(a fresh cvxpy problem is built on every call).

Tolerance translation (:data:`TOLERANCE_KEYS`):

==========  ======================================================  ============
solver      tolerance keywords set to ``tol``                       iterations
==========  ======================================================  ============
OSQP        eps_abs, eps_rel, polishing (tol <= 1e-6)                max_iter
CLARABEL    tol_gap_abs, tol_gap_rel, tol_feas (>= 1e-10)            max_iter
PROXQP      eps_abs, eps_rel (cvxpy passes nothing else)             max_iter
PIQP        eps_abs, eps_rel, eps_duality_gap_abs, _rel              max_iter
SCS         eps_abs, eps_rel                                         max_iters
DAQP        primal_tol, dual_tol                                     iter_limit
HIGHS       primal_ and dual_feasibility_tolerance,                  --
            qp_regularization_value = min(1e-7, tol) (as qp_qpsolvers)
ECOS        abstol, reltol, feastol                                  max_iters
CVXOPT      abstol, reltol, feastol                                  max_iters
QPALM       eps_abs, eps_rel                                         max_iter
GUROBI      FeasibilityTol, OptimalityTol, BarConvTol (>= 1e-9)      --
==========  ======================================================  ============

Any other solver gets no tolerance keyword (``extra["tolerance_applied"]``).
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from . import qp_clarabel, qp_osqp
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

DIST = "cvxpy"

TOLERANCE_KEYS: dict[str, tuple[tuple[str, ...], str | None]] = {
    "PROXQP": (("eps_abs", "eps_rel"), "max_iter"),
    "PIQP": (("eps_abs", "eps_rel", "eps_duality_gap_abs", "eps_duality_gap_rel"), "max_iter"),
    "SCS": (("eps_abs", "eps_rel"), "max_iters"),
    "DAQP": (("primal_tol", "dual_tol"), "iter_limit"),
    "HIGHS": (("primal_feasibility_tolerance", "dual_feasibility_tolerance"), None),
    "ECOS": (("abstol", "reltol", "feastol"), "max_iters"),
    "CVXOPT": (("abstol", "reltol", "feastol"), "max_iters"),
    "QPALM": (("eps_abs", "eps_rel"), "max_iter"),
    "GUROBI": (("FeasibilityTol", "OptimalityTol", "BarConvTol"), None),
    # OSQP and CLARABEL: the native back-ends' translate()
}
_FLOORS = {"GUROBI": 1e-9}

#: ``prob.status`` -> lcpbench Status (strict).
STATUS_MAP = {
    "optimal": Status.SOLVED,
    "optimal_inaccurate": Status.INACCURATE,
    "user_limit": Status.MAX_ITER,
    "infeasible": Status.INFEASIBLE,
    "unbounded": Status.INFEASIBLE,  # unbounded below: no minimiser
    # infeasible_inaccurate, unbounded_inaccurate, solver_error, ... -> FAILED
}


def version() -> str | None:
    """Installed version of the ``cvxpy`` distribution, or None."""
    return dist_version(DIST)


def translate(settings: Settings, solver: str) -> dict:
    """Keyword arguments for ``prob.solve(solver=solver, ...)`` (see the table).

    ``tol=None`` gives ``{}``: the defaults cvxpy hands the solver (cvxpy
    overrides some, e.g. OSQP gets eps 1e-5, 10 000 iterations, polishing).
    """
    solver = solver.upper()
    if solver == "OSQP":
        opts = qp_osqp.translate(settings)
        opts.pop("time_limit", None)
        return opts
    if solver == "CLARABEL":  # as through qpsolvers: eps itself (qp_clarabel.translate)
        opts = qp_clarabel.translate(settings, 1.0)
        opts.pop("time_limit", None)
        return opts
    opts: dict = {}
    keys, iter_key = TOLERANCE_KEYS.get(solver, ((), None))
    if settings.eps is not None:
        tol = max(float(settings.eps), _FLOORS.get(solver, 0.0))
        opts.update({k: tol for k in keys})
        if solver == "HIGHS":  # its Hessian regularisation (1e-7) limits accuracy
            opts["qp_regularization_value"] = min(1e-7, tol)
    if settings.max_iter is not None and iter_key is not None:
        opts[iter_key] = int(settings.max_iter)
    return opts


def solve_qp(qp: BoxQP, settings: Settings, warm: QPWarm | None = None,
             **options) -> QPResult:
    """Solve ``qp`` through cvxpy.

    Parameters
    ----------
    qp : BoxQP
    settings : Settings
        Translated by :func:`translate` for the solver cvxpy uses.
    warm : QPWarm, optional
        Ignored.
    **options
        ``solver`` (a cvxpy solver name, default: cvxpy's choice); the rest
        is passed to ``prob.solve`` after the translation (it wins).
    """
    opened, early = open_box_qp(qp, "cvxpy")
    if early is not None:
        return early
    P, c, lower, upper, cp = opened
    n = c.size

    options = dict(options)
    solver = options.pop("solver", None)
    iu = np.flatnonzero(np.isfinite(upper))
    il = np.flatnonzero(np.isfinite(lower))
    t0 = time.perf_counter()
    try:
        x = cp.Variable(n)
        cons_u = x[iu] <= upper[iu] if iu.size else None
        cons_l = x[il] >= lower[il] if il.size else None
        Ar, lr, ur = prepare_rows(qp, n)  # a LinearQP's rows: A x == b, A x <= u, A x >= l
        row_cons = []  # (constraint, its rows, the sign of its dual in y_rows)
        if Ar is not None:
            eq, ru, rl = qp.row_kinds()
            if eq.size:
                row_cons.append((Ar[eq] @ x == ur[eq], eq, 1.0))
            if ru.size:
                row_cons.append((Ar[ru] @ x <= ur[ru], ru, 1.0))
            if rl.size:
                row_cons.append((Ar[rl] @ x >= lr[rl], rl, -1.0))
        prob = cp.Problem(cp.Minimize(0.5 * cp.quad_form(x, cp.psd_wrap(P)) + c @ x),
                          [k for k in (cons_u, cons_l) if k is not None]
                          + [rc for rc, _, _ in row_cons])
        if solver is None:  # the solver cvxpy would pick, to translate for it
            solver = prob._construct_chain().solver.name()
        solver = str(solver).upper()
        kwargs = {**translate(settings, solver), **options}
        t1 = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            prob.solve(solver=solver, **kwargs)
        t2 = time.perf_counter()
    except Exception as exc:  # noqa: BLE001 - never raise on solver trouble (SolverError, ...)
        return QPResult.failure(n, Status.FAILED, f"cvxpy raised {type(exc).__name__}: {exc}",
                                setup_time=time.perf_counter() - t0, time_source="wall",
                                extra={"solver": solver})
    status = STATUS_MAP.get(prob.status, Status.FAILED)
    stats = prob.solver_stats
    xv = x.value
    y = np.zeros(n)
    ok = xv is not None
    for cons, idx, sign in ((cons_u, iu, 1.0), (cons_l, il, -1.0)):
        if cons is not None:
            dual = cons.dual_value
            if dual is None:
                ok = False
            else:
                y[idx] += sign * np.asarray(dual, dtype=float).ravel()
    y_rows = None if Ar is None else np.zeros(Ar.shape[0])
    for rc, idx, sign in row_cons:  # cvxpy's dual of == is that of P x + c + Aᵀy = 0
        if rc.dual_value is None:
            ok = False
        else:
            y_rows[idx] += sign * np.asarray(rc.dual_value, dtype=float).ravel()
    if not ok or status in (Status.INFEASIBLE, Status.FAILED) or not np.all(np.isfinite(xv)):
        xv = np.full(n, np.nan)
        y = np.full(n, np.nan)
        y_rows = None if y_rows is None else np.full(y_rows.size, np.nan)
        if status in (Status.SOLVED, Status.INACCURATE):
            status = Status.FAILED
    compile_time = prob.compilation_time
    solver_reported = stats.solve_time is not None and stats.solve_time > 0
    if solver_reported:
        solve_time, source = float(stats.solve_time), "solver"
    else:
        wall = getattr(prob, "_solve_time", None)
        solve_time = float(wall) if wall is not None else (t2 - t1) - (compile_time or 0.0)
        source = "wall"
    return QPResult(
        x=np.asarray(xv, dtype=float), y=y, status=status,
        iterations=int(stats.num_iters or 0),
        solve_time=solve_time, setup_time=float(compile_time or 0.0),
        message="" if status is Status.SOLVED else f"cvxpy/{solver}: {prob.status}",
        time_source=source,
        extra={"solver": solver, "solver_status": prob.status, "objective": prob.value,
               "iterations_reported": stats.num_iters is not None,
               "native_setup_time": stats.setup_time, "wall_total": t2 - t0,
               "tolerance_applied": settings.eps is not None and bool(translate(settings, solver)),
               "kwargs": kwargs, "warnings": [str(w.message) for w in caught]},
        y_rows=y_rows,
    )
