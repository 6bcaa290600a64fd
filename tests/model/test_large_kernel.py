"""The compiled parts of a large-N outer step (:mod:`lcpbench.model.large_kernel`).

Each is checked against the numpy reference it replaces (the same arithmetic:
bit for bit where no sum is reordered), and the block solves against a dense
solve of the same principal block (an independent method).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lcpbench.model import large_n
from lcpbench.model.chain import energy, heights
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.problems.scenes import ActuatorScene

FIELDS = ("bands", "linear", "lower", "upper", "inv_a_cos", "coef", "origin", "alpha0",
          "phi_origin")
#: numpy's tan and arcsin are its own SIMD code on AVX-512 machines and libm's
#: elsewhere, and the kernels call libm: one ulp apart on some arguments. Fields
#: computed from them are compared to a few ulps of the terms (machine-independent).
ULPS = 4
EPS = np.finfo(float).eps


def _same_to_ulps(got, ref, scale):
    got, ref = np.asarray(got), np.asarray(ref)
    assert got.shape == ref.shape
    assert np.all(np.abs(got - ref) <= ULPS * EPS * scale)


def _chain_alpha(links, seed=0, shrink=0.97):
    chain = ActuatorScene(150.0, 3.0, links=links).chain()
    rng = np.random.default_rng(seed)
    return chain, chain.rest_alpha * shrink + 1e-4 * rng.standard_normal(chain.links)


@pytest.mark.parametrize("links,seed", [(300, 0), (5000, 1)])
def test_compiled_assembly_is_the_reference_step_in_increments(links, seed):
    """Route against route: the compiled assembly must be the numpy one bit for bit (the
    same arithmetic); the numpy step is checked against the paper's equations in
    tests/model/test_assembly.py."""
    chain, alpha = _chain_alpha(links, seed)
    ref = large_n.increment_step(assemble_step(chain, alpha))
    got = large_n.increments_at(chain, alpha)
    for f in FIELDS:
        assert np.array_equal(getattr(got, f), getattr(ref, f)), f
    # v = tan α − α and φ₀ = v_j − v_{j+1}: to the ulps of tan α
    t = np.abs(np.tan(alpha)) + np.abs(alpha)
    _same_to_ulps(got.v, ref.v, t)
    _same_to_ulps(got.phi0, ref.phi0, t[:-1] + t[1:])
    assert np.array_equal(got.heights, assemble_step(chain, alpha).origin)
    assert np.array_equal(got.factor.rows, ref.factor.rows)
    assert np.array_equal(got.factor.rrows, ref.factor.rrows)
    rng = np.random.default_rng(seed + 10)
    for _ in range(3):
        u = 1e-3 * rng.standard_normal(got.size)
        assert np.array_equal(got.gradient(u), ref.gradient(u))
        assert np.array_equal(got.gradient_scale(u), ref.gradient_scale(u))
    # the factored gradient is H u + c (H from the bands): a property, not the code
    u = 1e-3 * rng.standard_normal(got.size)
    Hu = got.factor.matvec(u)
    assert np.max(np.abs(got.gradient(u) - (Hu + got.linear))) <= 1e-9 * np.max(np.abs(Hu))


def _fsum_energy(chain, alpha):
    """The energy's definition summed exactly (math.fsum of numpy's terms, the
    heights by fsum too): an independent reference for the compiled sums."""
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]
    phi = alpha[right] - np.where(left >= 0, alpha[np.maximum(left, 0)], 0.0)
    dy = chain.link_length * np.sin(alpha)
    y = np.array([0.0] + [math.fsum(dy[:i + 1]) for i in range(dy.size)])
    centre = 0.5 * (y[:-1] + y[1:])
    springs = math.fsum(chain.joint_stiffness * (phi - chain.rest_joint) ** 2)
    return 0.5 * springs - math.fsum(chain.link_load * centre)


@pytest.mark.parametrize("links", [300, 4000])
def test_energy_is_its_definition_summed_exactly(links):
    """chain.energy (the one compiled energy, compensated sums) equals the energy's
    terms summed exactly, to a few ulps of the terms' size."""
    chain, alpha = _chain_alpha(links)
    E = energy(chain, alpha)
    size = 0.5 * float(np.sum(chain.joint_stiffness * (alpha[1:] - alpha[:-1]) ** 2)) + float(
        np.sum(np.abs(chain.link_load)) * chain.length)
    assert abs(E - _fsum_energy(chain, alpha)) <= 64 * EPS * size


