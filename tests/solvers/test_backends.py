"""Every installed back-end, through the one interface, on problems with known answers.

The one rule checked everywhere: a back-end may fail (any status but SOLVED),
but an answer marked SOLVED must be right — checked against an independent
answer (hand-derived, enumeration of complementary bases, or the exact active
set confirmed by Lemke on the contact step).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from energy_oracle import assert_step_kkt
from hypothesis import given, settings
from hypothesis import strategies as st
from known_answers import CYCLING_PRONE as ALL_CYCLING_PRONE
from known_answers import LCP_KNOWN, PAPER_SCENE, SICONOS_EXPECTED, SICONOS_LCP_DIR

from lcpbench import ActuatorScene, solve
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.step_solver import solve_step
from lcpbench.problems.lcpfile import read_lcp
from lcpbench.solvers import available_backends, get_backend, solve_lcp
from lcpbench.solvers.base import Settings, Status, lcp_residuals
from lcpbench.solvers.enumeration import enumerate_lcp

BACKENDS = available_backends()
PEER = SICONOS_LCP_DIR  # copy of shared/peer-data
EXPECTED = json.loads(SICONOS_EXPECTED.read_text())
#: Finite, exact methods: they must solve every solvable problem of their class.
EXACT = {"active-set", "lemke", "siconos-lemke"}


def check_solved_is_right(sol, M, q, z_ref=None, atol=1e-5):
    """SOLVED ⇒ z >= 0, w >= 0, z'w = 0 to atol (independently), and z = z_ref if given."""
    if sol.status is not Status.SOLVED:
        return False
    z = np.asarray(sol.z)
    w = M @ z + q
    scale = max(1.0, np.abs(q).max())
    assert z.min() >= -atol * scale
    assert w.min() >= -atol * scale
    assert abs(z @ w) <= atol * scale * max(1.0, np.abs(z).max())
    if z_ref is not None:
        np.testing.assert_allclose(z, z_ref, atol=atol * scale)
    return True


# -- small problems with hand-derived answers (known_answers.LCP_KNOWN) ----------------
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("case", sorted(LCP_KNOWN))
def test_known_answers(backend, case):
    M, q, z = (np.array(x, dtype=float) for x in LCP_KNOWN[case])
    sol = solve_lcp(M, q, backend, "mid")
    solved = check_solved_is_right(sol, M, q, z)
    # a well-conditioned 2x2/3x3 SPD problem: every back-end must solve it, except
    # that at a degenerate solution (z_i = w_i = 0) interior-point methods converge
    # like the square root of their gap, so they may stop short and say so
    if case != "degenerate" or backend in EXACT:
        assert solved, sol.message


@pytest.mark.parametrize("backend", BACKENDS)
def test_random_spd_against_enumeration(backend):
    @settings(max_examples=8, deadline=None, derandomize=True)
    @given(st.integers(1, 6), st.integers(0, 2**32 - 1))
    def run(n, seed):
        rng = np.random.default_rng(seed)
        A = rng.normal(size=(n, n))
        M = A @ A.T + 0.5 * np.eye(n)
        q = rng.normal(size=n)
        (ref,) = enumerate_lcp(M, q)  # SPD: exactly one solution
        sol = solve_lcp(M, q, backend, "mid")
        solved = check_solved_is_right(sol, M, q, ref, atol=1e-4)
        if backend in EXACT:
            assert solved, sol.message

    run()


