"""The one result type of every LCP back-end, and the shared status set.

An LCP here is: find ``z >= 0`` with ``w = M z + q >= 0`` and ``z'w = 0``.
In the contact step ``z`` is the gap vector g and ``w`` the reaction R
(eq. 30); ``z`` and ``w`` are the LCP's own letters and stay so in the
solvers. The step and result types call R ``forces`` (:class:`StepSolution`
``forces_upper``/``forces_lower``/``forces_net``, ``ContactResult.forces``).
A back-end never raises on non-convergence; it returns a status.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.metadata
import os
import sys
from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from ..errors import ProblemError


class Status(str, Enum):
    """The small shared set every solver's own status codes map onto."""

    SOLVED = "solved"
    INACCURATE = "inaccurate"
    MAX_ITER = "max_iterations"
    RAY = "ray"
    INFEASIBLE = "infeasible"
    FAILED = "failed"


@dataclass
class LCPSolution:
    """Solution of ``w = M z + q``, ``0 <= z`` perp ``w >= 0``.

    Attributes
    ----------
    z, w : ndarray
        Primal unknown and complementary slack (gaps g and reactions R in
        the contact step). ``w`` is what the solver reports; residuals are
        computed by :func:`lcp_residuals`, identically for every back-end.
    status : Status
    iterations : int
        Pivots (Lemke), sweeps (PGS) or active-set changes.
    solve_time, setup_time : float
        Seconds.
    message : str
        Human-readable reason when ``status`` is not SOLVED.
    """

    z: np.ndarray
    w: np.ndarray
    status: Status
    iterations: int = 0
    solve_time: float = 0.0
    setup_time: float = 0.0
    message: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def solved(self) -> bool:
        return self.status is Status.SOLVED


def lcp_residuals(M, q: np.ndarray, z: np.ndarray, with_w: bool = False):
    """Residuals of a candidate LCP solution, the same for every back-end.

    ``w`` is recomputed as ``M z + q`` (not taken from the solver). Values are
    scaled by ``max(1, |q|_inf)`` so they compare across problems. Computed in one
    compiled pass (:func:`lcpbench.solvers.pivoting_kernel.natural_residuals`; M dense,
    a sparse M made dense first). ``with_w``: return ``(residuals, w)``.
    """
    if not _RESIDUALS:
        from ..numba_cache import held, kernel_module

        held(_RESIDUALS).append(kernel_module("lcpbench.solvers.pivoting_kernel",
                                              "natural_residuals"))
    M = M.toarray() if hasattr(M, "toarray") else M
    natural, min_z, min_w, comp, w = _RESIDUALS[0].natural_residuals(
        np.ascontiguousarray(M, dtype=float), np.ascontiguousarray(q, dtype=float).ravel(),
        np.ascontiguousarray(z, dtype=float).ravel())
    res = {"natural": float(natural), "min_z": float(min_z), "min_w": float(min_w),
           "complementarity": float(comp)}
    return (res, w) if with_w else res


_RESIDUALS: list = []  # the compiled residuals (solvers/pivoting_kernel.py), once loaded


@dataclass
class StepSolution:
    """Solution of one contact step in node heights (the QP view).

    The step's counterpart of :class:`LCPSolution`: the same status set, the
    same solver-reported counts and times, plus lcpbench's own residuals.

    Attributes
    ----------
    u : ndarray
        Heights of the free nodes (mm); the gaps are ``upper − u``.
    forces_upper, forces_lower : ndarray
        Reactions R (eq. 30) of the upper and lower walls at each free node
        (N, >= 0): the QP multipliers.
    status, iterations, solve_time, setup_time, message :
        As for :class:`LCPSolution`.
    active_upper, active_lower : ndarray of bool or None
        The contact set, for warm starts.
    """

    u: np.ndarray
    forces_upper: np.ndarray
    forces_lower: np.ndarray
    status: Status
    iterations: int = 0
    solve_time: float = 0.0
    setup_time: float = 0.0
    message: str = ""
    active_upper: np.ndarray | None = None
    active_lower: np.ndarray | None = None
    time_source: str = "solver"  # "solver": reported by it; "wall": measured around it
    build_time: float = 0.0  # lcpbench's time to build the back-end's form (s)
    # filled in by lcpbench (model.step_solver), the same for every back-end:
    backend: str = ""
    settings: str = ""
    scaled: bool = True
    residuals: dict = field(default_factory=dict)
    forces_net: np.ndarray | None = None  # net R = K g + z (eq. 30) from the gaps (N)
    wall_time: float = 0.0
    formulation: str = ""  # the form handed over (model.formulations); "": its own
    eps: float | None = None  # the tolerance ε handed to the back-end; None: its own

    @property
    def solved(self) -> bool:
        return self.status is Status.SOLVED


