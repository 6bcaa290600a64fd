"""Block principal pivoting from a support (solvers/pivoting_kernel.py), the frictional
step's warm start: against enumeration of every support (an independent oracle), and
never a wrong answer called DONE."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from lcpbench.numba_cache import jit_module

# through the kernels' cache (a direct import would cache them beside their sources)
pk = jit_module("lcpbench.solvers.pivoting_kernel")
frictional_lcp = jit_module("lcpbench.model.friction_step").frictional_lcp

FEAS, PIV, RCOND = 1e-10, 1e-13, 1e-12


def enumerate_lcp(M, q, tol=1e-9):
    """Every solution of the LCP found by trying each support S: z_S = −M_SS⁻¹ q_S."""
    n = q.size
    found = []
    for bits in itertools.product((False, True), repeat=n):
        S = np.array(bits)
        z = np.zeros(n)
        if S.any():
            try:
                z[S] = np.linalg.solve(M[np.ix_(S, S)], -q[S])
            except np.linalg.LinAlgError:
                continue
        w = M @ z + q
        if z.min() >= -tol and w.min() >= -tol and abs(z @ w) <= tol:
            found.append(z)
    return found


def p_matrix(rng, n):
    """A nonsymmetric P-matrix (positive definite symmetric part): one solution."""
    B = rng.normal(size=(n, n))
    return B @ B.T / n + 0.2 * np.eye(n) + 0.5 * (B - B.T) / np.sqrt(n)


@pytest.mark.parametrize("seed", range(6))
def test_p_matrix_from_any_start_is_the_enumerated_solution(seed):
    rng = np.random.default_rng(seed)
    n = 7
    M, q = p_matrix(rng, n), rng.normal(size=n)
    (z_star,) = enumerate_lcp(M, q)
    for _ in range(5):
        start = rng.random(n) < 0.5
        z, w, S, end, solves = pk.support_pivots(M, q, start, 200, FEAS, PIV, RCOND)
        assert end == pk.DONE
        assert np.allclose(z, z_star, rtol=0, atol=1e-10)
        assert np.allclose(w, M @ z_star + q, rtol=0, atol=1e-10)


def test_from_the_answers_own_support_one_solve():
    rng = np.random.default_rng(39)
    M, q = p_matrix(rng, 8), rng.normal(size=8)
    (z_star,) = enumerate_lcp(M, q)
    z, _, _, end, solves = pk.support_pivots(M, q, z_star > 0, 20, FEAS, PIV, RCOND)
    assert end == pk.DONE and solves == 1
    assert np.allclose(z, z_star, rtol=0, atol=1e-12)


def fc2d_problem(rng, nc):
    """u = W r + q with W symmetric positive definite (as tests/solvers/
    test_fc2d_friction_solvers.py), every contact pressed by the free motion."""
    B = rng.normal(size=(2 * nc, 2 * nc))
    W = B @ B.T / (2 * nc) + 0.1 * np.eye(2 * nc)
    q = rng.normal(size=2 * nc)
    q[0::2] = -np.abs(q[0::2])
    return W, q, rng.uniform(0.05, 1.0, nc)


@pytest.mark.parametrize("seed", range(8))
def test_frictional_lcp_answers_obey_coulomb_and_are_enumerated(seed):
    """On the Stewart–Trinkle LCP of small fc2d problems (not P-matrices), a DONE answer
    is one of the LCP's solutions found by enumeration, and satisfies Signorini–Coulomb
    contact by contact (checked on (N, T) directly)."""
    rng = np.random.default_rng(100 + seed)
    nc = 2
    W, q, mu = fc2d_problem(rng, nc)
    n_idx, t_idx = 2 * np.arange(nc), 2 * np.arange(nc) + 1
    idx = np.concatenate([n_idx, t_idx])
    Wb = W[np.ix_(idx, idx)]
    M, qq = frictional_lcp(Wb, q[n_idx], q[t_idx], mu, np.arange(nc))
    answers = enumerate_lcp(M, qq)
    assert answers  # (the LCP always has a solution: W is positive definite)
    start = np.zeros(qq.size, bool)
    start[:nc] = True  # every wall row pressed, sticking
    z, w, S, end, _ = pk.support_pivots(M, qq, start, 50, FEAS, PIV, RCOND)
    if end != pk.DONE:
        return  # not finite on these matrices: the caller falls back to Lemke
    assert any(np.allclose(z, a, rtol=0, atol=1e-8) for a in answers)
    N, T = z[:nc], z[nc:2 * nc] - z[2 * nc:3 * nc]
    u = W @ np.ravel(np.column_stack([N, T])) + q
    un, ut = u[0::2], u[1::2]
    assert np.all(N >= -1e-10) and np.all(un >= -1e-9) and np.all(np.abs(N * un) <= 1e-9)
    assert np.all(np.abs(T) <= mu * N + 1e-9)
    slides = np.abs(ut) > 1e-9
    assert np.allclose(np.abs(T[slides]), (mu * N)[slides], rtol=0, atol=1e-9)
    assert np.all(T[slides] * ut[slides] <= 1e-12)


@pytest.mark.parametrize("seed", range(20))
def test_never_done_with_a_wrong_answer(seed):
    """Arbitrary matrices (no solution promised): DONE only where z, w >= 0 and z'w = 0."""
    rng = np.random.default_rng(seed)
    n = 6
    M, q = rng.normal(size=(n, n)), rng.normal(size=n)
    z, w, S, end, _ = pk.support_pivots(M, q, rng.random(n) < 0.5, 30, FEAS, PIV, RCOND)
    assert end in (pk.DONE, pk.MAX_ITER, pk.SINGULAR, pk.CYCLE)
    if end == pk.DONE:
        w_true = M @ z + q
        scale = max(1.0, np.abs(q).max(), np.abs(z).max())
        assert z.min() >= 0.0 and w_true.min() >= -1e-9 * scale
        assert abs(z @ w_true) <= 1e-9 * scale


