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

from lcpbench import ActuatorScene, CantileverScene, solve
from lcpbench.model import compiled, large_n
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.finish import finish
from lcpbench.model.judge import force_tol
from lcpbench.model.kernel_call import kernel_args
from lcpbench.model.large_driver import run_large
from lcpbench.model.result import certify
from lcpbench.model.step_solver import _judge, make_step_solver, solve_step
from lcpbench.numba_cache import jit_module
from lcpbench.solvers.base import Status
from lcpbench.solvers.registry import get_settings
from lcpbench.thresholds import EPS, ROUNDOFF_ULPS

N = 100_000


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_steps_heights_are_the_correctly_rounded_prefix_sums(seed):
    """The heights u₀ of a step's linearisation point, summed with compensation
    (chain_kernel.add_compensated), against the correctly rounded sums of a sin α."""
    rng = np.random.default_rng(seed)
    n = 3000
    chain = ActuatorScene(150.0, 3.0, links=n).chain()
    # a chain's Δy: slowly varying, both signs, a few orders of magnitude
    alpha = chain.rest_alpha * (1 + 1e-3 * rng.standard_normal(n))
    got = assemble_step(chain, alpha).origin  # the heights of free nodes 1 … N − 1
    dy = chain.link_length * np.sin(alpha)
    exact = np.array([math.fsum(dy[: i + 1]) for i in range(n - 1)])  # correctly rounded
    plain = np.cumsum(dy)[: n - 1]
    # Neumaier: |y − s| <= ε|s| + O(n ε²) Σ|Δy|; the plain sum carries ~√n ε max|y|
    allowed = EPS * np.abs(exact) + 4 * n * EPS**2 * np.sum(np.abs(dy))
    assert np.all(np.abs(got - exact) <= allowed)
    assert np.max(np.abs(plain - exact)) > np.max(np.abs(got - exact))  # it does something


def _bits(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a.shape == b.shape and np.array_equal(a.view(np.int64), b.view(np.int64))


@pytest.mark.parametrize("scene", [ActuatorScene(150.0, 3.0, links=50),
                                   ActuatorScene(150.0, 3.0, links=5000),
                                   ActuatorScene(150.0, 3.0, links=60, channel=True),
                                   CantileverScene(links=60)], ids=str)
def test_every_kernel_sums_the_heights_as_the_reference(scene):
    """Route against route: the promise is the same bits in every kernel's prefix sums (the
    correctly rounded sums are the oracle in
    test_the_steps_heights_are_the_correctly_rounded_prefix_sums)."""
    # the step's assembly (compiled_driver.assemble_step, the solve kernel's banded_step)
    # and the judge kernel's and the increments' loops: the same bits
    chain = scene.chain()
    rng = np.random.default_rng(7)
    alpha = chain.rest_alpha * 0.97 + 1e-3 * rng.standard_normal(chain.links)
    ref = assemble_step(chain, alpha)
    _, a, jl, jr, k, rest, _, nodal_load, fs, *_ = kernel_args(chain)
    n = chain.free_nodes.size
    ck = jit_module("lcpbench.model.compiled_kernel")
    got = ck.banded_step(alpha, a, jl, jr, k, rest, fs, n, nodal_load)
    assert _bits(got[4], ref.origin) and _bits(got[5], ref.alpha0) and _bits(got[6], ref.phi_origin)
    jk = jit_module("lcpbench.model.judge_kernel")
    w = np.zeros((jk.ROWS, alpha.size + 2))
    jk.positions(alpha, a, w)  # (judge_checks.positions, as the judge kernel has it)
    jk._step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, w, np.empty((3, n)))
    assert _bits(w[jk.ORIGIN][:n], ref.origin) and _bits(w[jk.ALPHA0][:alpha.size], ref.alpha0)
    if large_n.takes(chain):
        inc = large_n.increments_at(chain, alpha)
        assert _bits(inc.heights, ref.origin) and _bits(inc.alpha0, ref.alpha0)


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
    assert res.engine.startswith("increments driver (large N")  # the increments path
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
    # the step at the answer, solved by the default back-end: every node with a wall row
    # that is off its wall carries a net force within the round-off of the factored
    # gradient there, the ones next to a run of nodes with no wall row included (the
    # run's own nodes hold by construction: their residual is left where it is small)
    chain = tight.scene.chain()
    step = large_n.increments_at(chain, tight.alpha)
    sol = solve_step(step, "active-set")
    assert sol.solved, sol.message
    rows = np.isfinite(step.upper) | np.isfinite(step.lower)
    off = rows & ~(sol.active_upper | sol.active_lower)
    floor = ROUNDOFF_ULPS * EPS * step.gradient_scale(sol.u)  # u: the increments
    R = sol.forces_net
    assert np.all(np.abs(R[off]) <= floor[off])
    ends = np.flatnonzero(np.diff(rows.astype(int)) != 0)
    next_to_runs = [i if rows[i] else i + 1 for i in ends]
    assert len(next_to_runs) >= 2 and all(off[i] for i in next_to_runs)


