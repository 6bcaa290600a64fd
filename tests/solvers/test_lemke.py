"""Tests of the dense Lemke solver.

Expected answers come from hand derivation, from an independent brute-force
enumeration of the 2^n complementary bases, or from LCP theory (a feasible
LCP with a positive semidefinite M is solved by Lemke; an infeasible one
ends on a ray) -- never from the solver's own output.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from known_answers import BOTH_ACTIVE, CYCLING_PRONE, IDENTITY, SECOND_ACTIVE, SICONOS_LCP_DIR

from lcpbench.solvers.base import LCPSolution, Status, lcp_residuals
from lcpbench.solvers.enumeration import enumerate_lcp
from lcpbench.solvers.lemke import _lexmin_row, lemke


def assert_valid(sol: LCPSolution, M: np.ndarray, q: np.ndarray) -> None:
    """``sol`` is SOLVED and its ``z`` solves the LCP to tight tolerances."""
    assert sol.status is Status.SOLVED, sol.message
    res = lcp_residuals(M, q, sol.z)
    assert res["min_z"] >= -1e-10
    assert res["min_w"] >= -1e-8
    assert res["complementarity"] <= 1e-8 * max(1.0, np.abs(sol.z).max())
    assert res["natural"] <= 1e-8
    np.testing.assert_allclose(sol.w, M @ sol.z + q, atol=1e-10 * max(1, np.abs(q).max()))


# --- 1. small hand-derivable problems -------------------------------------------------------


def test_identity_by_hand():
    # w = z + q: z = max(-q, 0), w = max(q, 0).
    M, q = IDENTITY.arrays()
    sol = lemke(M, q)
    assert_valid(sol, M, q)
    np.testing.assert_allclose(sol.z, IDENTITY.z, atol=1e-14)
    np.testing.assert_allclose(sol.w, IDENTITY.w, atol=1e-14)
    assert sol.iterations == 2  # z0 in, then z1 in / z0 out


def test_2x2_p_matrix_by_hand_and_enumeration():
    # M = [[2, 1], [1, 2]], q = [-5, -6]: both z > 0 gives z = [4/3, 7/3].
    M, q = BOTH_ACTIVE.arrays()
    sol = lemke(M, q)
    assert_valid(sol, M, q)
    np.testing.assert_allclose(sol.z, BOTH_ACTIVE.z, rtol=1e-12)
    # M = [[2, 1], [1, 2]], q = [1, -4]: z = [0, 2], w = [3, 0].
    q2 = SECOND_ACTIVE.arrays()[1]
    (ref,) = enumerate_lcp(M, q2)  # P-matrix: exactly one solution
    np.testing.assert_allclose(ref, SECOND_ACTIVE.z)
    np.testing.assert_allclose(lemke(M, q2).z, ref, atol=1e-12)


def test_nonsymmetric_p_matrix_against_enumeration():
    M = np.array([[1.0, 2.0, 0.0], [0.0, 1.0, 3.0], [4.0, 0.0, 1.0]])  # triangular-ish, P
    for q in ([-1.0, -1.0, -1.0], [2.0, -3.0, 1.0], [-5.0, 1.0, -2.0]):
        q = np.array(q)
        sols = enumerate_lcp(M, q)
        assert len(sols) >= 1
        sol = lemke(M, q)
        assert_valid(sol, M, q)
        assert any(np.allclose(sol.z, s, atol=1e-10) for s in sols)


# --- 2. trivial case ------------------------------------------------------------------------


def test_nonnegative_q_gives_zero():
    M = np.array([[1.0, -3.0], [2.0, 0.5]])
    q = np.array([0.0, 4.0])
    sol = lemke(M, q)
    assert sol.status is Status.SOLVED and sol.iterations == 0
    np.testing.assert_array_equal(sol.z, 0.0)
    np.testing.assert_array_equal(sol.w, q)


# --- 3. random SPD problems against enumeration ---------------------------------------------


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 8), seed=st.integers(0, 2**32 - 1))
def test_random_spd_matches_enumeration(n, seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    M = A @ A.T / n + 0.1 * np.eye(n)
    q = rng.normal(size=n) * rng.choice([1e-2, 1.0, 1e2])
    (ref,) = enumerate_lcp(M, q)  # SPD => P-matrix => unique solution
    sol = lemke(M, q)
    assert_valid(sol, M, q)
    np.testing.assert_allclose(sol.z, ref, atol=1e-8 * max(1.0, np.abs(ref).max()))


@settings(max_examples=40, deadline=None)
@given(n=st.integers(9, 12), seed=st.integers(0, 2**32 - 1))
def test_random_spd_larger_is_valid(n, seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    M = A @ A.T / n + 0.1 * np.eye(n)
    q = rng.normal(size=n)
    assert_valid(lemke(M, q), M, q)


# --- 4. degenerate / tie-prone problems -----------------------------------------------------


def test_all_ratios_tie_identity():
    # q = -1: every row ties in the first ratio test; answer z = 1, w = 0.
    n = 6
    M, q = np.eye(n), -np.ones(n)
    sol = lemke(M, q)
    assert_valid(sol, M, q)
    np.testing.assert_allclose(sol.z, 1.0, atol=1e-12)


def test_rank_one_duplicated_columns():
    # M = 1 1' (PSD, all columns equal), q = -1: solutions are {z >= 0, sum z = 1}, w = 0.
    n = 4
    M, q = np.ones((n, n)), -np.ones(n)
    sol = lemke(M, q)
    assert_valid(sol, M, q)
    assert math.isclose(sol.z.sum(), 1.0, rel_tol=1e-12)
    np.testing.assert_allclose(sol.w, 0.0, atol=1e-12)


def test_zeros_in_q_degenerate():
    # q has zeros and repeated entries; M SPD so the solution is unique.
    M = np.array([[2.0, -1.0, 0.0, 0.0], [-1.0, 2.0, -1.0, 0.0],
                  [0.0, -1.0, 2.0, -1.0], [0.0, 0.0, -1.0, 2.0]])
    for q in ([0.0, -1.0, 0.0, -1.0], [-1.0, 0.0, 0.0, -1.0], [0.0, 0.0, -1.0, 0.0]):
        q = np.array(q)
        (ref,) = enumerate_lcp(M, q)
        sol = lemke(M, q)
        assert_valid(sol, M, q)
        np.testing.assert_allclose(sol.z, ref, atol=1e-12)


@settings(max_examples=80, deadline=None)
@given(n=st.integers(1, 8), k=st.integers(1, 8), seed=st.integers(0, 2**32 - 1))
def test_degenerate_psd_with_planted_solution(n, k, seed):
    """Singular integer PSD M, q planted from a complementary (z*, w*) with many double zeros.

    Theory: a feasible LCP with PSD M is solved by Lemke (with anti-cycling), and for
    symmetric PSD M the vector w is the same at every solution, so w == w*.
    """
    rng = np.random.default_rng(seed)
    B = rng.integers(-2, 3, size=(n, min(k, n))).astype(float)
    B[:, 0] = B[:, -1]  # a duplicated column => extra singularity
    M = B @ B.T
    kind = rng.integers(0, 3, size=n)  # 0: z=w=0 (degenerate), 1: z>0, 2: w>0
    z_star = np.where(kind == 1, rng.integers(1, 3, size=n), 0).astype(float)
    w_star = np.where(kind == 2, rng.integers(1, 3, size=n), 0).astype(float)
    q = w_star - M @ z_star
    sol = lemke(M, q)
    assert_valid(sol, M, q)
    np.testing.assert_allclose(sol.w, w_star, atol=1e-8 * max(1.0, np.abs(q).max()))


# known_answers.CYCLING_PRONE: Lemke with a naive tie-break cycles on these.


@pytest.mark.parametrize("M, q", CYCLING_PRONE)
def test_cycling_prone_examples_solved(M, q):
    M, q = np.array(M, dtype=float), np.array(q, dtype=float)
    sols = enumerate_lcp(M, q)
    assert sols  # feasible: each has a solution
    sol = lemke(M, q)
    assert_valid(sol, M, q)
    assert any(np.allclose(sol.z, s, atol=1e-10) for s in sols)


def test_round_off_in_an_exact_zero_column_does_not_decide_the_order():
    # Rows 0-2 tie on the right-hand side; on B^{-1} column 0 they are exactly 0 in exact
    # arithmetic but hold round-off (~1e-17, rows of size ~1); column 1 is the first real
    # difference and row 2 has the least ratio there (0.15 < 0.18 < 0.45).
    n = 3
    tab = np.array([[-3.7e-17, 0.45, 1.0, 0.0],
                    [-7.3e-17, 0.18, -1.0, 0.0],
                    [-1.0e-18, 0.15, 1.0, 0.0]])
    rows, a = np.arange(3), np.ones(3)
    assert _lexmin_row(tab, rows, a, n, -1, 1.0) == 2
    # a genuine (not round-off) difference in column 0 still decides it
    tab[1, 0] = -1e-3
    assert _lexmin_row(tab, rows, a, n, -1, 1.0) == 1


PEER = SICONOS_LCP_DIR  # Siconos LCPs
needs_peer = pytest.mark.skipif(not PEER.is_dir(), reason="peer Siconos data not present")


@needs_peer
def test_siconos_tobenna_solved():
    """n = 40, q with 32 zeros: a deeply degenerate problem where the lexicographic test has to
    look past B^{-1} columns that are exactly zero (round-off only) in floating point; taking
    that round-off for a real difference broke the lexicographic order and Lemke cycled.
    An exact rational run of the same rules takes 127 pivots (Siconos 4.4 reports 126)."""
    from lcpbench.problems.lcpfile import read_lcp

    prob = read_lcp(PEER / "lcp_tobenna.dat")
    M, q = np.asarray(prob.M, dtype=float), np.asarray(prob.q, dtype=float)
    sol = lemke(M, q)
    assert sol.status is Status.SOLVED, sol.message
    assert 40 <= sol.iterations < 500
    # independent check with numpy, relative to the size of the terms summed in M z + q
    z = sol.z
    w = M @ z + q
    floor = float((np.abs(M) @ np.abs(z) + np.abs(q)).max())
    assert z.min() >= 0.0
    assert w.min() >= -1e-12 * floor
    assert abs(z @ w) <= 1e-12 * floor * np.abs(z).sum()
    assert np.abs(np.minimum(z, w)).max() <= 1e-12 * floor  # complementary row by row


# --- 5. no solution: secondary ray ----------------------------------------------------------


@pytest.mark.parametrize(
    "M, q",
    [
        ([[-1.0]], [-1.0]),  # w = -z - 1 < 0 for all z >= 0
        ([[0.0, 0.0], [0.0, 0.0]], [-1.0, 1.0]),  # w1 = -1
        ([[0.0, 1.0], [-1.0, 0.0]], [-1.0, -1.0]),  # skew (PSD): w2 = -z1 - 1 < 0
        ([[1.0, -1.0], [-1.0, 1.0]], [-1.0, -1.0]),  # PSD: w1 + w2 = -2 < 0
    ],
)
def test_infeasible_ends_on_ray(M, q):
    M, q = np.array(M), np.array(q)
    assert enumerate_lcp(M, q) == []
    sol = lemke(M, q)
    assert sol.status is Status.RAY
    assert sol.message


# --- 6. pivot budget ------------------------------------------------------------------------


def test_max_pivots_exhausted():
    M, q = np.eye(3), -np.ones(3)  # needs 4 pivots
    sol = lemke(M, q, max_pivots=1)
    assert sol.status is Status.MAX_ITER and sol.iterations == 1
    assert lemke(M, q, max_pivots=4).status is Status.SOLVED


# --- 7. statuses, bad input, covering -------------------------------------------------------


@pytest.mark.parametrize(
    "M, q",
    [
        (np.eye(2), [np.nan, -1.0]),
        (np.eye(2), [-np.inf, -1.0]),
        ([[1.0, np.nan], [0.0, 1.0]], [-1.0, -1.0]),
    ],
)
def test_non_finite_input_fails_cleanly(M, q):
    sol = lemke(np.array(M), np.array(q))
    assert isinstance(sol.status, Status)
    assert sol.status is Status.FAILED and sol.message


def test_overflow_fails_cleanly():
    sol = lemke(np.array([[1e-200]]), np.array([-1e200]))  # z = 1e400 overflows
    assert sol.status is Status.FAILED and sol.message


def test_failed_verification_is_inaccurate(monkeypatch):
    # The final check, not the pivoting, decides SOLVED: an impossible tolerance downgrades.
    import lcpbench.solvers.lemke as mod

    monkeypatch.setattr(mod, "RESIDUAL_TOL", -1.0)
    sol = mod.lemke(np.eye(2), np.array([-1.0, 2.0]))
    assert sol.status is Status.INACCURATE and "residual" in sol.message


def test_shape_mismatch_raises():
    with pytest.raises(ValueError):
        lemke(np.eye(2), np.ones(3))
    with pytest.raises(ValueError):
        lemke(np.eye(2), -np.ones(2), covering=np.array([1.0, 0.0]))


def test_custom_covering_vector():
    M = np.array([[2.0, 1.0], [1.0, 2.0]])
    q = np.array([-5.0, -6.0])
    sol = lemke(M, q, covering=np.array([0.5, 3.0]))
    assert_valid(sol, M, q)
    np.testing.assert_allclose(sol.z, [4 / 3, 7 / 3], rtol=1e-12)


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 6), seed=st.integers(0, 2**32 - 1))
def test_never_wrongly_solved_on_arbitrary_matrices(n, seed):
    # Arbitrary (possibly non-P, non-PSD) M: any status is allowed, but SOLVED must be right.
    rng = np.random.default_rng(seed)
    M, q = rng.normal(size=(n, n)), rng.normal(size=n)
    sol = lemke(M, q)
    assert isinstance(sol.status, Status)
    if sol.status is Status.SOLVED:
        assert_valid(sol, M, q)


# --- the contact-step shape ------------------------------------------------------------------


def test_pentadiagonal_spd_n139_like_the_contact_step():
    """The shape of the N = 140 contact step; speed is measured in benchmarks/, not here."""
    n = 139
    M = (6.01 * np.eye(n) - 4 * np.eye(n, k=1) - 4 * np.eye(n, k=-1)
         + np.eye(n, k=2) + np.eye(n, k=-2))  # (second difference)^2 + 0.01 I: SPD
    q = np.zeros(n)
    q[60:80] = -1.0  # a localised load
    sol = lemke(M, q)
    assert_valid(sol, M, q)
    # independent check: the LCP of an SPD M is the QP min ½zᵀMz + qᵀz, z >= 0
    from scipy.optimize import minimize
    ref = minimize(lambda z: 0.5 * z @ M @ z + q @ z, np.zeros(n), jac=lambda z: M @ z + q,
                   bounds=[(0, None)] * n, method="L-BFGS-B",
                   options={"ftol": 1e-15, "gtol": 1e-12, "maxiter": 10000})
    assert np.allclose(sol.z, ref.x, atol=1e-5 * np.abs(ref.x).max())


# -- size guard -------------------------------------------------------------------------
def test_tableau_over_the_memory_bound_is_failed_before_allocating():
    from lcpbench.solvers import lemke as lemke_mod

    n = lemke_mod._max_size() + 1
    assert lemke_mod.tableau_bytes(n) > lemke_mod.MAX_TABLEAU_BYTES
    assert lemke_mod.tableau_bytes(n - 1) <= lemke_mod.MAX_TABLEAU_BYTES
    M = np.broadcast_to(np.float64(1.0), (n, n))  # a view: no n x n memory
    sol = lemke(M, -np.ones(n))
    assert sol.status is Status.FAILED
    assert f"n = {n}" in sol.message and "GiB" in sol.message and "limit" in sol.message
    assert sol.iterations == 0


def test_size_guard_message_at_the_documented_maximum():
    from lcpbench.solvers import lemke as lemke_mod

    msg = lemke_mod.too_large(100_000)  # the scenes' largest N
    assert msg.startswith("problem too large for dense Lemke: n = 100000 needs a 74.51 GiB")
    assert lemke_mod.too_large(140) is None


@pytest.mark.parametrize("bad", [-1e-9, float("nan"), 0.5])
def test_a_tie_tolerance_out_of_range_is_refused_by_name(bad):
    with pytest.raises(ValueError, match="tie_rtol"):
        lemke(np.eye(2), np.array([-1.0, 1.0]), tie_rtol=bad)
