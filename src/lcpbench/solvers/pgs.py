"""Projected Gauss–Seidel (PGS) with optional over-relaxation (projected SOR).

Solves the LCP: find ``z >= 0`` with ``w = M z + q >= 0`` and ``z'w = 0``.

One sweep visits the rows in order and sets

    z_i <- max(0, z_i - omega * w_i / M_ii),   w = M z + q at the current z,

so every row sees the updates of the rows before it (true Gauss–Seidel). ``w``
is kept current by column updates: when ``z_i`` changes by ``d``,
``w += d * M[:, i]``, restricted to the rows where column ``i`` is non-zero
(the band of a banded ``M``) and done by BLAS ``daxpy`` in place. Rows whose
``z_i`` stays put (``z_i = 0``, ``w_i >= 0``) cost a comparison only. At the
end of every sweep ``w`` is recomputed as ``M z + q`` (one matrix-vector
product), so round-off of the column updates never accumulates and the
stopping test always judges the true residual of the iterate it returns.

PGS converges for symmetric positive definite ``M`` and ``0 < omega < 2``
(Cryer 1971; Cottle, Pang & Stone, *The Linear Complementarity Problem*,
1992, sec. 5.2). On other problems it may cycle or diverge; it then reports
MAX_ITER or FAILED, never SOLVED with a wrong ``z``. Convergence is linear
with a rate that degrades with the conditioning of ``M``.
"""

from __future__ import annotations

import time
from collections import deque
from functools import lru_cache

import numpy as np
from scipy.linalg.blas import daxpy

from lcpbench.errors import ProblemError
from lcpbench.solvers.base import LCPSolution, Settings, Status

#: Tolerance used by :func:`solve_lcp` when ``Settings.eps`` is None.
DEFAULT_EPS = 1e-8
#: Sweep budget used by :func:`solve_lcp` when ``Settings.max_iter`` is None.
DEFAULT_MAX_SWEEPS = 10_000  # ~1 s at n = 140; the contact step needs far more (cond ~1e8)
#: Sweeps over which ``extra["rate"]`` averages the residual's contraction.
RATE_WINDOW = 100
#: Keyword options :func:`solve_lcp` passes on to :func:`pgs`.
OPTIONS = ("omega",)


@lru_cache(maxsize=1)
def _daxpy_in_place() -> bool:
    """Whether scipy's ``daxpy`` updates a contiguous float64 view in place."""
    buf = np.zeros(4)
    view = buf[1:3]
    out = daxpy(np.ones(2), view, a=1.0)
    return out is view and buf[1] == 1.0


def _as_real(x, what: str) -> np.ndarray:
    """``x`` (array_like or scipy sparse) as a float array, or ProblemError."""
    try:
        x = np.asarray(x.toarray() if hasattr(x, "toarray") else x)
        if np.iscomplexobj(x):
            raise ValueError("complex values")
        return np.array(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"{what} must be real and numeric: {exc}") from exc


def _is_number(x) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)


def check_inputs(M, q, omega, eps, max_sweeps, z0, time_limit):
    """Convert and check the inputs; raise ProblemError on caller errors."""
    M = _as_real(M, "M")
    if M.ndim != 2 or M.shape[0] != M.shape[1] or M.shape[0] == 0:
        raise ProblemError(f"M must be a non-empty square matrix, got shape {M.shape}")
    n = M.shape[0]
    q = _as_real(q, "q").ravel()
    if q.size != n:
        raise ProblemError(f"q must have length {n} (the size of M), got {q.size}")
    if not np.all(np.isfinite(M)):
        raise ProblemError("M must be finite (found NaN or inf)")
    if not np.all(np.isfinite(q)):
        raise ProblemError("q must be finite (found NaN or inf)")
    if not (_is_number(omega) and 0.0 < float(omega) < 2.0):
        raise ProblemError(f"omega must be a number in the open interval (0, 2), got {omega!r}")
    if not (_is_number(eps) and 0.0 <= float(eps) < np.inf):
        raise ProblemError(f"eps must be a finite number >= 0, got {eps!r}")
    if isinstance(max_sweeps, bool) or not isinstance(max_sweeps, (int, np.integer)) \
            or max_sweeps < 0:
        raise ProblemError(f"max_sweeps must be an integer >= 0, got {max_sweeps!r}")
    if time_limit is not None and not (
            _is_number(time_limit) and float(time_limit) >= 0.0):
        raise ProblemError(f"time_limit must be None or a number >= 0, got {time_limit!r}")
    if z0 is None:
        z = np.zeros(n)
    else:
        z = _as_real(z0, "z0").ravel()
        if z.size != n:
            raise ProblemError(f"z0 must have length {n} (the size of M), got {z.size}")
        if not np.all(np.isfinite(z)):
            raise ProblemError("z0 must be finite (found NaN or inf)")
        z = np.maximum(z, 0.0)
    return M, q, float(omega), float(eps), int(max_sweeps), z


