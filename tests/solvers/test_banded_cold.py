"""The active set from cold: the dual walk (default) against independent answers.

Every answer must be exact: hand-derived on small problems, enumeration of all
faces (3^n) or of complementary bases (lcpbench.solvers.enumeration) on random
SPD banded problems, the primal active set and Lemke on contact steps, and
complementarity to round-off as a property. Counts of face solves are checked
as regression guards (deterministic); times never are (benchmarks/perf.py).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from energy_oracle import assert_step_kkt
from hypothesis import given, settings
from hypothesis import strategies as st
from known_answers import CONTACT_QP_KNOWN, PAPER_SCENE

from lcpbench import ActuatorScene, solve
from lcpbench.errors import ProblemError
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.compiled_driver import run as run_driver
from lcpbench.model.step_solver import solve_step
from lcpbench.problems.cantilever import CantileverScene
from lcpbench.solvers import banded
from lcpbench.solvers.banded import solve_banded_qp
from lcpbench.solvers.base import Status
from lcpbench.solvers.enumeration import enumerate_lcp
from lcpbench.solvers.runner import solve_lcp

INF = np.inf


class DenseBoxQP:
    """min ½uᵀHu + cᵀu, lower <= u <= upper, in the shape solve_banded_qp reads,
    written here from a dense H (independent of lcpbench's adapters)."""

    def __init__(self, H, c, lower, upper):
        self.H = np.asarray(H, dtype=float)
        self.linear = np.asarray(c, dtype=float)
        self.lower = np.asarray(lower, dtype=float)
        self.upper = np.asarray(upper, dtype=float)
        n = self.linear.size
        rows, cols = np.nonzero(np.tril(self.H))
        b = int(np.max(rows - cols, initial=0))
        self.bands = np.zeros((b + 1, n))
        for k in range(b + 1):
            self.bands[k, : n - k] = np.diagonal(self.H, -k)

    @property
    def size(self):
        return self.linear.size

    def gradient(self, u):
        return self.H @ u + self.linear

    def gradient_scale(self, u):
        return np.abs(self.H) @ np.abs(u) + np.abs(self.linear) + np.finfo(float).tiny

    def unconstrained_minimiser(self):
        return np.linalg.solve(self.H, -self.linear)


def brute_force(qp: DenseBoxQP) -> np.ndarray:
    """The unique KKT point, by trying every face (free / upper / lower per node)."""
    n = qp.size
    H, c, lo, hi = qp.H, qp.linear, qp.lower, qp.upper
    scale = 1.0 + np.abs(c).max() + np.abs(H).max()
    found = []
    for face in itertools.product((0, 1, -1), repeat=n):
        face = np.array(face)
        if np.any((face == 1) & ~np.isfinite(hi)) or np.any((face == -1) & ~np.isfinite(lo)):
            continue
        u = np.where(face == 1, hi, np.where(face == -1, lo, 0.0))
        F = np.flatnonzero(face == 0)
        if F.size:
            fixed = np.flatnonzero(face != 0)
            u[F] = np.linalg.solve(H[np.ix_(F, F)], -c[F] - H[np.ix_(F, fixed)] @ u[fixed])
        g = H @ u + c
        tol = 1e-9 * scale
        ok = (np.all(u <= hi + tol) and np.all(u >= lo - tol)
              and np.all(-g[face == 1] >= -tol) and np.all(g[face == -1] >= -tol))
        if ok:
            found.append(u)
    assert found, "a strictly convex box QP always has a KKT point"
    return found[0]


def random_banded_spd(rng, n, b, gram=False):
    """A random SPD matrix of bandwidth b, signs mixed (not an M-matrix).

    ``gram``: B Bᵀ + δI with B lower bidiagonal-ish of bandwidth b // 2, not
    diagonally dominant and possibly badly conditioned, like the chain's
    (LM)²; otherwise a diagonally dominant one.
    """
    b = min(b, n - 1)
    B = np.zeros((n, n))
    for k in range((b // 2 if gram else b) + 1):
        B += np.diag(rng.normal(size=n - k), -k)
    H = B @ B.T
    if gram:
        return H + np.diag(np.full(n, 10.0 ** rng.uniform(-4, 0)))
    rows, cols = np.indices(H.shape)
    H[np.abs(rows - cols) > b] = 0.0  # back to bandwidth b ...
    H += np.diag(np.abs(H).sum(axis=1) + 0.1)  # ... and made diagonally dominant: SPD
    return H


def assert_kkt(qp, sol, rtol=1e-10):
    """Feasible, reactions >= 0, complementary and stationary, to round-off."""
    u, ru, rl = sol.u, sol.forces_upper, sol.forces_lower
    g = qp.gradient(u)
    force = max(float(np.max(qp.gradient_scale(u))), 1e-300)
    span = 1.0 + np.abs(u).max()
    assert np.all(u <= qp.upper + rtol * span) and np.all(u >= qp.lower - rtol * span)
    assert ru.min() >= 0.0 and rl.min() >= 0.0
    assert np.abs(g + ru - rl).max() <= rtol * force
    gap_up = np.where(np.isfinite(qp.upper), qp.upper - u, 0.0)
    gap_lo = np.where(np.isfinite(qp.lower), u - qp.lower, 0.0)
    assert np.abs(gap_up * ru).max() <= rtol * force * span
    assert np.abs(gap_lo * rl).max() <= rtol * force * span


# -- hand-made problems (known_answers.CONTACT_QP_KNOWN) ---------------------------
HAND = CONTACT_QP_KNOWN


@pytest.mark.parametrize("case", sorted(HAND))
@pytest.mark.parametrize("method", banded.METHODS)
def test_hand_made(case, method):
    H, c, lo, hi, u, ru, rl = HAND[case]
    qp = DenseBoxQP(H, c, lo, hi)
    sol = solve_banded_qp(qp, method=method)
    assert sol.status is Status.SOLVED, sol.message
    np.testing.assert_allclose(sol.u, u, atol=1e-12)
    np.testing.assert_allclose(sol.forces_upper, ru, atol=1e-12)
    np.testing.assert_allclose(sol.forces_lower, rl, atol=1e-12)
    assert_kkt(qp, sol)


def test_symmetric_pair_released_together():
    """Mirror-image walls reach zero reaction together and are released as one."""
    n = 7
    H = (np.diag(np.full(n, 6.0)) + np.diag(np.full(n - 1, -4.0), 1) + np.diag(np.full(n - 1, -4.0), -1)
         + np.diag(np.full(n - 2, 1.0), 2) + np.diag(np.full(n - 2, 1.0), -2))
    H += np.diag(np.full(n, 0.5))
    x = np.linspace(-1, 1, n)
    c = -H @ (1.0 - x**2) * 3.0  # an arch
    qp = DenseBoxQP(H, c, np.full(n, -INF), np.full(n, 1.0))
    sol = solve_banded_qp(qp)
    np.testing.assert_allclose(sol.u, brute_force(qp), atol=1e-10)
    assert np.array_equal(sol.active_upper, sol.active_upper[::-1])  # symmetric answer


# -- random SPD banded problems against enumeration --------------------------------
def random_box_qp(rng, n, b, gram, two_sided):
    """A random box QP: H of bandwidth b (:func:`random_banded_spd`), most nodes with an
    upper wall, some (``two_sided``) with a lower one too."""
    H = random_banded_spd(rng, n, b, gram)
    c = rng.normal(scale=5.0, size=n)
    hi = np.where(rng.random(n) < 0.8, rng.normal(size=n), INF)
    below = np.where(np.isfinite(hi), hi - rng.uniform(0.1, 3.0, size=n), rng.normal(size=n))
    lo = np.where(two_sided & (rng.random(n) < 0.6), below, -INF)
    return DenseBoxQP(H, c, lo, hi)



@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.integers(1, 7), st.integers(1, 3), st.integers(0, 2**32 - 1), st.booleans(),
       st.booleans())
def test_random_banded_against_face_enumeration(n, b, seed, two_sided, gram):
    qp = random_box_qp(np.random.default_rng(seed), n, b, gram, two_sided)
    ref = brute_force(qp)
    for method in banded.METHODS:
        sol = solve_banded_qp(qp, method=method)
        assert sol.status is Status.SOLVED, (method, sol.message)
        np.testing.assert_allclose(sol.u, ref, atol=1e-9 * (1 + np.abs(ref).max()))
        assert_kkt(qp, sol)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.integers(1, 9), st.integers(0, 2**32 - 1))
def test_random_banded_against_lcp_enumeration(n, seed):
    """Upper walls only: the gaps g = h − u solve the LCP (H, −(H h + c))."""
    rng = np.random.default_rng(seed)
    H = random_banded_spd(rng, n, 2)
    hi = rng.normal(size=n)
    c = rng.normal(scale=5.0, size=n)
    qp = DenseBoxQP(H, c, np.full(n, -INF), hi)
    sols = enumerate_lcp(H, -(H @ hi + c))
    assert len(sols) >= 1
    g_ref = sols[0]
    sol = solve_banded_qp(qp)
    assert sol.status is Status.SOLVED, sol.message
    np.testing.assert_allclose(hi - sol.u, g_ref, atol=1e-8 * (1 + np.abs(g_ref).max()))


@settings(max_examples=80, deadline=None, derandomize=True)
@given(st.integers(2, 60), st.integers(0, 2**32 - 1), st.floats(0.0, 1.0), st.booleans())
def test_complementarity_to_round_off(n, seed, reach, gram):
    """Property: whatever the problem, the dual walk's answer is a KKT point to
    round-off, and it is the primal method's answer."""
    rng = np.random.default_rng(seed)
    H = random_banded_spd(rng, n, 2, gram)
    c = rng.normal(scale=10.0, size=n)
    u0 = np.linalg.solve(H, -c)
    hi = np.where(rng.random(n) < 0.9, u0 - reach * np.abs(rng.normal(size=n)) * u0.std(), INF)
    lo = np.where(rng.random(n) < 0.3, np.minimum(hi, u0) - rng.uniform(0, 2, size=n), -INF)
    qp = DenseBoxQP(H, c, lo, hi)
    sol = solve_banded_qp(qp)
    assert sol.status is Status.SOLVED, sol.message
    assert_kkt(qp, sol)
    ref = solve_banded_qp(qp, method="primal")
    np.testing.assert_allclose(sol.u, ref.u, atol=1e-9 * (1 + np.abs(ref.u).max()))


# -- the contact step -----------------------------------------------------------------
@pytest.fixture(scope="module")
def paper_step():
    scene = ActuatorScene(**PAPER_SCENE)
    result = solve(scene, solver="active-set", tol=1e-10)
    return assemble_step(result.scene.chain(), result.alpha)


def test_paper_step_cold(paper_step):
    """The N = 140 step (what `lcpbench export` writes): the same answer as the primal
    method and Lemke, from cold, in a handful of face solves instead of ~220."""
    step = paper_step
    dual = solve_banded_qp(step)
    primal = solve_banded_qp(step, method="primal")
    assert dual.status is Status.SOLVED and primal.status is Status.SOLVED
    assert np.array_equal(dual.active_upper, primal.active_upper)
    np.testing.assert_allclose(dual.u, primal.u, atol=1e-12 * step.length_scale)
    np.testing.assert_allclose(dual.forces_upper, primal.forces_upper,
                               atol=1e-9 * primal.forces_upper.max())
    lemke = solve_step(step, "lemke", "high")
    assert lemke.solved
    np.testing.assert_allclose(dual.u, lemke.u, atol=1e-9 * step.length_scale)
    assert dual.iterations <= 20 < primal.iterations  # 6 and 220 when written


def test_paper_step_warm_start_is_one_solve(paper_step):
    step = paper_step
    cold = solve_banded_qp(step)
    warm = solve_banded_qp(step, start=cold.u, active_upper=cold.active_upper)
    assert warm.status is Status.SOLVED and warm.iterations == 1
    np.testing.assert_allclose(warm.u, cold.u, atol=1e-12 * step.length_scale)
    # a wrong warm set (every reachable node) is repaired, not trusted
    wrong = solve_banded_qp(step, active_upper=np.isfinite(step.upper))
    assert wrong.status is Status.SOLVED
    np.testing.assert_allclose(wrong.u, cold.u, atol=1e-12 * step.length_scale)


@pytest.mark.parametrize("scene", [
    ActuatorScene(theta=150, height=1.0, links=400),
    ActuatorScene(theta=180, height=0.5, links=140, channel=True),
    ActuatorScene(theta=90, height=2.0, links=60, weight=0.02),
    CantileverScene(load=0.01, height=0.1, links=140),
], ids=["N400-h1", "channel", "heavy", "cantilever"])
def test_every_step_of_a_solve_matches_the_primal_method(scene):
    """Along whole nonlinear solves, cold and warm, the dual walk never needs its
    safeguard and agrees with the primal method on every step."""
    seen = []

    def both(step, warm):
        kw = {} if warm is None else {"start": warm.u, "active_upper": warm.active_upper,
                                      "active_lower": warm.active_lower}
        sols = [solve_banded_qp(step, **kw), solve_banded_qp(step)]
        ref = solve_banded_qp(step, method="primal")
        for sol in sols:
            assert sol.status is Status.SOLVED and "took over" not in sol.message
            scale = 1.0 + np.abs(ref.u).max()
            np.testing.assert_allclose(sol.u, ref.u, atol=1e-10 * scale)
            assert_step_kkt(step, sol.u)  # the step's KKT conditions, written out
        seen.append(sols[1].iterations)
        return sols[0]

    out = run_driver(scene.chain(), both, tol=1e-8)
    assert out.converged and seen


# -- the safeguard --------------------------------------------------------------------
def test_safeguard_takes_over_from_a_stuck_walk(paper_step, monkeypatch):
    """If the dual walk stops short (here: forced to, with every wall held), the
    primal method finishes from there and the answer is still exact."""
    step = paper_step
    exact = solve_banded_qp(step)

    def stuck(step, warm_up, warm_lo, max_iter, reach=0):
        held = np.isfinite(step.upper)
        return step.unconstrained_minimiser(), None, held, np.zeros_like(held), 3, "stuck"

    monkeypatch.setattr(banded, "_dual", stuck)
    sol = solve_banded_qp(step)
    assert sol.status is Status.SOLVED
    assert "stuck" in sol.message and "primal active set took over" in sol.message
    assert sol.iterations > 3
    np.testing.assert_allclose(sol.u, exact.u, atol=1e-12 * step.length_scale)


def test_iteration_limit_is_a_status(paper_step):
    sol = solve_banded_qp(paper_step, max_iter=2)
    assert sol.status is Status.MAX_ITER


def test_unknown_method():
    with pytest.raises(ProblemError, match="method"):
        solve_banded_qp(DenseBoxQP([[1.0]], [0.0], [-INF], [1.0]), method="simplex")


def test_empty_box_is_not_solved():
    qp = DenseBoxQP([[1.0]], [0.0], [1.0], [0.0])
    assert solve_banded_qp(qp).status is not Status.SOLVED


def test_a_wall_crossed_by_the_refinement_is_walked_on():
    """The walk decides on unrefined heights; where the refinement at its optimum
    carries a free node through its wall (a grazing contact: the first solve off by
    more than the slack, cond(H) ε |u|), the walk goes on and holds the node. H is the
    squared second difference, cond(H) ~ 1.6e10; its first solve and its refinement
    are computed here as the walk computes them (the banded LDLᵀ of linalg.ldl_kernel,
    H u + c by the walk's matvec_row), and the refinement moves a node by far more than
    the slack (round-off times cond(H)). A wall half-way between the two is not
    violated before the refinement and is after: the answer holds that node, and is a
    KKT point (the independent check)."""
    from lcpbench.numba_cache import kernel_module

    ldl = kernel_module("lcpbench.linalg.ldl_kernel", "refactor")
    walk = kernel_module("lcpbench.solvers.dual_kernel", "box_qp")
    n = 120
    D2 = np.diff(np.eye(n), 2, axis=0)
    H = D2.T @ D2 + 1e-9 * np.eye(n)
    c = -H @ np.sin(3 * np.linspace(0, 1, n))
    qp = DenseBoxQP(H, c, np.full(n, -INF), np.full(n, INF))
    fac = np.empty((4, n))
    assert ldl.refactor(fac, qp.bands, np.zeros(n, bool), np.zeros(0), 0, n)
    first = -c.copy()
    ldl.resolve(fac, first)  # the walk's first solve
    fix = np.array([walk.matvec_row(qp.bands, first, j, n, False) for j in range(n)]) + c
    ldl.resolve(fac, fix)  # its refinement (H u + c summed as the walk sums it): u - fix
    i = int(np.argmax(np.abs(fix)))
    slack = 32 * np.finfo(float).eps * (1 + np.abs(first).max())
    assert abs(fix[i]) > 1e3 * slack  # the premise: the refinement moves node i far
    wall = first[i] - 0.5 * fix[i]  # between the first solve and the refined one
    if fix[i] > 0:  # the refinement moves the node down, below a lower wall
        qp.lower[i] = wall
    else:  # up, above an upper wall
        qp.upper[i] = wall
    sol = solve_banded_qp(qp)
    assert sol.status is Status.SOLVED, sol.message
    assert (sol.active_lower | sol.active_upper)[i]  # held where the refinement took it
    assert_kkt(qp, sol)


@pytest.mark.parametrize("seed", range(10))
def test_solve_lcp_active_set_is_the_enumerated_answer(seed):
    """``solve_lcp(M, q, "active-set")`` on a dense symmetric positive definite M: the
    compiled walk with its dense faces (M of full bandwidth; n = 3 has two
    sub-diagonals, the banded faces), against the enumeration of the complementary
    bases; solved by the walk itself, not by its fallback."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 10))
    A = rng.normal(size=(n, n))
    M, q = A @ A.T / n + 0.05 * np.eye(n), rng.normal(size=n)
    (exact,) = enumerate_lcp(M, q)  # M positive definite: one answer
    sol = solve_lcp(M, q, "active-set")
    assert sol.status is Status.SOLVED and sol.extra["backend"] == "active-set", sol.message
    np.testing.assert_allclose(sol.z, exact, atol=1e-10)


def test_solve_lcp_active_set_on_a_large_dense_lcp_is_complementary():
    """n = 150, dense: the answer is complementary to round-off (lcpbench's residuals,
    computed from z alone) and found by the walk itself."""
    rng = np.random.default_rng(11)
    A = rng.normal(size=(150, 150))
    M, q = A @ A.T / 150 + 0.05 * np.eye(150), rng.normal(size=150)
    sol = solve_lcp(M, q, "active-set")
    assert sol.status is Status.SOLVED and sol.extra["backend"] == "active-set", sol.message
    w = M @ sol.z + q
    assert sol.z.min() >= 0.0 and w.min() >= -1e-12 * np.abs(q).max()
    assert np.max(np.abs(sol.z * w)) <= 1e-12 * np.abs(q).max() * max(1.0, sol.z.max())


@settings(max_examples=30, deadline=None, derandomize=True)
@given(st.integers(3, 8), st.integers(0, 2**32 - 1), st.booleans(), st.booleans())
def test_a_qp_with_a_few_sub_diagonals_is_a_kkt_point(b, seed, two_sided, gram):
    """H with 3–8 sub-diagonals and n >= 4 b (the walk's faces: the banded Cholesky
    of the whole face, O(n b²), not the free block's): the answer is a KKT point
    (:func:`assert_kkt`, from H, c and the bounds alone), the walk's own."""
    rng = np.random.default_rng(seed)
    width = 2 * b if gram else b  # (a Gram matrix B Bᵀ doubles B's bandwidth b)
    n = int(rng.integers(4 * width, 12 * width))
    qp = random_box_qp(rng, n, width, gram, two_sided)
    assert 3 <= qp.bands.shape[0] - 1 <= n // 4  # (the few-sub-diagonals faces)
    sol = solve_banded_qp(qp)
    assert sol.status is Status.SOLVED and "primal" not in sol.message, sol.message
    assert_kkt(qp, sol)


def test_an_elastic_step_is_refused_not_solved_as_rigid():
    """The walk and its certificate take rigid walls: an elastic step handed to it
    directly is a ProblemError naming the call that takes it (before, its rigid answer
    was certified: no penetration where the springs give 0.5 mm)."""
    chain = ActuatorScene(theta=150, height=3.0, links=40, wall_stiffness=0.1).chain()
    step = assemble_step(chain, chain.rest_alpha)
    assert step.elastic
    with pytest.raises(ProblemError, match="solve_step"):
        solve_banded_qp(step)
    sol = solve_step(step, "active-set")  # the call that takes it: the springs give way
    assert sol.solved and np.max(sol.u - step.upper) > 0.1
