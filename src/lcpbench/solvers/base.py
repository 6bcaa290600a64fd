"""The one result type of every LCP back-end, and the shared status set.

An LCP here is: find ``z >= 0`` with ``w = M z + q >= 0`` and ``z'w = 0``.
In the contact step ``z`` is the gap vector g and ``w`` the reaction R.
A back-end never raises on non-convergence; it returns a status.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np


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


def lcp_residuals(M, q: np.ndarray, z: np.ndarray) -> dict[str, float]:
    """Residuals of a candidate LCP solution, the same for every back-end.

    ``w`` is recomputed as ``M z + q`` (not taken from the solver). Values are
    scaled by ``max(1, |q|_inf)`` so they compare across problems.
    """
    z = np.asarray(z, dtype=float)
    w = M @ z + q
    scale = max(1.0, float(np.max(np.abs(q), initial=0.0)))
    return {
        "natural": float(np.max(np.abs(np.minimum(z, w)), initial=0.0)) / scale,
        "min_z": float(np.min(z, initial=0.0)),
        "min_w": float(np.min(w, initial=0.0)) / scale,
        "complementarity": abs(float(z @ w)) / scale,
    }


@dataclass
class StepSolution:
    """Solution of one contact step in node heights (the QP view).

    Attributes
    ----------
    u : ndarray
        Heights of the free nodes (mm); the gaps are ``upper − u``.
    reaction_upper, reaction_lower : ndarray
        Reactions of the upper and lower walls (N, >= 0): the QP multipliers.
    status, iterations, solve_time, setup_time, message :
        As for :class:`LCPSolution`.
    active_upper, active_lower : ndarray of bool or None
        The contact set, for warm starts.
    """

    u: np.ndarray
    reaction_upper: np.ndarray
    reaction_lower: np.ndarray
    status: Status
    iterations: int = 0
    solve_time: float = 0.0
    setup_time: float = 0.0
    message: str = ""
    active_upper: np.ndarray | None = None
    active_lower: np.ndarray | None = None

    @property
    def solved(self) -> bool:
        return self.status is Status.SOLVED