# -- settings profiles --------------------------------------------------------
@dataclass(frozen=True)
class Settings:
    """One generic accuracy request, translated by each back-end into its own
    parameters.

    ``eps`` is a tolerance on the residuals of the (nondimensionalised)
    problem: primal and dual feasibility and complementarity, absolute and
    relative alike (each back-end's own ``eps_abs``/``tol``/``feastol``...).
    ``None`` means "the solver's own defaults".

    ``driver_tol`` is the driver's ``tol`` (rad) that goes with the profile:
    the bound on the change of the link angles α between contact steps
    (eq. 32). A profile is one accuracy for the whole solve, so ``solve``,
    ``sweep`` and ``select`` run a profile at this tolerance unless a ``tol``
    is given. Back-ends ignore it.
    """

    name: str
    eps: float | None
    max_iter: int | None = None
    time_limit: float | None = None  # seconds, where the solver supports it
    driver_tol: float = 1e-3  # rad; the paper's 1e-3 unless the profile says otherwise


#: The settings profiles: one table of the back-end ε and the driver tol (rad).
#: "default" is each back-end's own defaults at the paper's 1e-3 rad; "low", "mid"
#: and "high" ask for a relative force accuracy of 1e-3, 1e-6 and 1e-9
#: (:func:`lcpbench.accuracy.accuracy_settings`, docs/accuracy.md).
PROFILES: dict[str, Settings] = {
    "default": Settings("default", None, driver_tol=1e-3),
    "low": Settings("low", 1e-3, driver_tol=1e-3),
    "mid": Settings("mid", 1e-6, driver_tol=1e-6),
    "high": Settings("high", 1e-9, driver_tol=1e-9),
}


# -- the QP view of a problem -------------------------------------------------
@dataclass
class BoxQP:
    """``minimise ½ xᵀPx + cᵀx  subject to  lower <= x <= upper``.

    Bounds may be ±inf (no constraint on that row). ``P`` is symmetric
    positive (semi)definite, stored as a full (both triangles)
    ``scipy.sparse.csc_matrix``; :meth:`dense` gives it as an array.
    ``bands`` is P in lower banded storage when P is banded (the contact
    step: pentadiagonal), for structure-exploiting back-ends.
    """

    P: object
    c: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    bands: np.ndarray | None = None

    @property
    def size(self) -> int:
        return self.c.size

    def dense(self) -> np.ndarray:
        P = self.P
        return P.toarray() if hasattr(P, "toarray") else np.asarray(P, dtype=float)

    def constrained_rows(self) -> np.ndarray:
        """Indices of rows with at least one finite bound."""
        return np.flatnonzero(np.isfinite(self.lower) | np.isfinite(self.upper))


