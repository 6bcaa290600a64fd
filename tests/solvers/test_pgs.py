"""Tests of projected Gauss–Seidel / projected SOR.

Expected answers come from hand derivation (iterates traced sweep by sweep),
from an independent brute-force enumeration of the 2^n complementary bases,
or from theory (PGS converges for symmetric positive definite M and
0 < omega < 2; its iterates map exactly under scaling) -- never from the
solver's own output.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from known_answers import BOTH_ACTIVE, SECOND_ACTIVE

from lcpbench.errors import ProblemError
from lcpbench.solvers.base import PROFILES, Settings, Status, lcp_residuals
from lcpbench.solvers.enumeration import enumerate_lcp
from lcpbench.solvers.pgs import pgs, solve_lcp


def random_spd(rng: np.random.Generator, n: int) -> np.ndarray:
    A = rng.normal(size=(n, n))
    return A @ A.T / n + 0.2 * np.eye(n)


def assert_solves(sol, M, q, atol=1e-8):
    """SOLVED, z >= 0, w reported as M z + q, natural residual small."""
    assert sol.status is Status.SOLVED, sol.message
    assert np.all(sol.z >= 0)
    np.testing.assert_allclose(sol.w, M @ sol.z + q, rtol=0, atol=1e-12 * max(1, np.abs(q).max()))
    assert lcp_residuals(M, q, sol.z)["natural"] <= atol


# --- 1. hand-derived problems ---------------------------------------------------------------


def test_diagonal_is_exact_after_one_sweep():
    # M = diag(2, 4), q = [-2, 4]: rows decouple, z = [1, 0], w = [0, 4], one sweep.
    M, q = np.diag([2.0, 4.0]), np.array([-2.0, 4.0])
    sol = pgs(M, q)
    assert_solves(sol, M, q)
    assert sol.iterations == 1
    np.testing.assert_array_equal(sol.z, [1.0, 0.0])
    np.testing.assert_array_equal(sol.w, [0.0, 4.0])


def test_nonnegative_q_gives_zero_without_sweeping():
    M, q = np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([0.0, 3.0])
    sol = pgs(M, q)
    assert sol.status is Status.SOLVED and sol.iterations == 0
    np.testing.assert_array_equal(sol.z, 0.0)
    np.testing.assert_array_equal(sol.w, q)


def test_q_zero_is_solved_by_zero():
    sol = pgs(np.eye(3), np.zeros(3))
    assert sol.status is Status.SOLVED and sol.iterations == 0
    assert sol.extra["residual"] == 0.0


def test_one_constraint_active_by_hand():
    # M = [[2, 1], [1, 2]], q = [1, -4]. Sweep 1 from z = 0: w_0 = 1 > 0 keeps z_0 = 0;
    # w_1 = -4 gives z_1 = 4 / 2 = 2. Then w = [3, 0]: solved exactly after one sweep.
    M, q = SECOND_ACTIVE.arrays()
    sol = pgs(M, q)
    assert_solves(sol, M, q)
    assert sol.iterations == 1
    np.testing.assert_array_equal(sol.z, SECOND_ACTIVE.z)
    np.testing.assert_array_equal(sol.w, SECOND_ACTIVE.w)


def test_first_sweep_is_gauss_seidel_not_jacobi():
    # M = [[2, 1], [1, 2]], q = [-5, -6], z = 0. Row 0: z_0 = 5/2. Row 1 sees the new z_0:
    # w_1 = 2.5 - 6 = -3.5, z_1 = 1.75 (Jacobi would give 3). With omega = 1.5:
    # z_0 = 1.5 * 5/2 = 3.75, w_1 = 3.75 - 6 = -2.25, z_1 = 1.5 * 2.25 / 2 = 1.6875.
    M, q = BOTH_ACTIVE.arrays()
    one = pgs(M, q, max_sweeps=1)
    assert one.status is Status.MAX_ITER and one.iterations == 1
    np.testing.assert_array_equal(one.z, [2.5, 1.75])
    sor = pgs(M, q, omega=1.5, max_sweeps=1)
    np.testing.assert_array_equal(sor.z, [3.75, 1.6875])


def test_both_active_converges_to_hand_solution():
    # Both z > 0: M z = -q gives z = [4/3, 7/3], w = 0.
    M, q = BOTH_ACTIVE.arrays()
    sol = pgs(M, q, eps=1e-12)
    assert_solves(sol, M, q, atol=1e-11)
    np.testing.assert_allclose(sol.z, BOTH_ACTIVE.z, rtol=1e-11)
    assert sol.extra["omega"] == 1.0 and sol.extra["residual"] <= 1e-12
    assert sol.solve_time >= 0 and sol.setup_time >= 0


def test_rate_is_the_gauss_seidel_contraction():
    # 2x2 SPD [[a, b], [b, a]] with both z > 0: PGS is plain Gauss-Seidel, whose error
    # contracts by (b/a)^2 per sweep. [[2, 1], [1, 2]]: 1/4.
    M, q = BOTH_ACTIVE.arrays()
    assert pgs(M, q, eps=1e-12).extra["rate"] == pytest.approx(0.25, rel=0.02)


def test_ill_conditioned_solved_z_is_only_as_good_as_residual_over_one_minus_rate():
    # [[1, 1-e], [1-e, 1]], q = -[1, 1]: z* = [1, 1] / (2 - e); GS rate (1-e)^2 = 0.998.
    # The test stops on a small *step*; the error in z is ~ residual / (1 - rate) >> tol.
    e = 1e-3
    M, q = np.array([[1.0, 1 - e], [1 - e, 1.0]]), -np.ones(2)
    z_star = np.ones(2) / (2 - e)
    sol = pgs(M, q, eps=1e-6)
    assert sol.solved
    assert sol.extra["rate"] == pytest.approx((1 - e) ** 2, rel=1e-6)
    err = np.abs(sol.z - z_star).max() / z_star.max()
    estimate = sol.extra["residual"] / (1 - sol.extra["rate"])
    assert err > 100 * 1e-6
    assert estimate / 4 <= err <= 4 * estimate


# --- 2. random SPD problems against enumeration ---------------------------------------------


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 6), seed=st.integers(0, 2**32 - 1),
       omega=st.sampled_from([1.0, 0.7, 1.5]))
def test_random_spd_matches_enumeration(n, seed, omega):
    rng = np.random.default_rng(seed)
    M = random_spd(rng, n)
    q = rng.normal(size=n) * rng.choice([1e-2, 1.0, 1e2])
    (ref,) = enumerate_lcp(M, q)  # SPD => P-matrix => exactly one solution
    sol = pgs(M, q, omega=omega, eps=1e-12)
    assert_solves(sol, M, q, atol=1e-9)
    cond = np.linalg.cond(M)
    np.testing.assert_allclose(sol.z, ref, atol=1e-10 * cond * max(1.0, np.abs(ref).max()))


def test_sor_reaches_the_same_answer():
    rng = np.random.default_rng(7)
    M = random_spd(rng, 6)
    q = rng.normal(size=6)
    (ref,) = enumerate_lcp(M, q)
    gs, sor = pgs(M, q, eps=1e-12), pgs(M, q, omega=1.5, eps=1e-12)
    for sol in (gs, sor):
        assert_solves(sol, M, q, atol=1e-10)
        np.testing.assert_allclose(sol.z, ref, atol=1e-9)
    assert sor.extra["omega"] == 1.5


def test_banded_spd_and_sparse_input():
    # Tridiagonal SPD M (the banded column updates touch only 3 rows) given dense and as CSR.
    n = 30
    M = 2.5 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    q = np.sin(np.arange(n)) - 0.2
    dense = pgs(M, q, eps=1e-12)
    assert_solves(dense, M, q, atol=1e-10)
    sparse = pgs(sp.csr_matrix(M), q, eps=1e-12)
    np.testing.assert_array_equal(sparse.z, dense.z)
    assert sparse.iterations == dense.iterations


# --- 3. invariance of the stopping test -----------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_scale_invariance(seed):
    rng = np.random.default_rng(seed)
    M = random_spd(rng, 8)
    q = rng.normal(size=8)
    base = pgs(M, q, eps=1e-9)
    assert base.solved
    for s in (1e-6, 1e6):
        scaled = pgs(s * M, s * q, eps=1e-9)
        assert scaled.solved and scaled.iterations == base.iterations
        np.testing.assert_allclose(scaled.z, base.z, rtol=1e-12, atol=1e-13)
        assert scaled.extra["residual"] == pytest.approx(base.extra["residual"], rel=1e-6)
    # A power of two scales without rounding: bit-identical iterates.
    exact = pgs(2.0**-30 * M, 2.0**-30 * q, eps=1e-9)
    np.testing.assert_array_equal(exact.z, base.z)


def test_symmetric_diagonal_scaling_maps_iterates():
    # (D M D, D q) has iterates D^{-1} z; powers of two make the map exact, sweep by sweep.
    rng = np.random.default_rng(3)
    M = random_spd(rng, 5)
    q = rng.normal(size=5)
    d = 2.0 ** np.array([-20, -3, 0, 5, 18])
    for k in (1, 4, 25):
        plain = pgs(M, q, eps=0.0, max_sweeps=k)
        scaled = pgs(d[:, None] * M * d[None, :], d * q, eps=0.0, max_sweeps=k)
        np.testing.assert_array_equal(scaled.z, plain.z / d)
    # A moderate scaling is still solved to the same answer. (The test takes a max over
    # rows, so wildly different d_i -- like the 2^38 spread above -- loosen it on the
    # rows measured in the smaller units; that is documented, not tested.)
    d = 2.0 ** np.array([-3, -1, 0, 2, 3])
    sol = pgs(d[:, None] * M * d[None, :], d * q, eps=1e-12)
    assert sol.solved
    (ref,) = enumerate_lcp(M, q)
    np.testing.assert_allclose(sol.z * d, ref, atol=1e-9)


# --- 4. problems PGS cannot solve -----------------------------------------------------------


def test_zero_diagonal_fails_with_message():
    M, q = np.array([[0.0, 1.0], [-1.0, 0.0]]), np.array([-1.0, 1.0])
    sol = pgs(M, q)
    assert sol.status is Status.FAILED and sol.iterations == 0
    assert "M_ii > 0" in sol.message and "M[0, 0]" in sol.message


def test_negative_diagonal_fails():
    sol = pgs(np.array([[1.0, 0.0], [0.0, -2.0]]), np.array([-1.0, -1.0]))
    assert sol.status is Status.FAILED and "M[1, 1]" in sol.message


def test_nonsymmetric_two_cycle_is_not_solved():
    # M = [[1, 3], [-3, 1]] (positive definite, not symmetric; unique solution
    # z = [0.1, 0.3]), q = [-1, 0]. From z = 0: sweep 1 gives z = [1, 3]; sweep 2:
    # w_0 = 1 + 9 - 1 = 9 -> z_0 = 0, w_1 = 3 -> z_1 = 0, back to z = 0: a 2-cycle.
    M, q = np.array([[1.0, 3.0], [-3.0, 1.0]]), np.array([-1.0, 0.0])
    (ref,) = enumerate_lcp(M, q)
    np.testing.assert_allclose(ref, [0.1, 0.3])
    sol = pgs(M, q, max_sweeps=501)
    assert sol.status is Status.MAX_ITER and sol.iterations == 501
    np.testing.assert_array_equal(sol.z, [1.0, 3.0])
    assert "501" in sol.message
    assert pgs(M, q, max_sweeps=500).z.tolist() == [0.0, 0.0]


def test_divergence_to_infinity_fails():
    # M = [[1, -3], [-3, 1]], q = [-1, -1]: infeasible; each sweep multiplies z by ~9.
    sol = pgs(np.array([[1.0, -3.0], [-3.0, 1.0]]), np.array([-1.0, -1.0]))
    assert sol.status is Status.FAILED and "non-finite" in sol.message
    assert sol.iterations < 1000


@settings(max_examples=60, deadline=None)
@given(n=st.integers(2, 5), seed=st.integers(0, 2**32 - 1))
def test_never_solved_with_a_wrong_answer(n, seed):
    """Non-symmetric M with a positive diagonal: if PGS says SOLVED, z really solves."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(n, n)) * 2
    M[np.diag_indices(n)] = rng.uniform(0.5, 2.0, size=n)
    q = rng.normal(size=n)
    sol = pgs(M, q, eps=1e-10, max_sweeps=300)
    assert sol.status in (Status.SOLVED, Status.MAX_ITER, Status.FAILED)
    if sol.solved:
        w = M @ sol.z + q
        scale = max(1.0, np.abs(q).max(), np.abs(sol.z).max())
        assert sol.z.min() >= 0
        assert np.abs(np.minimum(sol.z, w)).max() <= 1e-8 * scale