@pytest.mark.parametrize("links", [300, 20000])
def test_compiled_trial_agrees_with_the_reference(links):
    chain, alpha = _chain_alpha(links)
    rng = np.random.default_rng(3)
    du = 1e-2 / links * rng.standard_normal(chain.free_nodes.size)
    at = large_n.trial_of(chain, alpha, du)
    for t in (1.0, 0.5, 0.125):  # properties: the heights moved by t·du, each link on
        a, E_t = at(t)  # its branch and winding, and the energy of that chain
        moved = heights(chain, a) - heights(chain, alpha)
        assert np.max(np.abs(moved - t * du)) <= 1e-12 * chain.length
        assert np.array_equal(np.cos(a) >= 0, np.cos(alpha) >= 0)
        assert np.max(np.abs(a - alpha)) < 0.1
        assert abs(E_t - energy(chain, a)) <= 1e-13 * abs(E_t)
    # a move no chain of these links can make (one link 2a long): no trial
    big = np.zeros(chain.free_nodes.size)
    big[chain.free_nodes.size // 2] = 2 * chain.link_length
    a, E_t = large_n.trial_of(chain, alpha, big)(1.0)
    assert a is None


def test_block_solves_match_a_dense_solve_of_the_block():
    chain, alpha = _chain_alpha(400)
    step = large_n.increments_at(chain, alpha)
    H = step.dense_hessian()
    rng = np.random.default_rng(5)
    n = step.size
    cases = [np.flatnonzero(~np.isfinite(chain.upper)),  # what the step judge re-solves
             np.r_[0:20, 21:40, 42:50, 200:203, n - 9:n], np.r_[7:8]]
    for idx in cases:
        assert idx.size * 2 <= n  # the block path
        rhs = rng.standard_normal(idx.size)
        want = np.linalg.solve(H[np.ix_(idx, idx)], rhs)
        got = step.solve_on(idx, rhs)
        assert np.max(np.abs(got - want)) <= 1e-8 * np.max(np.abs(want))


@pytest.mark.parametrize("links", [300, 20000])
def test_trial_from_the_assembly_is_the_trial_from_alpha(links):
    """The line search's trial with the assembly's sin α and sign of cos α
    (:func:`large_kernel.trial_energy_at`) gives the chain and energy of the trial
    from α alone, bit for bit."""
    chain, alpha = _chain_alpha(links)
    step = large_n.increments_at(chain, alpha, large_n.StepWork(chain.links))
    rng = np.random.default_rng(4)
    du = 1e-2 / links * rng.standard_normal(chain.free_nodes.size)
    fast, plain = large_n.trial_of(chain, alpha, du, step), large_n.trial_of(chain, alpha, du)
    for t in (1.0, 0.5, 0.125):
        (a, E), (b, F) = fast(t), plain(t)
        assert np.array_equal(a, b) and E == F


def _numpy_residuals(step, u):
    from lcpbench.model import step_solver

    class Plain:  # the step without its compiled residuals: the numpy reference runs
        def __getattr__(self, name):
            if name == "compiled_residuals":
                raise AttributeError(name)
            return getattr(step, name)

    return step_solver.step_residuals(Plain(), u)


@pytest.mark.parametrize("links,seed", [(400, 0), (20000, 1)])
def test_compiled_step_residuals_are_the_reference_residuals(links, seed):
    """The step judge's residuals in one kernel against step_residuals' numpy on a
    step answer (the walk's) and on heights off it: the same reactions and verdict
    terms bit for bit (Σ g·r, reported only, summed in another order).

    Route against route: the residuals are the step judge's own numbers, which only its
    definition fixes; the step's answer is checked by its KKT conditions in
    tests/model/test_large_n.py."""
    from lcpbench.solvers.banded import solve_banded_qp

    chain, alpha = _chain_alpha(links, seed)
    step = large_n.increments_at(chain, alpha)
    u = solve_banded_qp(step).u
    rng = np.random.default_rng(seed)
    for x in (u, u + 1e-6 * rng.standard_normal(u.size)):
        got, R = step.compiled_residuals(x)
        want, R_ref = _numpy_residuals(step, x)
        assert np.array_equal(R, R_ref)
        for key in ("natural", "min_gap", "min_reaction", "term_size"):
            assert got[key] == want[key], key
        # a sum of n terms in another order: within n ε Σ|g r| of each other
        up = np.isfinite(step.upper)
        size = np.sum(np.abs((step.upper[up] - x[up]) / step.length_scale
                             * (R_ref[up] / step.force_scale)))
        assert abs(got["complementarity"] - want["complementarity"]) <= \
            x.size * np.finfo(float).eps * size
    bad = u.copy()
    bad[3] = np.nan
    assert step.compiled_residuals(bad) is None  # the reference reports NaN heights


def test_outer_steps_that_rewrite_one_set_of_arrays_give_fresh_arrays_answer(monkeypatch):
    """The large-N driver assembles every outer step into one :class:`large_n.StepWork`;
    with fresh arrays for each step (as before) the solve is the same, bit for bit.

    Route against route: reusing arrays is promised to change nothing, bit for bit;
    at N = 6000 the energy oracle is out of reach (~N² terms)."""
    import lcpbench
    from lcpbench.model import large_driver

    scene = ActuatorScene(150.0, 3.0, links=6000)
    reused = lcpbench.solve(scene, tol=1e-3)
    fresh = large_n.increments_at
    monkeypatch.setattr(large_driver, "increments_at", lambda chain, alpha, work: fresh(chain, alpha))
    new = lcpbench.solve(scene, tol=1e-3)
    assert reused.engine.startswith("numpy (large N")
    assert np.array_equal(reused.alpha, new.alpha) and reused.total_force == new.total_force
    assert reused.converged == new.converged
