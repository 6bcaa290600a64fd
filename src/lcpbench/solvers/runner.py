"""Running a back-end on an LCP, judged by lcpbench's own residuals.

Every back-end gets its problem in the form it works on (LCP, or the
equivalent QP when M is symmetric) and returns its own answer; lcpbench then
computes the residuals itself, from z alone (:func:`lcp_residuals`),
identically for every back-end, and :func:`lcpbench.solvers.judge.verdict`
demotes a SOLVED that fails them to INACCURATE. A back-end that raises is
turned into a FAILED status: nothing a solver does escapes as an exception.

The contact step of the actuator is run through the same back-ends by
:mod:`lcpbench.model.step_solver` (solvers know nothing of actuators).
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from .base import BoxQP, LCPSolution, QPWarm, Settings, Status, lcp_residuals
from .judge import accept_tol, verdict
from .registry import Backend, get_backend, get_settings


def _failed_lcp(n: int, message: str, status: Status = Status.FAILED) -> LCPSolution:
    nan = np.full(n, np.nan)
    return LCPSolution(nan, nan.copy(), status, message=message)


# -- LCPs ---------------------------------------------------------------------
def check_lcp(M, q):
    """Dense real ``M`` (n x n, n >= 1) and ``q`` (n), finite, or one ProblemError.

    Refused rather than cast: complex entries (the imaginary part would be
    dropped), booleans, strings and objects; a 0x0 M (no problem to solve).
    """
    try:
        M = np.asarray(M.toarray() if hasattr(M, "toarray") else M)
        q = np.asarray(q)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"M and q must be real numeric arrays ({exc})") from exc
    for name, a in (("M", M), ("q", q)):
        if a.dtype.kind not in "iuf":
            kind = {"c": "complex", "b": "bool"}.get(a.dtype.kind, str(a.dtype))
            raise ProblemError(f"{name} must be a real numeric array (int or float), "
                               f"got dtype {kind}")
    M, q = M.astype(float, copy=False), q.astype(float, copy=False).ravel()
    if M.ndim != 2 or M.shape != (q.size, q.size):
        raise ProblemError(f"M must be square of size len(q) = {q.size}, got shape {M.shape}")
    if q.size == 0:
        raise ProblemError("M must be at least 1x1, got shape (0, 0)")
    if not (np.all(np.isfinite(M)) and np.all(np.isfinite(q))):
        raise ProblemError("M and q must be finite")
    return M, q


def is_symmetric(M: np.ndarray) -> bool:
    return bool(np.max(np.abs(M - M.T), initial=0.0) <= 1e-12 * max(np.max(np.abs(M)), 1e-300))


#: Largest n for which :func:`default_lcp_solver` picks Lemke (M not symmetric positive
#: definite). Each pivot costs O(n²) and a dense problem takes about n/2 to n pivots or
#: more: n = 800, 0.6 s; n = 3000 did not finish in 10 min.
LEMKE_DEFAULT_MAX_SIZE = 1000


def default_lcp_solver(M) -> tuple[str, str]:
    """The back-end ``lcpbench lcp`` runs when none is named, and why.

    ``"active-set"`` (the built-in box QP, O(n³) at worst) where M is symmetric
    positive definite (symmetric to 1e-12 of max|M| and its Cholesky factor exists);
    ``"lemke"`` otherwise, up to n = :data:`LEMKE_DEFAULT_MAX_SIZE`.

    Parameters
    ----------
    M : ndarray, shape (n, n)

    Returns
    -------
    (str, str)
        The back-end's name and the reason, e.g. ``"M is symmetric positive definite"``.

    Raises
    ------
    ProblemError
        When M is not symmetric positive definite and n exceeds
        :data:`LEMKE_DEFAULT_MAX_SIZE`: the message says which back-end to name instead.
    """
    M = np.asarray(M, dtype=float)
    n = M.shape[0]
    if is_symmetric(M):
        try:
            np.linalg.cholesky(0.5 * (M + M.T))
        except np.linalg.LinAlgError:
            why = "M is symmetric but not positive definite"
        else:
            return "active-set", "M is symmetric positive definite"
    else:
        why = "M is not symmetric"
    if n > LEMKE_DEFAULT_MAX_SIZE:
        raise ProblemError(
            f"solver: {why}, so the default would be Lemke, which lcpbench runs by default "
            f"only up to n = {LEMKE_DEFAULT_MAX_SIZE} (its O(n^2) pivots take minutes "
            f"beyond; this LCP has n = {n}): name a back-end with --solver, e.g. pgs or "
            f"psor (iterative), or lemke to run it all the same")
    return "lemke", why


def solve_lcp(M, q, solver: str = "lemke", settings: str | Settings = "default",
              warm: np.ndarray | None = None) -> LCPSolution:
    """Solve ``0 <= z ⟂ M z + q >= 0`` with any back-end.

    A QP back-end solves ``min ½ zᵀMz + qᵀz, z >= 0``, equivalent when M is
    symmetric positive semidefinite; for non-symmetric M it returns FAILED.
    ``sol.extra["residuals"]`` holds lcpbench's residuals (:func:`lcp_residuals`).
    """
    backend = get_backend(solver)
    s = get_settings(settings)
    M, q = check_lcp(M, q)
    try:
        sol = run_lcp(backend, M, q, s, warm)
    except Exception as exc:  # a back-end failure is a status, never an exception
        sol = _failed_lcp(q.size, f"{backend.name} raised {type(exc).__name__}: {exc}")
    sol.extra["backend"] = backend.name
    sol.extra["settings"] = s.name
    judge_lcp(M, q, sol, s)
    if sol.status is not Status.SOLVED and backend.fallback:
        first = sol
        sol = solve_lcp(M, q, backend.fallback, s, warm)
        sol.message = fallback_message(backend, first, sol)
        sol.iterations += first.iterations
        sol.solve_time += first.solve_time
        sol.extra["backend"] = f"{backend.name}>{backend.fallback}"
    return sol


def judge_lcp(M: np.ndarray, q: np.ndarray, sol: LCPSolution, s: Settings) -> LCPSolution:
    """``sol`` judged on (M, q) by lcpbench's residuals of its z alone, in place: the
    residuals in ``sol.extra["residuals"]``, a SOLVED that fails them demoted
    (:func:`~.judge.verdict`; never promoted), a non-finite z FAILED."""
    if np.all(np.isfinite(sol.z)):
        res = lcp_residuals(M, q, sol.z)
        sol.extra["residuals"] = res
        status, why = verdict(sol.status, res["natural"], accept_tol(s, _lcp_scale(M, q, sol.z)))
        if why:
            sol.status, sol.message = status, why
    elif sol.status is Status.SOLVED:
        sol.status, sol.message = Status.FAILED, "non-finite solution"
    return sol


def fallback_message(backend, first, second) -> str:
    msg = (f"{backend.name}: {first.status.value} ({first.message}); "
           f"fell back to {backend.fallback}")
    return msg + (f": {second.message}" if second.message else "")


def _lcp_scale(M, q, z) -> float:
    """S of :data:`FLOOR_ULPS`, in the units of :func:`lcp_residuals`."""
    scale = max(1.0, float(np.max(np.abs(q), initial=0.0)))
    return float(np.max(np.abs(M) @ np.abs(z) + np.abs(q), initial=0.0)) / scale


def run_lcp(backend: Backend, M, q, s: Settings, warm) -> LCPSolution:
    """``backend``'s answer to the LCP (M, q), not judged: an LCP back-end's own, a QP
    back-end's ``min ½zᵀMz + qᵀz, z >= 0`` (FAILED for a non-symmetric M)."""
    mod = backend.load()
    if backend.form == "lcp":
        z0 = None if warm is None else np.maximum(np.asarray(warm, dtype=float), 0.0)
        return mod.solve_lcp(M, q, s, z0, **backend.options)
    if not is_symmetric(M):
        return _failed_lcp(q.size, f"{backend.name} is a QP back-end: it needs symmetric M "
                                   "(min ½zᵀMz + qᵀz over z >= 0)")
    n = q.size
    Ms = 0.5 * (M + M.T)
    import scipy.sparse as sp  # at the first QP, not at start-up

    qp = BoxQP(sp.csc_matrix(Ms), q.copy(), np.zeros(n), np.full(n, np.inf))
    qwarm = None if warm is None else QPWarm(np.maximum(np.asarray(warm, float), 0.0))
    res = mod.solve_qp(qp, s, qwarm, **backend.options)
    # P z + q + y = 0 with y = −(multiplier of z >= 0): w = −y
    return LCPSolution(res.x, -res.y, res.status, res.iterations, res.solve_time,
                       res.setup_time, res.message,
                       extra={"time_source": res.time_source, **res.extra})


