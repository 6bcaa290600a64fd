"""Large N (issue 19, item 3): the increment formulation on the tridiagonal factor.

Expected values come from independent methods (dense solves of the same face, the
step's KKT conditions and the equilibrium by central differences of the exact energy,
tests/energy_oracle.py,
the existing height formulation with the banded Cholesky at moderate N) or
from theory (second-order convergence of the force in N).
"""

from __future__ import annotations

import numpy as np
import pytest
from energy_oracle import assert_equilibrium, assert_step_kkt

from lcpbench.linalg.saddle import TridiagonalFactor
from lcpbench.model import step_solver
from lcpbench.model.chain import heights
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.compiled_driver import run as run_driver
from lcpbench.model.large_driver import run_large
from lcpbench.model.large_n import increments_at, layout_fits, trial_of
from lcpbench.model.outer import feasible_start
from lcpbench.model.step_solver import make_step_solver, solve_step
from lcpbench.problems.scenes import ActuatorScene
from lcpbench.solvers.base import Status


def _step(links=60, theta=150.0, height=3.0, shrink=0.9):
    chain = ActuatorScene(theta, height, links=links).chain()
    return chain, assemble_step(chain, chain.rest_alpha * shrink)


@pytest.mark.parametrize("share", [0.0, 0.1, 0.5, 0.9])
@pytest.mark.parametrize("seed", [0, 1])
def test_face_solve_matches_a_dense_solve_of_the_same_face(share, seed):
    _, step = _step()
    n = step.size
    rng = np.random.default_rng(seed)
    fixed = rng.random(n) < share
    rhs = rng.standard_normal(n)
    H = step.dense_hessian()
    face = H.copy()
    face[fixed, :] = 0.0
    face[:, fixed] = 0.0
    face[fixed, fixed] = 1.0
    x = TridiagonalFactor(step.coef, step.stiffness).face_solve(fixed, rhs)
    expected = np.linalg.solve(face, rhs)
    assert np.max(np.abs(x - expected)) <= 1e-8 * np.max(np.abs(expected))


def test_the_factored_product_is_H():
    _, step = _step()
    x = np.random.default_rng(3).standard_normal(step.size)
    Hx = step.dense_hessian() @ x
    got = TridiagonalFactor(step.coef, step.stiffness).matvec(x)
    assert np.allclose(got, Hx, rtol=1e-12, atol=1e-12 * np.max(np.abs(Hx)))


def test_the_step_in_increments_solves_the_step_in_heights():
    """The step in increments (d = u − u₀) is the step's QP moved to u₀: u₀ + d must
    solve the step in heights. Oracle: that step's KKT conditions written out on its
    numbers (tests/energy_oracle.py: feasible, stationary off the walls, the walls
    pushing), and complementarity of the answer's reactions with its gaps."""
    chain = ActuatorScene(150, 3.0, links=400).chain()
    _, alpha = feasible_start(chain, chain.rest_alpha)
    step = assemble_step(chain, alpha)
    inc = increments_at(chain, alpha)
    assert np.array_equal(inc.heights, step.origin)  # u₀: the heights at α
    b = solve_step(inc, "active-set")
    assert b.status is Status.SOLVED and b.active_upper.any()
    u = b.u + inc.heights
    R = assert_step_kkt(step, u, rtol=1e-8)  # the step's KKT conditions
    gap = step.upper - u
    scale = np.max(np.abs(R))
    assert np.all(np.abs(R[~b.active_upper]) <= 1e-8 * scale)  # no force off the wall
    assert np.all(np.abs(gap[b.active_upper]) <= 1e-9 * chain.length)  # on it: no gap


def test_the_trial_moves_the_heights_by_the_increments():
    chain, step = _step(links=50)
    du = 1e-3 * np.sin(np.linspace(0, np.pi, step.size))
    alpha, _ = trial_of(chain, step.alpha, du)(1.0)
    assert alpha is not None
    assert np.allclose(heights(chain, alpha), heights(chain, step.alpha) + du, atol=1e-12)


@pytest.mark.parametrize("theta,height", [(150, 3.0), (90, 2.0), (180, 1.0)])
def test_large_path_agrees_with_the_height_path_at_moderate_n(theta, height):
    scene = ActuatorScene(theta, height, links=300)
    chain = scene.chain()
    assert layout_fits(chain)
    solver = make_step_solver("active-set")
    ref = run_driver(chain, solver, tol=1e-9)
    big = run_large(chain, solver, tol=1e-9)
    assert ref.converged and big.converged
    F_ref, F_big = float(np.sum(ref.forces_upper)), float(np.sum(big.forces_upper))
    assert abs(F_big - F_ref) <= 1e-7 * max(abs(F_ref), chain.force_scale)
    assert np.max(np.abs(big.alpha - ref.alpha)) <= 1e-7
    assert_equilibrium(scene, big.alpha, big.forces_upper)  # (tests/energy_oracle.py)


def test_force_converges_at_least_at_second_order_in_n():
    """The Hencky chain is a second-order discretisation: the Richardson estimate of the
    order is at least ~2 (measured 3.1 here: where the contact falls between nodes
    moves with N, so the order is not a clean 2 at these N)."""
    import lcpbench

    F = [lcpbench.solve(ActuatorScene(150, 3.0, links=n), tol=1e-10).total_force
         for n in (100, 200, 400)]
    order = np.log2(abs(F[0] - F[1]) / abs(F[1] - F[2]))
    assert order >= 1.7


def test_dense_lcp_form_is_refused_before_allocation(monkeypatch):
    monkeypatch.setattr(step_solver, "MAX_DENSE_FORM_BYTES", 8 * 5 * 50 * 50)
    _, step = _step(links=120)
    sol = solve_step(step, "lemke")
    assert sol.status is Status.FAILED
    assert "too large for a dense LCP form" in sol.message and "n = 119" in sol.message
