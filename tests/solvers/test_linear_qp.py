"""LinearQP (bounds and linear rows) in every QP back-end that takes rows, and the Ruiz
equilibration (lcpbench.solvers.equilibrate), checked by the KKT conditions."""

import numpy as np
import pytest
import scipy.sparse as sp

from lcpbench.solvers.base import PROFILES, LinearQP, Status
from lcpbench.solvers.equilibrate import (
    equilibrate_lcp,
    equilibrate_qp,
    scale_qp,
    unscale_qp,
)
from lcpbench.solvers.registry import available_backends, backends

ROWS = [pytest.param(name, id=name) for name, b in backends().items()
        if b.linear_rows and name in available_backends()
        and name not in ("qpsolvers-quadprog", "qpsolvers-qpoases")]  # strictly convex only


def _qp(seed=0, n=6, badly_scaled=False):
    rng = np.random.default_rng(seed)
    B = rng.standard_normal((n, n))
    s = np.logspace(0, 4, n) if badly_scaled else np.ones(n)
    P = sp.csc_matrix(s[:, None] * (B @ B.T + np.eye(n)) * s[None, :])
    A = sp.csr_matrix(rng.standard_normal((3, n)) * s[None, :])
    return LinearQP(P, rng.standard_normal(n) * s, np.full(n, -0.3) / s, np.full(n, np.inf),
                    A=A, row_lower=np.array([0.5, -np.inf, -0.2]),
                    row_upper=np.array([0.5, 0.1, np.inf]))


def _kkt(qp, x, y, yr):
    """Stationarity, feasibility and complementarity, relative to the data's size."""
    stat = qp.P @ x + qp.c + y + qp.A.T @ yr
    ax = qp.A @ x
    feas = max(np.max(np.maximum(qp.lower - x, 0)), np.max(np.maximum(ax - qp.row_upper, 0)),
               np.max(np.maximum(qp.row_lower - ax, 0)))
    comp = max(np.max(np.abs(np.minimum(np.abs(y), np.abs(x - qp.lower)))),
               np.max(np.abs(np.minimum(np.abs(yr[1:]), np.abs(np.r_[qp.row_upper[1] - ax[1],
                                                                      ax[2] - qp.row_lower[2]])))))
    return max(np.max(np.abs(stat)) / (1 + np.max(np.abs(qp.c))), feas, comp)


@pytest.mark.parametrize("name", ROWS)
def test_rows_and_their_multipliers(name):
    b = backends()[name]
    qp = _qp()
    res = b.load().solve_qp(qp, PROFILES["high"], None, **b.options)
    assert res.status is Status.SOLVED, res.message
    assert _kkt(qp, res.x, res.y, res.y_rows) <= 1e-6


@pytest.mark.parametrize("seed", range(4))
def test_ruiz_maps_back_to_the_original_kkt(seed):
    """Solved scaled, mapped back: the original problem's KKT conditions hold; the
    scaling brings the KKT matrix's largest entries near 1 (before the cost's σ)."""
    pytest.importorskip("osqp")
    from lcpbench.solvers.qp_osqp import solve_qp

    qp = _qp(seed, badly_scaled=True)
    scaling = equilibrate_qp(qp.P, qp.c, qp.A)
    small = scale_qp(qp, scaling)
    K = sp.bmat([[small.P / scaling.sigma, small.A.T], [small.A, None]]).toarray()
    assert np.all(np.abs(np.max(np.abs(K), axis=0) - 1) <= 0.05)
    res = solve_qp(small, PROFILES["high"])
    assert res.status is Status.SOLVED
    x, y, yr = unscale_qp(scaling, res.x, res.y, res.y_rows)
    assert _kkt(qp, x, y, yr) <= 1e-6


def test_ruiz_of_an_lcp_keeps_its_solutions():
    """z̃ solves the scaled LCP exactly when z = D z̃ solves the original (enumerated)."""
    rng = np.random.default_rng(1)
    B = rng.standard_normal((5, 5))
    s = np.logspace(0, 3, 5)
    M = s[:, None] * (B @ B.T + np.eye(5)) * s[None, :]
    q = rng.standard_normal(5) * s
    Ms, qs, D = equilibrate_lcp(M, q)
    assert np.allclose(Ms, Ms.T)
    import itertools
    for active in itertools.product([0, 1], repeat=5):  # the LCP by enumeration
        idx = np.flatnonzero(active)
        z = np.zeros(5)
        if idx.size:
            z[idx] = np.linalg.solve(M[np.ix_(idx, idx)], -q[idx])
        w = M @ z + q
        if np.all(z >= -1e-12) and np.all(w >= -1e-9 * np.max(np.abs(q))):
            break
    zt = z / D
    wt = Ms @ zt + qs
    assert np.all(zt >= -1e-12) and np.all(wt >= -1e-9 * np.max(np.abs(qs)))
    assert np.allclose(wt, D * w, rtol=0, atol=1e-9 * np.max(np.abs(D * w)))
