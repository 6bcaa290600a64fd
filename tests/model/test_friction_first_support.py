"""A frictional step with no last answer to start from (issue 39, target 5): the
frictionless contacts' active set (solvers/pivoting_kernel.py: symmetric_active_set), the
singleton presolve of the pivoting's linear solves (singleton_solve) and the stick/slide
guesses of model/friction_step.py (frictionless_contacts, then first_support_from, as the
default frictional solver calls them: model/friction_lemke.py), against independent
expectations:
enumeration of every support, numpy's dense solve, Coulomb's law contact by contact and
the μ = 0 limit."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from lcpbench.numba_cache import kernel_module

# (through the kernels' cache, as the library loads them: tests/model/test_kernel_cache.py)
_step = kernel_module("lcpbench.model.friction_step", "delassus_form")
frictional_lcp = _step.frictional_lcp
pk = kernel_module("lcpbench.solvers.pivoting_kernel", "support_pivots")


def first_support(M, q, pair, slide, normal_changes, max_changes, feas, piv, rcond):
    """The guesses as :meth:`lcpbench.model.friction_lemke.StepLemke.first_guess` takes
    them: the frictionless contacts, then the stick or slide guess and the pivoting from
    it; (z, w, support, end, solves), the normal LCP's end where it did not end DONE."""
    N, end, solves = _step.frictionless_contacts(M, q, pair.size, normal_changes, feas, piv)
    if end != pk.DONE:
        return np.zeros(q.size), q.copy(), np.zeros(q.size, np.bool_), end, solves
    z, w, S, end, more = _step.first_support_from(M, q, pair, N, slide, normal_changes,
                                                  max_changes, feas, piv, rcond)
    return z, w, S, end, solves + more

FEAS, PIV, RCOND = 1e-10, 1e-13, 1e-12


def enumerate_lcp(M, q, tol=1e-9):
    """Every solution of the LCP, found by trying each support S: z_S = −M_SS⁻¹ q_S."""
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


def contact_problem(rng, nc):
    """The Delassus form (g, s) = (g_f, s_f) + W (N, T) of nc contacts, W symmetric
    positive definite in the order (N…, T…), every contact pressed by the free motion."""
    B = rng.normal(size=(2 * nc, 2 * nc))
    W = B @ B.T / (2 * nc) + 0.1 * np.eye(2 * nc)
    g_f = -np.abs(rng.normal(size=nc))
    s_f = rng.normal(size=nc)
    return W, g_f, s_f


def coulomb_holds(W, g_f, s_f, mu, N, T, tol=1e-8):
    """Signorini–Coulomb contact by contact, on (N, T) and the gaps and slips they make:
    N >= 0 ⟂ g >= 0; |T| <= μN; a contact that slips is at its cone, T against the slip."""
    nc = N.size
    u = W @ np.concatenate([N, T]) + np.concatenate([g_f, s_f])
    g, s = u[:nc], u[nc:]
    ok = np.all(N >= -tol) and np.all(g >= -tol) and np.all(np.abs(N * g) <= tol)
    ok &= np.all(np.abs(T) <= mu * N + tol)
    slips = np.abs(s) > tol
    ok &= np.allclose(np.abs(T[slips]), (mu * N)[slips], rtol=0, atol=tol)
    return bool(ok and np.all(T[slips] * s[slips] <= tol))


@pytest.mark.parametrize("seed", range(10))
def test_symmetric_active_set_is_the_enumerated_answer(seed):
    """A symmetric positive definite LCP has one solution: the active set finds the one
    enumeration finds, and its last w is M z + q."""
    rng = np.random.default_rng(seed)
    n = 7
    B = rng.normal(size=(n, n))
    M, q = B @ B.T / n + 0.05 * np.eye(n), rng.normal(size=n)
    (z_star,) = enumerate_lcp(M, q)
    z, w, end, solves = pk.symmetric_active_set(M, q, 100, FEAS, PIV)
    assert end == pk.DONE and solves >= 1
    np.testing.assert_allclose(z, z_star, rtol=0, atol=1e-10)
    np.testing.assert_allclose(w, np.maximum(M @ z_star + q, 0.0), rtol=0, atol=1e-10)


def test_symmetric_active_set_says_when_its_budget_ends():
    rng = np.random.default_rng(1)
    n = 8
    B = rng.normal(size=(n, n))
    M, q = B @ B.T + np.eye(n), -np.ones(n) - rng.random(n)  # every unknown > 0
    assert pk.symmetric_active_set(M, q, 2, FEAS, PIV)[2] == pk.MAX_ITER