def test_n_1e5_agrees_with_a_cold_start(tight, monkeypatch):
    """Route against route: at N = 10⁵ the oracles are out of reach (central differences of
    the energy cost N² = 10¹⁰ operations, SLSQP far more); two independent starts
    reaching one force within τ is the check (the joint torques are checked from statics
    in the tests above)."""
    # another start (the rest shape clipped to the walls, no nested start): 6 outer steps
    # and a different contact search; the two certified forces within tau
    monkeypatch.setattr(compiled, "_coarse_solve", lambda *a, **k: None)
    cold = solve(ActuatorScene(150.0, 3.0, links=N), tol=1e-9)
    assert cold.converged, cold.reason
    assert cold.outer_iterations > tight.outer_iterations  # it did take another path
    F0 = tight.judgement.force_unit
    assert abs(cold.total_force - tight.total_force) / F0 <= force_tol(1e-9)


def test_a_back_end_off_by_just_under_the_floor_is_not_certified_wrong():
    """Route against route: the honest solve at N = 10⁴ is the expectation (central
    differences of the energy cost ~20 s there); what is tested is the judge's refusal
    of a planted defect of 1e-7 F₀ or more, far above the honest answer's error."""
    # an adversary: the built-in back-end's answer moved, on the nodes with no wall row,
    # to a residual of 0.9 of the round-off floor (which the step verdict leaves alone),
    # every step. Its forces move; the one rule: the result is not marked converged
    # unless it is within tau of the certified answer
    scene = ActuatorScene(150.0, 3.0, links=10_000)
    chain = scene.chain()
    honest = solve(scene, tol=1e-9)
    assert honest.converged, honest.reason
    base, moved = make_step_solver("active-set"), []

    def adversary(step, warm):
        sol = base(step, warm)
        if sol.status is Status.SOLVED:
            rows = np.isfinite(step.upper) | np.isfinite(step.lower)
            free = np.flatnonzero(~(sol.active_upper | sol.active_lower))
            r = np.where(~rows, 0.9 * ROUNDOFF_ULPS * EPS * step.gradient_scale(sol.u), 0.0)
            d = np.zeros(step.size)
            d[free] = step.solve_on(free, r[free])
            before = sol.forces_net.copy()
            sol.u = sol.u + d
            _judge(step, sol, get_settings("default"))
            moved.append(float(np.max(np.abs(sol.forces_net - before))))
        return sol

    out = run_large(chain, adversary, tol=1e-9)
    res = finish(scene, chain, out, solver="active-set", method="globalised", tol=1e-9,
                 elapsed=0.0, settings="default", engine="adversary",
                 why=None)
    F0 = honest.judgement.force_unit
    assert moved and max(moved) > force_tol(1e-9) * F0  # the adversary moved the forces
    assert not res.converged or abs(res.total_force - honest.total_force) <= force_tol(1e-9) * F0