def _planted_psd(n, seed):
    """Singular PSD M with a planted degenerate solution (many z_i = w_i = 0)."""
    rng = np.random.default_rng(seed)
    B = rng.integers(-2, 3, size=(n, max(1, n // 2))).astype(float)
    M = B @ B.T
    kind = rng.integers(0, 3, size=n)
    z = np.where(kind == 1, rng.integers(1, 3, size=n), 0).astype(float)
    w = np.where(kind == 2, rng.integers(1, 3, size=n), 0).astype(float)
    return M, w - M @ z, w


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_degenerate_psd(backend, seed):
    # symmetric PSD: w is the same at every solution (theory), so w == w*
    M, q, w_star = _planted_psd(6, seed)
    sol = solve_lcp(M, q, backend, "mid")
    if check_solved_is_right(sol, M, q, atol=1e-4):
        np.testing.assert_allclose(M @ sol.z + q, w_star, atol=1e-3)


# Degenerate non-symmetric problems on which Lemke with a naive tie-break cycles
# (known_answers.CYCLING_PRONE; these two of them).
CYCLING_PRONE = [ALL_CYCLING_PRONE[0], ALL_CYCLING_PRONE[2]]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("k", range(len(CYCLING_PRONE)))
def test_cycling_prone(backend, k):
    M, q = (np.array(x, dtype=float) for x in CYCLING_PRONE[k])
    sol = solve_lcp(M, q, backend, "mid")
    solved = check_solved_is_right(sol, M, q, atol=1e-6)
    b = get_backend(backend)
    if b.form == "qp" and not b.fallback:
        # non-symmetric M: the QP form does not apply, and the back-end says so
        assert sol.status is Status.FAILED and "symmetric" in sol.message
    if backend in ("lemke", "active-set"):  # the active set falls back to Lemke here
        assert solved, sol.message


# -- the N = 140 contact step -----------------------------------------------------------
@pytest.fixture(scope="module")
def contact_step():
    scene = ActuatorScene(**PAPER_SCENE)
    result = solve(scene, tol=1e-10)
    step = assemble_step(result.scene.chain(), result.alpha)
    ref = solve_step(step, "active-set", "high")
    rows = np.isfinite(step.upper)
    f_ref = ref.forces_net[rows].sum()
    # the reference solves the step: its KKT conditions, written out in
    # tests/energy_oracle.py (H positive definite: the answer is unique)
    assert ref.solved
    assert_step_kkt(step, ref.u)
    return step, ref, rows, f_ref


@pytest.mark.parametrize("scaled", [True, False], ids=["scaled", "raw"])
@pytest.mark.parametrize("backend", BACKENDS)
def test_contact_step(contact_step, backend, scaled):
    step, ref, rows, f_ref = contact_step
    b = get_backend(backend)
    # first-order LCP methods cannot converge on cond(K) ~ 1e8 in a test's time: give
    # them a small budget; they must then say so by status
    budget = 300 if (b.form == "lcp" and b.method == "iterative") else None
    sol = solve_step(step, backend, Settings("high", 1e-9, max_iter=budget), scaled=scaled)
    if backend in EXACT:
        assert sol.status is Status.SOLVED, sol.message
    if sol.status is Status.SOLVED:
        err = abs(sol.forces_net[rows].sum() - f_ref) / f_ref
        assert err <= 1e-6, f"{backend}: total force off by {err:.1e}, marked solved"
        assert sol.residuals["min_gap"] >= -1e-9
        np.testing.assert_allclose(sol.u, ref.u, atol=1e-6 * step.length_scale)


# -- the Siconos collection ----------------------------------------------------------------
PROBLEMS = sorted(p.name for p in PEER.glob("*.dat"))
#: Outcomes the expected-outcome table may list, alone or joined by "-or-".
OUTCOMES = {"solved", "unsolved", "max-iter"}


@pytest.mark.skipif(not PEER.is_dir(), reason="peer data not present")
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("problem", PROBLEMS)
def test_siconos_collection(problem, backend):
    prob = read_lcp(PEER / problem)
    M, q = prob.M, prob.q
    sol = solve_lcp(M, q, backend, EXPECTED["settings"])
    # never a wrong answer marked solved, whatever the back-end: at "default" SOLVED
    # promises a residual of 1e-5 (ten times the default request of 1e-6)
    check_solved_is_right(sol, M, q, atol=1e-5)
    if sol.status is Status.SOLVED:  # lcpbench's own residuals agree with the verdict
        assert lcp_residuals(M, q, sol.z)["natural"] <= 1e-5 * max(1.0, np.abs(q).max())
    expected = EXPECTED["outcomes"].get(problem, {}).get(backend)
    if expected is None:  # a back-end the table does not know (a plug-in): invariant only
        return
    allowed = set(expected.split("-or-"))
    assert allowed <= OUTCOMES, f"unknown outcome {expected!r} in the table"
    got = {"solved"} if sol.status is Status.SOLVED else {"unsolved"}
    if sol.status is Status.MAX_ITER:
        got.add("max-iter")
    assert got & allowed, (f"{backend} on {problem}: {sol.status.value} ({sol.message}); "
                           f"expected {expected}")
    if "-or-" in expected:  # a path-dependent outcome must say why in the table
        assert EXPECTED["why"].get(f"{Path(problem).stem} / {backend}")


def test_a_step_whose_residuals_cannot_be_computed_is_failed_not_raised(monkeypatch):
    # solve_step never raises on solver trouble: where lcpbench's own residuals need a
    # solve that fails (H not positive definite: a chain with links past the vertical
    # can give one), the step is FAILED with the reason, so the driver stops with it.
    # (The default back-end's compiled step computes them in its kernel, where a face
    # that is not positive definite is a bail to this numpy route: hence lemke here.)
    import lcpbench.model.step_solver as step_solver
    from lcpbench.solvers.base import Status

    def broken(step, u):
        raise np.linalg.LinAlgError("66-th leading minor not positive definite")

    monkeypatch.setattr(step_solver, "step_residuals", broken)
    step = assemble_step(ActuatorScene(150, 3.0, links=40).chain(),
                         ActuatorScene(150, 3.0, links=40).chain().rest_alpha)
    sol = solve_step(step, "lemke")
    assert sol.status is Status.FAILED
    assert "residuals could not be computed" in sol.message
