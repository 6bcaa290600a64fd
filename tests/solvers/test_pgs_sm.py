"""Tests of projected Gauss–Seidel with subspace minimisation (``pgs-sm``).

Expected answers come from an independent enumeration of the complementary bases
(small LCPs), from Lemke's pivoting (the contact step's LCP, in both of its LCP forms)
and from theory (a symmetric positive definite M has one answer; a PSD one an answer
set, judged by complementarity) -- never from pgs-sm's own output.
"""

from __future__ import annotations

import numpy as np
import pytest
from energy_oracle import assert_step_kkt

from lcpbench.errors import ProblemError
from lcpbench.solvers.base import PROFILES, Status, lcp_residuals
from lcpbench.solvers.enumeration import enumerate_lcp
from lcpbench.solvers.pgs_sm import pgs_sm, solve_lcp
from lcpbench.solvers.runner import solve_lcp as run

HIGH = PROFILES["high"]


def random_spd(rng, n):
    A = rng.normal(size=(n, n))
    return A @ A.T / n + 0.05 * np.eye(n)


@pytest.mark.parametrize("seed", range(12))
def test_matches_enumeration_on_random_spd_lcps(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 9))
    M, q = random_spd(rng, n), rng.normal(size=n)
    (exact,) = enumerate_lcp(M, q)  # M SPD: exactly one answer
    for z0 in (None, rng.uniform(0, 2, n)):  # cold, and any warm start
        sol = solve_lcp(M, q, HIGH, z0)
        assert sol.status is Status.SOLVED, sol.message
        np.testing.assert_allclose(sol.z, exact, atol=1e-10)
        np.testing.assert_allclose(sol.w, M @ sol.z + q, atol=1e-12)


def test_an_ill_conditioned_spd_lcp_is_solved_to_round_off():
    # cond(M) = 1e8, the contact step's order at N = 140: PGS alone would need ~1e8 sweeps
    rng = np.random.default_rng(7)
    Q, _ = np.linalg.qr(rng.normal(size=(8, 8)))
    M = Q @ np.diag(np.logspace(0, 8, 8)) @ Q.T
    q = rng.normal(size=8) * 1e3
    (exact,) = enumerate_lcp(M, q)
    sol = run(M, q, "pgs-sm", "high")  # judged by lcpbench's residuals too
    assert sol.solved, sol.message
    assert np.max(np.abs(sol.w - (M @ exact + q))) <= 1e-8 * np.max(np.abs(q))


def test_psd_lcp_with_an_answer_set_ends_complementary():
    # M = [[1, 1], [1, 1]] (singular), q = (−1, −1): every z >= 0 with z1 + z2 = 1 answers
    M, q = np.array([[1.0, 1.0], [1.0, 1.0]]), np.array([-1.0, -1.0])
    sol = solve_lcp(M, q, HIGH)
    assert sol.solved and abs(sol.z.sum() - 1.0) <= 1e-12
    assert lcp_residuals(M, q, sol.z)["natural"] <= 1e-12


def test_q_nonnegative_gives_zero():
    M = random_spd(np.random.default_rng(1), 5)
    sol = solve_lcp(M, np.linspace(0.0, 2.0, 5), HIGH)
    assert sol.solved and np.all(sol.z == 0.0)


def test_a_nonsymmetric_or_nonpositive_diagonal_m_fails_with_the_reason():
    q = np.array([-1.0, -1.0])
    sol = pgs_sm(np.array([[2.0, 1.0], [0.0, 2.0]]), q)
    assert sol.status is Status.FAILED and "symmetric" in sol.message
    sol = pgs_sm(np.array([[0.0, 1.0], [1.0, 2.0]]), q)
    assert sol.status is Status.FAILED and "M_ii > 0" in sol.message


def test_bad_options_are_one_problem_error_naming_them():
    M, q = np.eye(2), -np.ones(2)
    with pytest.raises(ProblemError, match="k_gs"):
        pgs_sm(M, q, k_gs=0)
    with pytest.raises(ProblemError, match="omega"):
        solve_lcp(M, q, HIGH, omega=1.5)


@pytest.fixture(scope="module")
def contact_step():
    import lcpbench
    from lcpbench.model.compiled_driver import assemble_step

    scene = lcpbench.ActuatorScene(theta=150, height=3.0, links=40)
    res = lcpbench.solve(scene, settings="high", tol=1e-11)
    return assemble_step(scene.chain(), np.asarray(res.alpha))


@pytest.mark.parametrize("form", ["gaps", "gaps+ruiz", "reactions", "reactions+ruiz"])
def test_contact_step_solves_the_steps_kkt_conditions_in_each_lcp_form(contact_step, form):
    """The heights solve the step's QP by its KKT conditions, written out in
    tests/energy_oracle.py (H positive definite: one answer), and the reactions are the
    ones those conditions give at them, R = −(H u + f), to 1e-7 of the largest (the
    LCP forms' round-off, cond · eps ~1e-12 here at N = 40, leaves room)."""
    from lcpbench.model.step_solver import solve_step

    sol = solve_step(contact_step, "pgs-sm", "high", formulation=form)
    assert sol.status is Status.SOLVED, sol.message  # judged by the step's own residuals
    R0 = assert_step_kkt(contact_step, sol.u)
    R = sol.forces_upper - sol.forces_lower
    assert np.max(np.abs(R - R0)) <= 1e-7 * np.max(np.abs(R0))


def test_registry_data_give_the_lcp_forms_only():
    from lcpbench.model.formulations import NAMES, accepts, parse_formulation
    from lcpbench.solvers.registry import get_backend

    b = get_backend("pgs-sm")
    assert (b.form, b.storage, b.method, b.warm_start) == ("lcp", "dense", "iterative", True)
    took = {n for n in NAMES if accepts(b, parse_formulation(n))}
    assert took == {"gaps", "gaps+ruiz", "reactions", "reactions+ruiz"}
