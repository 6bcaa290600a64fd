"""Validation against Euler–Bernoulli beam theory (Sec. III-G, eqs. 33–37)."""

from __future__ import annotations

import math

import numpy as np

from ..api import solve
from ..problems.cantilever import CantileverScene


def cantilever_validation(links: int = 140, *, tol: float = 1e-10, **scene) -> dict:
    """Model tip reaction against the theory of eqs. (34)–(37).

    The theory is linear (small deflections); the model keeps the exact
    geometry, so at the paper's load (tip deflection 1 mm over 30 mm) the two
    differ by the geometric nonlinearity as N → ∞ as well as by the
    discretisation. Returns the fields of ``lcpbench validate cantilever``.
    """

    sc = CantileverScene(links=links, **scene)
    res = solve(sc, tol=tol)
    theory = sc.theory_force()
    model = res.total_force
    return {
        "links": links,
        "model_force": model,
        "theory_force": theory,
        "relative_error": (model - theory) / theory if theory else math.nan,
        "converged": res.converged,
        "outer_iterations": res.outer_iterations,
        "contact_nodes": (np.asarray(res.contact_nodes) + 2).tolist(),  # 1-based node numbers
    }


def observed_order(links: list[int], values: list[float], reference: float | None = None) -> float:
    """Order p of convergence from a sequence at N, 2N, 4N, … (least squares).

    With a ``reference`` the errors are |v − reference|; without one, the
    differences of successive values (Richardson), which needs no limit.
    """
    links = np.asarray(links, float)
    v = np.asarray(values, float)
    if reference is not None:
        err, n = np.abs(v - reference), links
    else:
        err, n = np.abs(np.diff(v)), links[:-1]
    slope = np.polyfit(np.log(n), np.log(err), 1)[0]
    return float(-slope)