def _column_segments(M: np.ndarray, w: np.ndarray):
    """Per column ``i``: its non-zero span ``M[lo:hi, i]`` and the view ``w[lo:hi]``."""
    cols, segs = [], []
    nz = M != 0.0
    for i in range(M.shape[1]):
        rows = np.flatnonzero(nz[:, i])
        lo, hi = int(rows[0]), int(rows[-1]) + 1  # non-empty: M_ii > 0
        cols.append(np.ascontiguousarray(M[lo:hi, i]))
        segs.append(w[lo:hi])
    return cols, segs


def pgs(M, q, *, omega: float = 1.0, eps: float = 1e-10, max_sweeps: int = 100_000,
        z0=None, time_limit: float | None = None) -> LCPSolution:
    """Solve an LCP by projected Gauss–Seidel / projected SOR.

    Parameters
    ----------
    M : array_like, shape (n, n)
        LCP matrix (dense; a scipy sparse matrix is densified). Its diagonal
        must be strictly positive.
    q : array_like, shape (n,)
        LCP vector.
    omega : float
        Relaxation factor in the open interval (0, 2); 1 is plain PGS,
        ``omega > 1`` over-relaxation (projected SOR).
    eps : float
        Relative tolerance of the stopping test (below), ``>= 0``.
    max_sweeps : int
        Sweep budget; reaching it gives MAX_ITER.
    z0 : array_like, shape (n,), optional
        Initial iterate (warm start), projected onto ``z >= 0``; default 0.
    time_limit : float, optional
        Seconds; checked after each sweep, exceeding it gives MAX_ITER.

    Returns
    -------
    LCPSolution
        ``iterations`` counts sweeps (0 if the initial iterate already passes
        the test). ``w`` is recomputed as ``M z + q``. ``extra`` holds
        ``omega``, ``eps``, ``residual`` (the final relative residual
        ``r / s`` of the stopping test) and ``rate``, the mean contraction
        of that residual per sweep over the last (up to 100) sweeps (NaN
        without a sweep).

    Raises
    ------
    ProblemError
        If ``M`` is not square, ``q`` or ``z0`` has the wrong length, any
        input is non-finite, ``omega`` is outside (0, 2) or ``eps``,
        ``max_sweeps`` or ``time_limit`` is invalid (caller errors).

    Notes
    -----
    Stopping test, evaluated on ``w = M z + q`` recomputed at the end of the
    sweep (``z >= 0`` holds by construction)::

        r = max_i |min(z_i, w_i / M_ii)|  <=  eps * s,
        s = max(max_i |z_i|, max_i |q_i / M_ii|).

    ``min(z_i, w_i / M_ii)`` is the length of a projected step of row ``i``
    (the natural residual after diagonal scaling): zero exactly at a solution.
    Both ``r`` and ``s`` are lengths in the units of ``z``, so the test, the
    iterates and the sweep count are unchanged when ``(M, q)`` becomes
    ``(c M, c q)`` with ``c > 0``; under a symmetric scaling ``(D M D, D q)``
    the PGS iterates map exactly to ``D^{-1} z`` and each row's term is the
    same quantity in that row's new units (``r`` and ``s`` are maxima over
    rows, so a scaling that blows up some rows' units loosens the test on the
    others: nondimensionalise first). ``s`` is the larger of the size of
    the answer and of the unconstrained one-row solutions ``-q_i / M_ii``,
    so ``z = 0`` (when ``q >= 0``) is not judged against a zero scale unless
    ``q = 0``.

    The test bounds the step, not the error: with a linear rate ``rho``
    the relative error of ``z`` is about ``residual / (1 - rho)``, so on an
    ill-conditioned ``M`` (``rho`` close to 1) a SOLVED ``z`` can be far from
    the solution; ``extra["rate"]`` lets a caller see this.

    Status: SOLVED when the test holds; FAILED if a diagonal entry of ``M``
    is ``<= 0`` (PGS divides by it) or NaN/inf appears; MAX_ITER when the
    sweep budget or the time limit is exhausted.
    """
    t_setup = time.perf_counter()
    M, q, omega, eps, max_sweeps, z = check_inputs(M, q, omega, eps, max_sweeps, z0, time_limit)
    n = q.size
    diag = M.diagonal().copy()

    def result(status, sweeps, t_solve, message="", residual=float("nan"), rate=float("nan")):
        with np.errstate(all="ignore"):
            w = M @ z + q
        return LCPSolution(z=z, w=w, status=status, iterations=sweeps, solve_time=t_solve,
                           setup_time=setup, message=message,
                           extra={"omega": omega, "eps": eps, "residual": residual,
                                  "rate": rate})

    bad = np.flatnonzero(~(diag > 0.0))
    if bad.size:
        setup = time.perf_counter() - t_setup
        i = int(bad[0])
        return result(Status.FAILED, 0, 0.0,
                      f"PGS needs M_ii > 0; M[{i}, {i}] = {diag[i]:g} "
                      f"({bad.size} non-positive diagonal entries)")

    inv_diag = 1.0 / diag
    scale_q = float(np.max(np.abs(q * inv_diag)))
    w = np.empty(n)
    cols, segs = _column_segments(M, w)
    relax = (omega * inv_diag).tolist()
    in_place = _daxpy_in_place()
    setup = time.perf_counter() - t_setup

    def exact_w():
        np.matmul(M, z, out=w)
        np.add(w, q, out=w)  # in place: the views in ``segs`` stay valid

    def relative_residual() -> float:
        r = float(np.max(np.abs(np.minimum(z, w * inv_diag))))
        s = max(float(np.max(z)), scale_q)
        return r / s if s > 0 else (0.0 if r == 0 else np.inf)

    t0 = time.perf_counter()
    exact_w()
    res = relative_residual()
    if res <= eps:
        return result(Status.SOLVED, 0, time.perf_counter() - t0, residual=res)

    history = deque([res], maxlen=RATE_WINDOW + 1)
    zl = z.tolist()
    item = w.item
    rows = list(zip(range(n), relax, cols, segs))
    sweeps = 0
    status, message = Status.MAX_ITER, f"sweep budget {max_sweeps} exhausted"
    while sweeps < max_sweeps:
        for i, r_i, col, seg in rows:
            zi = zl[i]
            new = zi - r_i * item(i)
            if new < 0.0:
                new = 0.0
            if new != zi:
                zl[i] = new
                if in_place:
                    daxpy(col, seg, a=new - zi)
                else:
                    seg += (new - zi) * col
        sweeps += 1
        z[:] = zl
        with np.errstate(all="ignore"):
            exact_w()
            if not (np.all(np.isfinite(z)) and np.all(np.isfinite(w))):
                status, message = Status.FAILED, f"non-finite iterate after {sweeps} sweeps"
                break
            res = relative_residual()
        history.append(res)
        if res <= eps:
            status, message = Status.SOLVED, ""
            break
        if time_limit is not None and time.perf_counter() - t0 > time_limit:
            status, message = Status.MAX_ITER, f"time limit {time_limit:g} s reached"
            break
    t_solve = time.perf_counter() - t0
    if status is Status.MAX_ITER:
        message += f" (relative residual {res:.3g} > eps {eps:g})"
    rate = float("nan")
    if len(history) > 1 and history[0] > 0 and np.isfinite(history[0]):
        rate = (history[-1] / history[0]) ** (1.0 / (len(history) - 1))
    return result(status, sweeps, t_solve, message, res, rate)