@pytest.mark.parametrize("seed", range(6))
def test_singleton_solve_is_numpys_solve_on_a_nonsingular_matrix(seed):
    """Singleton rows and columns (the frictional step's pairs without a normal force: a
    cone row with one −1, a λ column with one 1) eliminated first: the same x as a dense
    solve."""
    rng = np.random.default_rng(seed)
    k = 9
    A = rng.normal(size=(k, k)) + 3 * np.eye(k)
    A[2, :] = 0.0
    A[2, 5] = -1.0  # a singleton row
    A[:, 7] = 0.0
    A[4, 7] = 1.0  # a singleton column
    b = rng.normal(size=k)
    x, ok = pk.singleton_solve(A.copy(), b.copy(), PIV, RCOND)
    assert ok
    np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-10, atol=1e-12)


def test_singleton_solve_on_a_consistent_singular_matrix():
    """A run of sticking nodes (two equal rows and columns) beside singletons: x solves
    A x = b, the run's load split equally (the least norm of what is left)."""
    A = np.array([[2.0, 2.0, 0.0, 1.0], [2.0, 2.0, 0.0, 1.0],
                  [0.0, 0.0, -1.0, 0.0], [0.0, 0.0, 0.0, 4.0]])
    b = np.array([-2.0, -2.0, 0.0, 0.0])
    x, ok = pk.singleton_solve(A.copy(), b.copy(), PIV, RCOND)
    assert ok
    np.testing.assert_allclose(A @ x, b, rtol=0, atol=1e-12)
    np.testing.assert_allclose(x, [-0.5, -0.5, 0.0, 0.0], rtol=0, atol=1e-12)
    assert not pk.singleton_solve(A.copy(), b.copy(), PIV, 0.0)[1]  # no least squares


@pytest.mark.parametrize("slide", [False, True], ids=["stick", "slide"])
@pytest.mark.parametrize("seed", range(12))
def test_first_support_answers_are_enumerated_and_obey_coulomb(seed, slide):
    """On small Stewart–Trinkle LCPs (2 contacts: 8 unknowns, every support enumerated), an
    answer the guesses end DONE is one of the LCP's solutions and obeys Signorini–Coulomb
    contact by contact; and one of the two guesses ends DONE on most of them."""
    rng = np.random.default_rng(300 + seed)
    nc = 2
    W, g_f, s_f = contact_problem(rng, nc)
    mu = rng.uniform(0.05, 1.0, nc)
    M, q = frictional_lcp(W, g_f, s_f, mu, np.arange(nc))
    answers = enumerate_lcp(M, q)
    assert answers
    z, w, S, end, _ = first_support(M, q, np.arange(nc), slide, 50, 50, FEAS, PIV, RCOND)
    if end != pk.DONE:
        return  # (no finiteness result: the step then goes to Lemke)
    assert any(np.allclose(z, a, rtol=0, atol=1e-8) for a in answers)
    N, T = z[:nc], z[nc:2 * nc] - z[2 * nc:3 * nc]
    assert coulomb_holds(W, g_f, s_f, mu, N, T)


def test_first_support_solves_most_small_steps():
    """Over 40 random 3-contact steps, stick then slide: at least 35 end DONE, each an
    answer by Coulomb's law (the rest go to Lemke)."""
    rng = np.random.default_rng(39)
    done = 0
    for _ in range(40):
        nc = 3
        W, g_f, s_f = contact_problem(rng, nc)
        mu = rng.uniform(0.05, 1.0, nc)
        M, q = frictional_lcp(W, g_f, s_f, mu, np.arange(nc))
        for slide in (False, True):
            z, w, S, end, _ = first_support(M, q, np.arange(nc), slide, 50, 20, FEAS, PIV,
                                            RCOND)
            if end == pk.DONE:
                N, T = z[:nc], z[nc:2 * nc] - z[2 * nc:3 * nc]
                assert coulomb_holds(W, g_f, s_f, mu, N, T)
                done += 1
                break
    assert done >= 35


@pytest.mark.parametrize("seed", range(6))
def test_mu_zero_is_the_frictionless_answer(seed):
    """μ = 0: the stick guess's N is the frictionless LCP's (0 <= N ⟂ W_nn N + g >= 0,
    one answer, by enumeration), with T = 0 (the slips are free)."""
    rng = np.random.default_rng(500 + seed)
    nc = 3
    W, g_f, s_f = contact_problem(rng, nc)
    M, q = frictional_lcp(W, g_f, s_f, np.zeros(nc), np.arange(nc))
    (N_star,) = enumerate_lcp(W[:nc, :nc], g_f)
    z, w, S, end, _ = first_support(M, q, np.arange(nc), False, 50, 20, FEAS, PIV, RCOND)
    assert end == pk.DONE
    np.testing.assert_allclose(z[:nc], N_star, rtol=0, atol=1e-10)
    np.testing.assert_allclose(z[nc:3 * nc], 0.0, rtol=0, atol=1e-12)