# --- 5. warm start, time limit, adapter -----------------------------------------------------


def test_warm_start_at_solution_takes_no_sweep_and_negative_warm_is_clipped():
    M, q = SECOND_ACTIVE.arrays()
    sol = pgs(M, q, z0=list(SECOND_ACTIVE.z))
    assert sol.solved and sol.iterations == 0
    clipped = pgs(M, q, z0=[-5.0, -1.0], max_sweeps=0)  # projected to 0, not yet swept
    np.testing.assert_array_equal(clipped.z, [0.0, 0.0])


def test_time_limit_stops_after_a_sweep():
    M, q = BOTH_ACTIVE.arrays()
    sol = pgs(M, q, time_limit=0.0)
    assert sol.status is Status.MAX_ITER and sol.iterations == 1
    assert "time limit" in sol.message


def test_adapter_translates_settings():
    M, q = BOTH_ACTIVE.arrays()
    default = solve_lcp(M, q, PROFILES["default"])
    assert default.solved and default.extra["eps"] == 1e-8
    low, high = solve_lcp(M, q, PROFILES["low"]), solve_lcp(M, q, PROFILES["high"])
    assert low.extra["eps"] == 1e-3 and high.extra["eps"] == 1e-9
    assert low.iterations < high.iterations
    capped = solve_lcp(M, q, Settings("cap", 1e-12, max_iter=2))
    assert capped.status is Status.MAX_ITER and capped.iterations == 2
    sor = solve_lcp(M, q, PROFILES["mid"], omega=1.3)
    assert sor.solved and sor.extra["omega"] == 1.3
    warm = solve_lcp(M, q, PROFILES["mid"], warm=np.array(BOTH_ACTIVE.z))
    assert warm.solved and warm.iterations == 0
    clipped = solve_lcp(M, q, Settings("zero", 1e-6, max_iter=0), warm=np.array([-1.0, 1.0]))
    np.testing.assert_array_equal(clipped.z, [0.0, 1.0])


