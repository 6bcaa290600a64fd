"""Face solves refactored from the first change (issue 19, target 5: large N).

The restarted factorisation (:mod:`lcpbench.linalg.face_kernel`) is checked
against independent computations: a full factorisation of the same face by
the reference kernel (:mod:`lcpbench.linalg.givens_kernel`), a dense solve of
the same face, and the KKT conditions of the contact step the walk on it solves,
written out on the step's numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from energy_oracle import assert_elastic_step_kkt, assert_step_kkt

from lcpbench.linalg.saddle import TridiagonalFactor
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.large_n import increments_at
from lcpbench.model.outer import feasible_start
from lcpbench.numba_cache import kernel_module
from lcpbench.problems.scenes import ActuatorScene
from lcpbench.solvers.banded import solve_banded_qp
from lcpbench.solvers.base import Status

face_kernel = kernel_module("lcpbench.linalg.face_kernel")
givens_kernel = kernel_module("lcpbench.linalg.givens_kernel")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_restarted_factor_is_the_full_factor_of_the_new_face(seed):
    rng = np.random.default_rng(seed)
    for _ in range(60):
        n = int(rng.integers(3, 40))
        rows = rng.standard_normal((n, 3))
        rows[:, 1] += 3.0
        R, filled = np.zeros((3, n)), np.zeros(n, np.bool_)
        snap, inv = np.zeros((n, 4)), np.zeros(n)
        fixed = rng.random(n) < 0.3
        assert face_kernel.factor_from(rows, fixed, R, filled, snap, inv, 0)
        for _ in range(5):  # a walk of faces, each refactored from its first change
            new = fixed.copy()
            flip = rng.integers(0, n, size=int(rng.integers(1, 3)))
            new[flip] = ~new[flip]
            changed = np.flatnonzero(new != fixed)
            j0 = int(changed[0]) - 1 if changed.size else n
            assert face_kernel.factor_from(rows, new, R, filled, snap, inv, j0)
            full = np.zeros((3, n))
            assert givens_kernel.factor(rows, new, full)
            assert np.allclose(R, full, rtol=1e-13, atol=1e-13 * np.max(np.abs(full)))
            assert np.allclose(inv, 1.0 / full[0], rtol=1e-13)
            fixed = new


def test_restarted_face_solves_match_dense_solves_along_a_walk():
    chain = ActuatorScene(150, 3.0, links=80).chain()
    step = assemble_step(chain, chain.rest_alpha * 0.9)
    n = step.size
    H = step.dense_hessian()
    rng = np.random.default_rng(7)
    fac = TridiagonalFactor(step.coef, step.stiffness)  # restart=True
    fixed = np.zeros(n, bool)
    for _ in range(12):
        flip = rng.integers(0, n, size=2)
        fixed[flip] = ~fixed[flip]
        rhs = rng.standard_normal(n)
        face = H.copy()
        face[fixed, :] = 0.0
        face[:, fixed] = 0.0
        face[fixed, fixed] = 1.0
        expected = np.linalg.solve(face, rhs)
        x = fac.face_solve(fixed, rhs)
        assert np.max(np.abs(x - expected)) <= 1e-8 * np.max(np.abs(expected))
        # resolve() solves again with this face's factor
        y = fac.resolve(rhs)
        assert np.max(np.abs(y - expected)) <= 1e-8 * np.max(np.abs(expected))


@pytest.mark.parametrize("links,shrink", [(4200, 1.0), (6000, 1.0), (4200, 0.95)])
def test_the_walk_on_restarted_faces_solves_the_step(links, shrink):
    """The dual walk on the step in increments (its faces refactored from the first
    change) reaches the step's minimiser. Oracle: the KKT conditions of the step in
    heights and of the step in increments written out on their numbers
    (tests/energy_oracle.py), and complementarity checked directly: a reaction only
    where the node is on the wall, >= 0, and the walk's reactions −(H d + c) there.
    (Stationarity off the walls is relative to the gradient's terms, ~10¹⁰ times the
    total force here: measured 10⁻⁶ F off, 10⁻¹³ F on the walls.)"""
    chain = ActuatorScene(150, 3.0, links=links).chain()
    _, alpha = feasible_start(chain, chain.rest_alpha * shrink)
    step = assemble_step(chain, alpha)
    inc = increments_at(chain, alpha)
    new = solve_banded_qp(inc)
    assert new.status is Status.SOLVED and new.active_upper.any()
    assert not new.active_lower.any()  # no lower wall in this scene
    u = new.u + inc.heights
    assert_step_kkt(step, u, rtol=1e-8)  # the step's KKT conditions, in heights
    R = assert_step_kkt(inc, new.u, rtol=1e-9)  # and in increments (R = −(H d + c))
    span = np.max(np.abs(step.upper - step.origin))
    F = np.sum(new.forces_upper)
    assert np.all(new.forces_upper >= 0.0)
    assert np.all(new.forces_upper[~new.active_upper] == 0.0)
    assert np.max(np.abs(u[new.active_upper] - step.upper[new.active_upper])) <= 1e-9 * span
    assert np.max(np.abs(R[new.active_upper] - new.forces_upper[new.active_upper])) <= 1e-9 * F


def test_large_n_answers_are_judged_by_the_judge_in_increments(monkeypatch):
    # the judge kernel's exact step is in heights on the Cholesky of H (round-off ~ N⁴);
    # from LARGE_N the judge takes its step in increments on the tridiagonal factor
    import lcpbench
    from lcpbench.model import judge as judge_module
    from lcpbench.model.large_n import LARGE_N

    calls = []
    kernel = judge_module._kernel()

    class Spy:  # the judge kernel, the entries called recorded
        def __getattr__(self, name):
            if name.startswith("judge_"):
                calls.append(name)
            return getattr(kernel, name)

    monkeypatch.setattr(judge_module, "_kernel", Spy)
    res = lcpbench.solve(ActuatorScene(150, 3.0, links=LARGE_N), tol=1e-3)
    assert res.judge == "increments" and res.converged
    assert calls == ["judge_in_increments"]  # the judge's own steps, in increments
    assert res.judgement.judge_rounds >= 1  # its step settled


def _kernel_step(step) -> tuple:
    """``(arrays, lower, upper)``: a step in increments as the judge's pivots take it
    (model/judge_exact_kernel.py; the factored gradient's arguments, the rows of A and
    their mirror, the bands, the linear term and a work row; the walls about u₀)."""
    f64 = np.ascontiguousarray
    arrays = tuple(f64(x, dtype=float) for x in (
        step.coef, step.stiffness, step.phi_origin, step.rest_joint, step.nodal_load,
        step.origin, step.factor.rows, step.factor.rrows, step.bands, step.linear))
    return arrays + (np.empty(step.size),), f64(step.lower, dtype=float), f64(step.upper,
                                                                             dtype=float)


@pytest.mark.parametrize("links,shrink,start", [(60, 1.0, "none"), (60, 0.9, "all"),
                                                 (4200, 1.0, "none")])
def test_the_judges_primal_step_reaches_the_steps_solution(links, shrink, start):
    # the judge's own step in increments (model/judge_exact_kernel.py) against the dual walk
    # (solvers/banded.py), an independent method, on the same step in increments
    from lcpbench.model.judge_checks import FREE, LO, UP
    from lcpbench.numba_cache import kernel_module

    chain = ActuatorScene(150, 3.0, links=links).chain()
    _, alpha = feasible_start(chain, chain.rest_alpha * shrink)
    step = increments_at(chain, alpha)
    ref = solve_banded_qp(step)
    assert ref.status is Status.SOLVED and np.count_nonzero(ref.active_upper) > 0
    n = step.size
    state = np.where(np.isfinite(step.upper), UP, FREE) if start == "all" else np.zeros(n)
    state = state.astype(np.int64)
    scale = float(np.max(ref.forces_upper))
    u, net, roundoff, sizes = (np.empty(n) for _ in range(4))
    # a wall releases its node where it pulls by more than 1e-9 of the largest force
    rounds = kernel_module("lcpbench.model.judge_exact_kernel").primal_step(*_kernel_step(step), np.zeros(n), 1e-9 * scale, state,
                                   4 * n + 30, u, net, roundoff, sizes)[0]
    assert rounds > 0
    held_up, held_lo = state == UP, state == LO
    # the step's KKT conditions from its exact gradient (independent of both walks):
    # stationary off the wall, the wall pushing on its rows, feasible; to 1e-9 of the
    # gradient's terms (the walk's slack) and of the walls' span
    g = step.gradient(u)
    size = float(np.max(step.gradient_scale(u)))
    span = np.max(np.abs(step.upper[np.isfinite(step.upper)]))
    assert np.max(np.abs(g[~held_up]), initial=0.0) <= 1e-9 * size
    assert np.max(g[held_up], initial=0.0) <= 1e-9 * size
    assert np.max(u - step.upper) <= 1e-12 * span
    assert np.max(np.abs(u[held_up] - step.upper[held_up])) <= 1e-12 * span
    # and the dual walk's answer (a strictly convex QP has one minimiser)
    assert np.array_equal(held_up, ref.active_upper) and not held_lo.any()
    assert np.max(np.abs(u - ref.u)) <= 1e-8 * span
    net = -g
    assert abs(np.sum(net[held_up]) - np.sum(ref.forces_upper)) <= 1e-7 * np.sum(ref.forces_upper)


@pytest.mark.parametrize("k,channel", [(0.1, False), (1e4, False), (10.0, True)])
def test_the_judges_pivoting_with_springs_solves_the_elastic_step(k, channel):
    # the judge's block principal pivoting in increments (model/judge_exact_kernel.py),
    # the springs of the nodes on an elastic wall rotated into the twisted factor, from
    # no contact: its answer meets the elastic step's stationarity, written out in
    # energy_oracle (strictly convex: one minimiser)
    from lcpbench.model.elastic import wall_springs
    from lcpbench.model.judge_checks import FREE, LO, UP

    chain = ActuatorScene(150, 3.0, links=200, wall_stiffness=k, channel=channel).chain()
    _, alpha = feasible_start(chain, chain.rest_alpha)
    step = increments_at(chain, alpha)
    n = step.size
    state = np.full(n, FREE, dtype=np.int64)
    u, net, roundoff, sizes = (np.empty(n) for _ in range(4))
    k_up, k_lo = wall_springs(step)
    rounds = kernel_module("lcpbench.model.judge_exact_kernel").pivot_step(
        *_kernel_step(step), k_up, k_lo, np.zeros(n), 0.0, state, 4 * n + 30, u, net,
        roundoff, sizes)[0]
    assert rounds > 1  # it pivoted: the unconstrained minimiser is through the wall
    assert_elastic_step_kkt(step, u)
    # the settled set is the nodes each spring holds (u beyond its wall)
    assert np.array_equal(state == UP, u > step.upper)
    assert np.array_equal(state == LO, u < step.lower)
    assert (state == UP).any()
