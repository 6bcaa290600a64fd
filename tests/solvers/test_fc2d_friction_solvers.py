"""The active set and the Tresca fixed point on small 2-D frictional contact problems,
against enumeration of every stick / slide / separate state (an independent oracle) and
against Siconos' fc2d enumeration where it is installed (issue 39, item 3)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from lcpbench.solvers import siconos_bridge
from lcpbench.solvers.base import Settings, Status
from lcpbench.solvers.fc2d_active import solve_fc2d_active
from lcpbench.solvers.fc2d_tresca import solve_fc2d_tresca
from lcpbench.solvers.registry import backends
from lcpbench.solvers.siconos_fc2d import solve_fc2d

TIGHT = Settings("test", 1e-12, driver_tol=1e-9)


def problem(rng, nc):
    """u = W r + q with W symmetric positive definite, some contacts pressed."""
    B = rng.normal(size=(2 * nc, 2 * nc))
    W = B @ B.T / (2 * nc) + 0.1 * np.eye(2 * nc)
    q = rng.normal(size=2 * nc)
    mu = rng.uniform(0.05, 1.0, nc)
    return W, q, mu


def enumerate_answers(W, q, mu, tol=1e-9):
    """Every r that satisfies Signorini–Coulomb, found by trying each contact in each of
    separate, stick, slide with u_t > 0 (r_t = −μ r_n), slide with u_t < 0 (r_t = μ r_n):
    the linear conditions of the states, then the inequalities."""
    nc = mu.size
    found = []
    for states in itertools.product(range(4), repeat=nc):
        A = np.zeros((2 * nc, 2 * nc))
        b = np.zeros(2 * nc)
        for c, s in enumerate(states):
            n, t = 2 * c, 2 * c + 1
            if s == 0:  # r_n = 0, r_t = 0
                A[n, n] = A[t, t] = 1.0
            elif s == 1:  # u_n = 0, u_t = 0
                A[n], A[t] = W[n], W[t]
                b[n], b[t] = -q[n], -q[t]
            else:  # u_n = 0, r_t ± μ r_n = 0
                A[n], b[n] = W[n], -q[n]
                A[t, t], A[t, n] = 1.0, (mu[c] if s == 2 else -mu[c])
        try:
            r = np.linalg.solve(A, b)
        except np.linalg.LinAlgError:
            continue
        u = W @ r + q
        ok = True
        for c, s in enumerate(states):
            rn, rt, un, ut = r[2 * c], r[2 * c + 1], u[2 * c], u[2 * c + 1]
            ok &= un >= -tol and rn >= -tol and abs(rt) <= mu[c] * rn + tol
            ok &= not (s == 2 and ut < -tol) and not (s == 3 and ut > tol)
        if ok and not any(np.allclose(r, f, rtol=0, atol=1e-9) for f in found):
            found.append(r)
    return found


def matches(r, answers, atol=1e-7):
    return any(np.allclose(r, a, rtol=0, atol=atol * max(1.0, np.abs(a).max()))
               for a in answers)


def small_problems(count=60, seed=3):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield problem(rng, int(rng.integers(1, 5)))


def test_active_set_answers_are_coulomb_answers_found_by_enumeration():
    solved = unique = 0
    for W, q, mu in small_problems():
        answers = enumerate_answers(W, q, mu)
        assert answers  # (a positive definite W always has one)
        sol = solve_fc2d_active(W, q, mu)
        unique += len(answers) == 1
        if sol.status is Status.SOLVED:
            solved += 1
            assert matches(sol.r, answers), (sol.r, answers)
    assert solved >= 0.9 * unique  # it answers (nearly) every problem with one answer


@pytest.mark.parametrize("name", ["proxsuite-dense", "qpsolvers-piqp", "osqp"])
def test_tresca_fixed_point_answers_are_coulomb_answers(name):
    b = backends()[name]
    if not b.available():
        pytest.skip(f"{name} not installed")
    mod = b.load()
    solved = 0
    for W, q, mu in small_problems(30, seed=5):
        sol = solve_fc2d_tresca(W, q, mu, mod.solve_qp, TIGHT, options=b.options)
        if sol.status is Status.SOLVED:
            solved += 1
            assert matches(sol.r, enumerate_answers(W, q, mu), atol=1e-6)
    assert solved > 0


def test_tresca_without_friction_is_one_qp_and_the_frictionless_answer():
    """μ = 0: the bounds stay 0, T = 0, and N is the frictionless LCP's answer."""
    b = backends()["proxsuite-dense"]
    if not b.available():
        pytest.skip("proxsuite not installed")
    rng = np.random.default_rng(8)
    W, q, _ = problem(rng, 3)
    mu = np.zeros(3)
    sol = solve_fc2d_tresca(W, q, mu, b.load().solve_qp, TIGHT, options=b.options)
    assert sol.status is Status.SOLVED and sol.iterations == 1
    assert np.abs(sol.r[1::2]).max() <= 1e-12
    assert matches(sol.r, enumerate_answers(W, q, mu), atol=1e-8)


def test_a_limit_too_small_is_never_solved():
    """One Tresca problem from b = 0 is the frictionless answer: not Coulomb's where a
    contact presses and its free slip is not 0, so not SOLVED."""
    b = backends()["proxsuite-dense"]
    if not b.available():
        pytest.skip("proxsuite not installed")
    W = np.array([[1.0, 0.3], [0.3, 1.0]])
    q = np.array([-1.0, 0.5])  # pressed, and sliding forward when free
    sol = solve_fc2d_tresca(W, q, np.array([0.5]), b.load().solve_qp, TIGHT,
                            options=b.options, max_fixed=1)
    assert sol.status is not Status.SOLVED
    full = solve_fc2d_tresca(W, q, np.array([0.5]), b.load().solve_qp, TIGHT,
                             options=b.options)
    assert full.status is Status.SOLVED
    # by hand: sliding forward, r_t = −μ r_n; u_n = 0 gives (1 − 0.15) r_n = 1
    rn = 1.0 / (1.0 - 0.3 * 0.5)
    np.testing.assert_allclose(full.r, [rn, -0.5 * rn], atol=1e-8)
    assert (W @ full.r + q)[1] > 0  # it does slide forward


def test_active_set_max_iter_is_not_solved():
    rng = np.random.default_rng(11)
    W, q, mu = problem(rng, 4)
    q[0::2] = -np.abs(q[0::2])  # every contact pressed
    sol = solve_fc2d_active(W, q, mu, states=np.zeros(4, np.int64), max_iter=1)
    assert sol.status is Status.MAX_ITER and "no consistent states" in sol.message


@pytest.mark.skipif(not siconos_bridge.available(), reason="siconos not installed")
def test_active_set_agrees_with_siconos_fc2d_enumeration():
    agreed = 0
    for W, q, mu in small_problems(20, seed=13):
        ours = solve_fc2d_active(W, q, mu)
        peer = solve_fc2d(W, q, mu, method="enum")
        if ours.solved and peer.solved and len(enumerate_answers(W, q, mu)) == 1:
            np.testing.assert_allclose(ours.r, peer.r, rtol=0,
                                       atol=1e-7 * max(1.0, np.abs(peer.r).max()))
            agreed += 1
    assert agreed > 0