@dataclass
class LinearQP(BoxQP):
    """A :class:`BoxQP` with linear rows: also ``row_lower <= A x <= row_upper``.

    ``A`` is an m x n ``scipy.sparse`` matrix; a row with equal bounds is an
    equality, ±inf leaves a side open. The back-ends whose registry record has
    ``constraints="linear"`` accept it; the multiplier of the rows is
    :attr:`QPResult.y_rows`, with ``P x + c + y + Aᵀ y_rows = 0``.
    """

    A: object = None
    row_lower: np.ndarray | None = None
    row_upper: np.ndarray | None = None

    @property
    def rows(self) -> int:
        return 0 if self.A is None else int(self.A.shape[0])

    def row_kinds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Indices of the equality rows, of the rows with a finite upper side and of
        those with a finite lower side (the last two exclude the equalities)."""
        lo, hi = np.asarray(self.row_lower, float), np.asarray(self.row_upper, float)
        eq = lo == hi
        return (np.flatnonzero(eq), np.flatnonzero(~eq & np.isfinite(hi)),
                np.flatnonzero(~eq & np.isfinite(lo)))


def prepare_rows(qp: BoxQP, n: int):
    """``(A, row_lower, row_upper)`` of a :class:`LinearQP` (A as float csr), or
    ``(None, None, None)`` for a plain box QP; one ProblemError on bad shapes."""
    if getattr(qp, "A", None) is None:
        return None, None, None
    import scipy.sparse as sp

    A = sp.csr_matrix(qp.A, dtype=float)
    m = A.shape[0]
    lo = np.asarray(qp.row_lower, dtype=float).ravel()
    hi = np.asarray(qp.row_upper, dtype=float).ravel()
    if A.shape[1] != n or lo.shape != (m,) or hi.shape != (m,):
        raise ProblemError(f"A must be m x {n} with row bounds of length m, got A "
                           f"{A.shape}, bounds {lo.shape} and {hi.shape}")
    if np.isnan(lo).any() or np.isnan(hi).any():
        raise ProblemError("NaN in the row bounds")
    return A, lo, hi


@dataclass
class QPWarm:
    """A warm start for a QP back-end: primal x and signed bound multiplier y."""

    x: np.ndarray
    y: np.ndarray | None = None


@dataclass
class QPResult:
    """What a QP back-end returns, before lcpbench judges it.

    ``y`` is the signed bound multiplier with the convention
    ``P x + c + y = 0``: ``y_i > 0`` where the upper bound pushes, ``y_i < 0``
    where the lower bound does (OSQP's convention for ``A = I``).
    Times are seconds; ``time_source`` says whether the solver reported them
    ("solver") or lcpbench measured wall time around the call ("wall").
    """

    x: np.ndarray
    y: np.ndarray
    status: Status
    iterations: int = 0
    solve_time: float = 0.0
    setup_time: float = 0.0
    message: str = ""
    time_source: str = "solver"
    extra: dict = field(default_factory=dict)
    y_rows: np.ndarray | None = None  # multiplier of a LinearQP's rows A x

    @classmethod
    def failure(cls, n: int, status: Status, message: str, **kw) -> QPResult:
        nan = np.full(n, np.nan)
        return cls(nan, nan.copy(), status, message=message, **kw)


@contextlib.contextmanager
def c_stdout_to_stderr():
    """Send what native code prints on file descriptor 1 to stderr meanwhile.

    Some solvers print from C even when told to be quiet (OSQP 1.1:
    "Polishing not needed"); on stdout that would corrupt ``--json`` output.
    """
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError, AttributeError):  # no real fd 1 (embedded, captured)
        yield
        return
    try:
        os.dup2(2, 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


# -- shared by the QP back-ends -------------------------------------------------
def prepare_box_qp(qp: BoxQP):
    """Validated ``(P, c, lower, upper)``: P as float csc, the rest float arrays.

    Shared by the QP back-ends. Raises
    :class:`ProblemError` on programmer errors (shapes, NaN); an empty box
    (``lower > upper``) is not an error but an infeasible problem.
    """
    n = qp.size
    c = np.asarray(qp.c, dtype=float).ravel()
    lower = np.asarray(qp.lower, dtype=float).ravel()
    upper = np.asarray(qp.upper, dtype=float).ravel()
    if lower.shape != (n,) or upper.shape != (n,):
        raise ProblemError(f"bounds must have length {n}")
    if getattr(qp.P, "shape", None) != (n, n):
        raise ProblemError(f"P must be {n} x {n}, got {getattr(qp.P, 'shape', None)}")
    if np.isnan(c).any() or np.isnan(lower).any() or np.isnan(upper).any():
        raise ProblemError("NaN in c or bounds")
    import scipy.sparse as sp  # at the first QP, not at start-up

    P = sp.csc_matrix(qp.P, dtype=float)
    return P, c, lower, upper


def empty_box_result(n: int, lower: np.ndarray, upper: np.ndarray) -> QPResult | None:
    """INFEASIBLE result when some ``lower_i > upper_i``, else None.

    For a box QP this is the complete infeasibility test, so back-ends answer
    it exactly instead of letting a solver spin to its iteration limit (ProxQP
    does not detect it and runs ~1e5 iterations).
    """
    bad = np.flatnonzero(lower > upper)
    if bad.size == 0:
        return None
    return QPResult.failure(n, Status.INFEASIBLE,
                            f"lower > upper on rows {bad[:10].tolist()}: the box is empty",
                            extra={"detected_by": "lcpbench"})


def open_box_qp(qp: BoxQP, module: str):
    """Validate ``qp`` and import the solver's module, for a QP back-end.

    Returns ``((P, c, lower, upper, mod), None)``, or ``(None, result)`` with
    the result to return at once: INFEASIBLE for an empty box, FAILED when
    the solver is not importable.
    """
    P, c, lower, upper = prepare_box_qp(qp)
    empty = empty_box_result(c.size, lower, upper)
    if empty is not None:
        return None, empty
    try:
        top, *rest = module.split(".")
        mod = importlib.import_module(top)
        for attr in rest:  # e.g. proxsuite.proxqp: an attribute of a native module
            mod = getattr(mod, attr)
    except (ImportError, AttributeError) as exc:
        pip = module.split(".")[0]
        return None, QPResult.failure(c.size, Status.FAILED,
                                      f"{pip} not importable ({exc}); pip install {pip}")
    return (P, c, lower, upper, mod), None


def dist_version(dist: str) -> str | None:
    """Installed version of a distribution, without importing it; None if absent."""
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return None


def iteration_limits(settings: Settings) -> dict:
    """``max_iter`` and ``time_limit`` of a profile, where set (for the adapters)."""
    out = {}
    if settings.max_iter is not None:
        out["max_iter"] = int(settings.max_iter)
    if settings.time_limit is not None:
        out["time_limit"] = float(settings.time_limit)
    return out