def test_a_singular_support_takes_the_least_squares_answer():
    """Two identical columns and rows (a run of nodes that stick: T per node is
    indeterminate): M_SS singular but consistent; the answer splits the load equally (the
    least norm) and solves the LCP."""
    M = np.array([[2.0, 2.0, 0.0], [2.0, 2.0, 0.0], [0.0, 0.0, 1.0]])
    q = np.array([-2.0, -2.0, 1.0])
    z, w, S, end, _ = pk.support_pivots(M, q, np.array([True, True, False]), 10, FEAS, PIV,
                                        RCOND)
    assert end == pk.DONE
    assert np.allclose(z, [0.5, 0.5, 0.0], rtol=0, atol=1e-12)
    assert np.allclose(M @ z + q, [0.0, 0.0, 1.0], rtol=0, atol=1e-12)
    z, w, S, end, _ = pk.support_pivots(M, q, np.array([True, True, False]), 10, FEAS, PIV,
                                        0.0)
    assert end == pk.SINGULAR  # (least squares turned off)


def test_lu_solve_against_numpy():
    rng = np.random.default_rng(3)
    A, b = rng.normal(size=(9, 9)), rng.normal(size=9)
    x, ok = pk.lu_solve(A.copy(), b.copy(), 1e-14)
    assert ok and np.allclose(x, np.linalg.solve(A, b), rtol=1e-12, atol=1e-12)
    A[:, 4] = A[:, 2]
    assert not pk.lu_solve(A.copy(), b.copy(), 1e-13)[1]


def reference_walk(M, q, S, changes, feas=FEAS, block_tries=3):
    """Júdice & Pires' walk as the module's note states it, written from that note with
    numpy's dense solve and no cycle test: (end, solves, z), end "done" or "budget";
    None where some M_SS is singular (the kernel's least squares is not this one's)."""
    n = q.size
    S = S.copy()
    best, stalled = n + 1, 0
    for it in range(1, changes + 1):
        z = np.zeros(n)
        if S.any():
            A = M[np.ix_(S, S)]
            if np.linalg.cond(A) > 1e10:
                return None
            z[S] = np.linalg.solve(A, -q[S])
        w = M @ z + q
        eps = feas * max(1.0, np.abs(q).max(), np.abs(z).max())
        bad = (S & (z < -eps)) | (~S & (w < -eps))
        if not bad.any():
            return "done", it, z
        if bad.sum() < best:
            best, stalled = bad.sum(), 0
        else:
            stalled += 1
        if stalled < block_tries:
            S = S ^ bad
        else:
            S[np.flatnonzero(bad)[0]] = not S[np.flatnonzero(bad)[0]]
    return "budget", changes, None


def test_a_cycle_ends_the_walk_where_the_budget_would_have_been_spent_for_nothing():
    """Arbitrary matrices (not P-matrices: the walk may go round): against the walk
    without a cycle test (:func:`reference_walk`, 200 changes), the kernel ends DONE
    exactly where it does (the same solves, the same z), and CYCLE only where it never
    gets there; some of these walks do go round."""
    rng = np.random.default_rng(7)
    cycles = 0
    for _ in range(300):
        n = 6
        M, q = rng.normal(size=(n, n)), rng.normal(size=n)
        start = rng.random(n) < 0.5
        ref = reference_walk(M, q, start, 200)
        if ref is None:
            continue
        z, w, S, end, solves = pk.support_pivots(M, q, start, 200, FEAS, PIV, 0.0)
        if ref[0] == "done":
            assert end == pk.DONE and solves == ref[1]
            assert np.allclose(z, np.maximum(ref[2], 0.0), rtol=0, atol=1e-9)
        else:
            assert end in (pk.CYCLE, pk.MAX_ITER)
            cycles += end == pk.CYCLE
            if end == pk.CYCLE:
                assert solves < 200
    assert cycles > 0


def numpy_residuals(M, q, z):
    """lcpbench's residuals from their definition, in numpy (the oracle)."""
    w = M @ z + q
    scale = max(1.0, float(np.max(np.abs(q), initial=0.0)))
    return {"natural": float(np.max(np.abs(np.minimum(z, w)), initial=0.0)) / scale,
            "min_z": float(np.min(z, initial=0.0)),
            "min_w": float(np.min(w, initial=0.0)) / scale,
            "complementarity": abs(float(z @ w)) / scale}


@pytest.mark.parametrize("n", [0, 1, 5, 40])
def test_lcp_residuals_are_their_definition(n):
    """solvers.base.lcp_residuals (the compiled pass) against the definition: the same
    values to round-off, NaN where z or w has one, w = M z + q returned on request."""
    from lcpbench.solvers.base import lcp_residuals

    rng = np.random.default_rng(n)
    for trial in range(6):
        M, q = rng.normal(size=(n, n)), 3.0 * rng.normal(size=n)
        z = np.maximum(rng.normal(size=n), 0.0)
        if trial == 1 and n:
            z[n // 2] = np.nan
        got, w = lcp_residuals(M, q, z, with_w=True)
        want = numpy_residuals(M, q, z)
        assert set(got) == set(want)
        for key, value in want.items():
            if np.isnan(value):
                assert np.isnan(got[key]), key
            else:
                assert got[key] == pytest.approx(value, rel=1e-12, abs=1e-300), key
        assert np.allclose(w, M @ z + q, rtol=1e-13, atol=1e-13, equal_nan=True)
