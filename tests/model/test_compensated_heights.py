"""Heights summed with compensation, and the judge's completion at round-off (issue 19, item 3).

At N = 10⁵ and tol 1e-9 the judge rejected the answer twice over, on round-off:
- the step's closure error y_N, a plain running sum of a sin α (round-off
  ~√N ε max|y| ≈ 10⁻¹³ mm), was put on the last link, bending it by
  y_N / (a cos α) ≈ 10⁻¹⁰ rad: k = EI/a times that is a torque 10 % off at the
  last joint (relative torque residual 4.7·10⁻⁶ against 10⁻⁶);
- re-solving the nodes with no wall row with the ends of each run held turned
  residuals of 10⁻¹¹ N into ±4·10⁻⁸ N on the run's end nodes, free nodes then
  reported as a wall pulling (the judge allows 5·10⁻⁹ N at tol 1e-9).

Expected values come from math.fsum (correctly rounded sums), the mechanics of
a chain in equilibrium (every joint's torque balanced), and the round-off of
the factored gradient (ROUNDOFF_ULPS ε of its terms).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lcpbench import ActuatorScene, solve
from lcpbench.model import large_n
from lcpbench.model.chain import compensated_heights
from lcpbench.model.judge import EPS, ROUNDOFF_ULPS
from lcpbench.model.result import certify
from lcpbench.model.step import assemble_step
from lcpbench.model.step_solver import solve_step

N = 100_000


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_compensated_heights_are_the_correctly_rounded_prefix_sums(seed):
    rng = np.random.default_rng(seed)
    n = 3000
    # a chain's Δy: slowly varying, both signs, a few orders of magnitude
    dy = 3e-4 * np.sin(np.linspace(1.3, -1.3, n)) * (1 + 1e-3 * rng.standard_normal(n))
    got = compensated_heights(dy)
    exact = np.array([math.fsum(dy[: i + 1]) for i in range(n)])  # correctly rounded
    plain = np.cumsum(dy)
    # Neumaier: |y − s| <= ε|s| + O(n ε²) Σ|Δy|; the plain sum carries ~√n ε max|y|
    allowed = EPS * np.abs(exact) + 4 * n * EPS**2 * np.sum(np.abs(dy))
    assert np.all(np.abs(got - exact) <= allowed)
    assert np.max(np.abs(plain - exact)) > np.max(np.abs(got - exact))  # it does something


def test_the_step_closes_the_chain_with_the_exact_closure_error():
    chain = ActuatorScene(150.0, 3.0, links=2000).chain()
    alpha = chain.rest_alpha * 0.97  # not closed: y_N of the order of the heights
    step = assemble_step(chain, alpha)
    y_N = math.fsum(chain.link_length * np.sin(alpha))
    shift = step.alpha0[-1] - alpha[-1]  # −y_N / (a cos α_N)
    expected = -y_N / (chain.link_length * math.cos(alpha[-1]))
    assert abs(shift - expected) <= 4 * EPS * (abs(expected) + abs(alpha[-1]))


@pytest.fixture(scope="module")
def tight():
    res = solve(ActuatorScene(150.0, 3.0, links=N), tol=1e-9)
    assert res.extra["engine"].startswith("numpy (large N")  # the increments path
    return res


def test_n_1e5_at_tol_1e9_is_accepted(tight):
    assert tight.converged, tight.reason


def test_every_joint_torque_balances_to_round_off_at_n_1e5(tight):
    # statics: k(φ − φ*) equals the moment of the forces at every joint; the last joint
    # was 10 % off before (4.7e-6 of the largest spring torque), the others ~1e-10
    chain = tight.scene.chain()
    cert = certify(chain, tight.alpha, tight.forces, np.zeros_like(tight.forces))
    assert cert.relative_torque_residual <= 1e-8
    res = np.abs(cert.torque_residual)
    assert res[-1] <= 10 * np.median(res) + 1e-12  # the last joint is not an outlier


def test_a_free_nodes_reaction_is_the_gradients_round_off_at_n_1e5(tight):
    # the step at the answer, solved by the default back-end: every node off the walls
    # carries a net force within the round-off of the factored gradient there
    chain = tight.scene.chain()
    step = large_n.increments_at(chain, tight.alpha)
    sol = solve_step(step, "active-set")
    assert sol.solved, sol.message
    off = ~(sol.active_upper | sol.active_lower)
    floor = ROUNDOFF_ULPS * EPS * step.gradient_scale(sol.u)  # u: the increments
    R = sol.forces_net
    assert np.all(np.abs(R[off]) <= floor[off])
    # and the nodes with no wall row end runs next to free wall-row nodes: both sides
    rows = np.isfinite(step.upper) | np.isfinite(step.lower)
    ends = np.flatnonzero(np.diff(rows.astype(int)) != 0)
    assert ends.size >= 2
    for i in ends:
        assert abs(R[i]) <= floor[i] and abs(R[i + 1]) <= floor[i + 1]