def solve_lcp(M, q, settings: Settings, warm=None, **options) -> LCPSolution:
    """Adapter of :func:`pgs` to the generic :class:`Settings`.

    Parameters
    ----------
    M, q : array_like
        The LCP.
    settings : Settings
        ``eps`` becomes the relative tolerance of the stopping test (None:
        ``1e-8``); ``max_iter`` the sweep budget (None: 10 000);
        ``time_limit`` is passed on.
    warm : array_like, optional
        Initial ``z``, clipped to ``z >= 0``; None starts from 0.
    **options
        ``omega`` (relaxation factor in (0, 2), default 1).

    Raises
    ------
    ProblemError
        On an unknown option or invalid input (see :func:`pgs`).
    """
    unknown = sorted(set(options) - set(OPTIONS))
    if unknown:
        raise ProblemError(f"unknown PGS option(s) {', '.join(unknown)}; allowed: "
                           f"{', '.join(OPTIONS)}")
    eps = DEFAULT_EPS if settings.eps is None else settings.eps
    max_sweeps = DEFAULT_MAX_SWEEPS if settings.max_iter is None else settings.max_iter
    # pgs validates ``warm`` and clips it to z >= 0.
    return pgs(M, q, omega=options.get("omega", 1.0), eps=eps, max_sweeps=max_sweeps,
               z0=warm, time_limit=settings.time_limit)
