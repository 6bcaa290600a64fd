"""Siconos' 2-D frictional contact solvers (fc2d), the peers of the frictional step.

A 2-D frictional contact problem (Siconos' FrictionContactProblem, dimension 2):
find per contact c the local velocity u_c = (u_n, u_t) and reaction r_c = (r_n, r_t)
with u = W r + q, 0 <= u_n ⟂ r_n >= 0, |r_t| <= μ_c r_n, and r_t = −μ_c r_n sign(u_t)
where u_t ≠ 0 (Coulomb). lcpbench hands its frictional step over in this form
(:func:`lcpbench.model.friction_solvers.fc2d_contacts`: u = (gap, slip), r = (N, T)).
Run through the Siconos worker (:mod:`.siconos_bridge`, the system interpreter).

Methods (our name -> ``SICONOS_FRICTION_2D_<name>``): ``nsgs`` (non-smooth
Gauss–Seidel), ``lemke`` (lexicographic Lemke on Siconos' own LCP form), ``enum``
(enumeration, small problems).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ProblemError
from .base import Status
from .siconos_bridge import available, call_worker

METHODS = {"nsgs": "NSGS", "lemke": "LEMKE", "enum": "ENUM"}
#: the largest Coulomb-law residual (in the problem's units) accepted as SOLVED
ACCEPT_TOL = 1e-8


@dataclass
class FC2DSolution:
    """r and u per contact, interleaved (n, t); ``status`` SOLVED when Siconos reports
    success and lcpbench's own residual (:func:`coulomb_residual`) is small."""

    r: np.ndarray
    u: np.ndarray
    status: Status
    iterations: int = 0
    residual: float = np.nan
    message: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def solved(self) -> bool:
        return self.status is Status.SOLVED


def coulomb_residual(W: np.ndarray, q: np.ndarray, mu: np.ndarray, r: np.ndarray) -> float:
    """The largest violation of Signorini–Coulomb at r, u = W r + q recomputed, in the
    units of q and r (scaled by max(1, |q|, |r|)): r_n, u_n >= 0, r_n u_n = 0,
    |r_t| <= μ r_n, and where |r_t| < μ r_n, u_t = 0; where u_t ≠ 0, r_t u_t <= 0."""
    u = W @ r + q
    rn, rt, un, ut = r[0::2], r[1::2], u[0::2], u[1::2]
    scale = max(1.0, float(np.abs(q).max(initial=0.0)), float(np.abs(r).max(initial=0.0)))
    cone = np.maximum(np.abs(rt) - mu * rn, 0.0)
    stick = np.minimum(np.abs(ut), np.maximum(mu * rn - np.abs(rt), 0.0))
    direction = np.maximum(rt * np.sign(ut), 0.0)
    worst = max(float(np.max(np.maximum(-rn, 0.0), initial=0.0)),
                float(np.max(np.maximum(-un, 0.0), initial=0.0)),
                float(np.max(np.minimum(np.abs(rn), np.abs(un)), initial=0.0)),
                float(np.max(cone, initial=0.0)), float(np.max(stick, initial=0.0)),
                float(np.max(np.minimum(direction, np.abs(ut)), initial=0.0)))
    return worst / scale


def fc2d_arrays(W, q, mu) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(W, q, mu)`` of the fc2d form as float arrays: W (2nc × 2nc), q (2nc), mu (nc);
    one ProblemError for other shapes."""
    W, q, mu = (np.asarray(x, dtype=float) for x in (W, q, mu))
    nc = mu.size
    if q.shape != (2 * nc,) or W.shape != (2 * nc, 2 * nc):
        raise ProblemError(f"W must be (2nc, 2nc) and q (2nc,) for nc = {nc} contacts, got "
                           f"{W.shape} and {q.shape}")
    return W, q, mu


def solve_fc2d(W, q, mu, *, method: str = "nsgs", tol: float | None = 1e-12,
               max_iter: int | None = None, timeout: float = 60.0) -> FC2DSolution:
    """Solve u = W r + q with 2-D Coulomb friction by a Siconos fc2d solver.

    ``W`` (2nc × 2nc), ``q`` (2nc) with each contact's (normal, tangential) rows
    together; ``mu`` (nc). Never raises for a solver failure: FAILED with a message
    (siconos absent, the worker died); ProblemError for an unknown method or shapes.
    """
    if method not in METHODS:
        raise ProblemError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    W, q, mu = fc2d_arrays(W, q, mu)
    nc = mu.size
    nan = np.full(2 * nc, np.nan)
    if not available():
        return FC2DSolution(nan, nan, Status.FAILED, message="siconos not installed")
    header = {"op": "fc2d", "method": METHODS[method], "tol": tol, "max_iter": max_iter,
              "problems": [{"nc": nc}]}
    try:
        reply, data = call_worker(header, [W.T, q, mu], timeout)
    except RuntimeError as exc:
        return FC2DSolution(nan, nan, Status.FAILED, message=str(exc))
    if not reply.get("ok"):
        return FC2DSolution(nan, nan, Status.FAILED, message=str(reply.get("error")))
    res = reply["results"][0]
    r, u = data[:2 * nc].copy(), data[2 * nc:4 * nc].copy()
    if res.get("error"):
        return FC2DSolution(r, u, Status.FAILED, message=res["error"], extra=res)
    residual = coulomb_residual(W, q, mu, r) if np.all(np.isfinite(r)) else np.inf
    ok = res["info"] == 0 and residual <= ACCEPT_TOL
    status = Status.SOLVED if ok else (Status.INACCURATE if np.isfinite(residual)
                                       else Status.FAILED)
    msg = "" if ok else f"siconos info {res['info']}, Coulomb residual {residual:.3g}"
    return FC2DSolution(r, u, status, res.get("iterations", 0), residual, msg, res)