def test_adapter_rejects_unknown_option():
    with pytest.raises(ProblemError, match="unknown PGS option.*relax.*allowed: omega"):
        solve_lcp(np.eye(2), -np.ones(2), PROFILES["mid"], relax=1.2)


# --- 6. caller errors -----------------------------------------------------------------------


@pytest.mark.parametrize("M, q, kw, match", [
    (np.ones((2, 3)), np.ones(2), {}, "M must be a non-empty square"),
    (np.ones(3), np.ones(3), {}, "M must be a non-empty square"),
    (np.zeros((0, 0)), np.zeros(0), {}, "M must be a non-empty square"),
    (np.eye(2), np.ones(3), {}, "q must have length 2"),
    (np.array([[1.0, np.nan], [0.0, 1.0]]), np.ones(2), {}, "M must be finite"),
    (np.eye(2), [1.0, np.inf], {}, "q must be finite"),
    (np.eye(2), np.ones(2), {"omega": 0.0}, r"omega must be .* \(0, 2\)"),
    (np.eye(2), np.ones(2), {"omega": 2.0}, r"omega must be .* \(0, 2\)"),
    (np.eye(2), np.ones(2), {"omega": float("nan")}, "omega"),
    (np.eye(2), np.ones(2), {"omega": "1"}, "omega"),
    (np.eye(2), np.ones(2), {"eps": -1e-3}, "eps must be"),
    (np.eye(2), np.ones(2), {"max_sweeps": -1}, "max_sweeps must be"),
    (np.eye(2), np.ones(2), {"max_sweeps": 2.5}, "max_sweeps must be"),
    (np.eye(2), np.ones(2), {"z0": np.ones(3)}, "z0 must have length 2"),
    (np.eye(2), np.ones(2), {"time_limit": -1.0}, "time_limit"),
    ([["a", "b"], ["c", "d"]], np.ones(2), {}, "M must be real and numeric"),
    (np.eye(2) * 1j, np.ones(2), {}, "M must be real and numeric: complex"),
    (np.eye(2), np.ones(2), {"omega": True}, "omega"),
    (np.eye(2), np.ones(2), {"z0": ["x", 1]}, "z0 must be real"),
])
def test_bad_input_raises_problem_error(M, q, kw, match):
    with pytest.raises(ProblemError, match=match):
        pgs(M, q, **kw)
