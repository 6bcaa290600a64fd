"""Ruiz equilibration of QP and LCP data (solver-side: no actuator here).

Ruiz's scaling (D. Ruiz, "A scaling algorithm to equilibrate both rows and columns
norms in matrices", RAL-TR-2001-034) divides each row and column of a symmetric
matrix by the square root of its largest entry, repeatedly, until every row's
largest entry is near 1. OSQP and Clarabel run it on their KKT matrix internally;
here it is applied to the data before a back-end sees it, so that every back-end
gets the same equilibrated problem and the answer is mapped back exactly:

* a QP ``min ½xᵀPx + cᵀx``, ``lower <= x <= upper``, ``row_lower <= A x <=
  row_upper``: ``x = D x̃``, rows scaled by E, the cost by σ. P̃ = σDPD, c̃ = σDc,
  Ã = EAD; a bound multiplier maps back as ``y = ỹ / (σ D)``, a row multiplier as
  ``y_rows = E ỹ_rows / σ``;
* an LCP ``w = M z + q``: ``z = D z̃``, ``w = w̃ / D`` with M̃ = DMD, q̃ = Dq (the
  same complementarity problem, symmetric M stays symmetric).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: sweeps of the scaling, and the spread of the largest entries at which it stops
RUIZ_SWEEPS = 25
RUIZ_SPREAD = 1e-3
#: a scaling factor is held within [1/LIMIT, LIMIT] per sweep (zero rows and columns)
RUIZ_LIMIT = 1e4


@dataclass
class Scaling:
    """``x = D x̃`` on the unknowns, E on the rows, σ on the cost."""

    D: np.ndarray
    E: np.ndarray
    sigma: float = 1.0


def _col_max(S) -> np.ndarray:
    """Largest |entry| of each column of a sparse or dense matrix."""
    if hasattr(S, "tocsc"):
        return np.asarray(abs(S).max(axis=0).todense()).ravel()
    return np.max(np.abs(S), axis=0, initial=0.0)


def ruiz_symmetric(K, sweeps: int = RUIZ_SWEEPS) -> np.ndarray:
    """The diagonal d with every column of ``diag(d) |K| diag(d)`` (K symmetric in
    pattern, sparse or dense) of largest entry near 1."""
    import scipy.sparse as sp

    n = K.shape[0]
    d = np.ones(n)
    dense = not sp.issparse(K)
    Ka = np.abs(K) if dense else abs(sp.csc_matrix(K))
    Ka = np.maximum(Ka, Ka.T) if dense else Ka.maximum(Ka.T).tocsc()
    for _ in range(sweeps):
        S = (d[:, None] * Ka * d[None, :]) if dense else sp.diags(d) @ Ka @ sp.diags(d)
        norms = _col_max(S)
        if norms.size and np.max(np.abs(1.0 - norms[norms > 0]), initial=0.0) < RUIZ_SPREAD:
            break
        delta = np.where(norms > 0, 1.0 / np.sqrt(np.where(norms > 0, norms, 1.0)), 1.0)
        d *= np.clip(delta, 1.0 / RUIZ_LIMIT, RUIZ_LIMIT)
    return d


def equilibrate_lcp(M: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(M̃, q̃, D)``: M̃ = DMD, q̃ = Dq; an answer maps back as z = D z̃, w = w̃ / D."""
    D = ruiz_symmetric(M)
    return D[:, None] * M * D[None, :], D * q, D


def equilibrate_qp(P, c: np.ndarray, A=None) -> Scaling:
    """The Ruiz scaling of a QP's KKT matrix ``[[P, Aᵀ], [A, 0]]`` and its cost σ."""
    import scipy.sparse as sp

    n = c.size
    P = sp.csc_matrix(P)
    if A is None or A.shape[0] == 0:
        K, m = P, 0
    else:
        m = A.shape[0]
        K = sp.bmat([[P, sp.csc_matrix(A).T], [A, None]], format="csc")
    d = ruiz_symmetric(K)
    D, E = d[:n], d[n:n + m]
    Ps = sp.diags(D) @ P @ sp.diags(D)
    col = _col_max(Ps)
    scale = max(float(np.mean(col)) if col.size else 0.0, float(np.max(np.abs(D * c), initial=0.0)))
    sigma = 1.0 / scale if scale > 0 else 1.0
    return Scaling(D, E, float(np.clip(sigma, 1.0 / RUIZ_LIMIT, RUIZ_LIMIT)))


def scale_qp(qp, scaling: Scaling):
    """The equilibrated copy of a BoxQP or LinearQP (see the module note)."""
    import scipy.sparse as sp

    from .base import BoxQP, LinearQP

    D, E, s = scaling.D, scaling.E, scaling.sigma
    Dm = sp.diags(D)
    P = (s * (Dm @ sp.csc_matrix(qp.P) @ Dm)).tocsc()
    c = s * D * qp.c
    lo, hi = qp.lower / D, qp.upper / D
    if getattr(qp, "A", None) is None:
        return BoxQP(P, c, lo, hi)
    A = (sp.diags(E) @ sp.csr_matrix(qp.A) @ Dm).tocsr()
    return LinearQP(P, c, lo, hi, A=A, row_lower=E * qp.row_lower, row_upper=E * qp.row_upper)


def unscale_qp(scaling: Scaling, x: np.ndarray, y: np.ndarray,
               y_rows: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """An equilibrated QP's ``(x, y, y_rows)`` in the original problem's terms."""
    D, E, s = scaling.D, scaling.E, scaling.sigma
    return D * x, y / (s * D), None if y_rows is None else E * y_rows / s
