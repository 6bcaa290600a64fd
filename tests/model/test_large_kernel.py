"""The compiled parts of a large-N outer step (:mod:`lcpbench.model.large_kernel`).

The assembly is checked against the energy's definition (its gradient and
Gauss–Newton Hessian in heights by central differences, summed exactly), the
trial and energy against their definitions, and the block solves against a
dense solve of the same principal block (an independent method).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lcpbench.model import large_n
from lcpbench.model.chain import energy, heights
from lcpbench.problems.scenes import ActuatorScene

EPS = np.finfo(float).eps


def _chain_alpha(links, seed=0, shrink=0.97):
    chain = ActuatorScene(150.0, 3.0, links=links).chain()
    rng = np.random.default_rng(seed)
    return chain, chain.rest_alpha * shrink + 1e-4 * rng.standard_normal(chain.links)


def _alpha_of(chain, u):
    """The link angles of free-node heights ``u`` (both ends at height 0), each on the
    branch cos α > 0 (the arcs of θ <= 150° have no link past vertical)."""
    y = np.concatenate(([0.0], u, [0.0]))
    return np.arcsin(np.diff(y) / chain.link_length)


@pytest.mark.parametrize("links,seed", [(120, 0), (300, 1)])
def test_the_step_in_increments_is_the_energys_quadratic_model_about_u0(links, seed):
    """The compiled assembly in increments d = u − u₀ against the energy's definition:
    at heights u₀ (α from them, so the chain closes), its linear term is ∇_u E(u₀) and its
    H is Jᵀ diag(k) J, J = ∂φ/∂u, both by central differences of the energy and of the
    joint angles as functions of the heights (eqs. 20-31 in heights); its walls are the
    chain's walls less u₀; its factored gradient is H d + c."""
    chain = ActuatorScene(150.0, 3.0, links=links).chain()
    rng = np.random.default_rng(seed)
    n = chain.free_nodes.size
    u0 = 0.97 * heights(chain, chain.rest_alpha) + 1e-3 * rng.standard_normal(n)
    alpha = _alpha_of(chain, u0)
    got = large_n.increments_at(chain, alpha)
    assert np.max(np.abs(got.heights - u0)) <= 64 * EPS * chain.length  # u₀ (mm)
    assert np.array_equal(got.origin, np.zeros(n))
    for wall, mine in ((chain.upper, got.upper), (chain.lower, got.lower)):
        held = np.isfinite(wall)
        assert np.array_equal(np.isfinite(mine), held) and np.all(mine[~held] == wall[~held])
        assert np.all(np.abs(mine[held] - (wall[held] - u0[held])) <= 64 * EPS * chain.length)
    t = np.abs(np.tan(alpha)) + np.abs(alpha)  # v = tan α − α, φ₀ = v_l − v_r (eq. 24)
    assert np.all(np.abs(got.v - (np.tan(alpha) - alpha)) <= 4 * EPS * t)
    assert np.all(np.abs(got.phi0 - (got.v[:-1] - got.v[1:])) <= 4 * EPS * (t[:-1] + t[1:]))
    h = 1e-6 * chain.link_length
    grad, J = np.empty(n), np.empty((chain.joint_links.shape[0], n))
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]

    def phi(u):
        a = _alpha_of(chain, u)
        return a[right] - a[left]

    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        grad[i] = (_fsum_energy(chain, _alpha_of(chain, u0 + e))
                   - _fsum_energy(chain, _alpha_of(chain, u0 - e))) / (2 * h)
        J[:, i] = (phi(u0 + e) - phi(u0 - e)) / (2 * h)
    g_scale = np.max(np.abs(grad))
    assert np.max(np.abs(got.linear - grad)) <= 1e-7 * g_scale, np.max(np.abs(got.linear - grad))
    H_fd = J.T @ (chain.joint_stiffness[:, None] * J)
    H = got.dense_hessian()
    assert np.max(np.abs(H - H_fd)) <= 1e-7 * np.max(np.abs(H_fd)), np.max(np.abs(H - H_fd))
    # the factored gradient is H d + c (H from the bands): a property, not the code
    d = 1e-3 * rng.standard_normal(n)
    Hd = got.factor.matvec(d)
    assert np.max(np.abs(got.gradient(d) - (Hd + got.linear))) <= 1e-9 * np.max(np.abs(Hd))
    assert np.max(np.abs(H @ d - Hd)) <= 1e-12 * np.max(np.abs(Hd))


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


@pytest.mark.parametrize("k", [0.1, 1e4])
def test_compiled_step_residuals_at_elastic_walls_are_the_reference_residuals(k):
    """The same at elastic walls (the compliant gaps g + R/k). The reactions are the same
    bits; the gaps' compliant part is R/k in the kernel and ((R/F)·F)/k in the reference,
    within an ulp of R: the verdict terms agree to a few ulps of their terms.

    Route against route, as above: the residuals are the step judge's definition."""
    from dataclasses import replace

    chain = replace(ActuatorScene(150.0, 3.0, links=400, wall_stiffness=k).chain(),
                    increments=True)
    rng = np.random.default_rng(3)
    alpha = chain.rest_alpha * 0.97 + 1e-4 * rng.standard_normal(chain.links)
    step = large_n.increments_at(chain, alpha)
    assert step.elastic
    u = np.minimum(step.upper + 1e-3, 0.5 * rng.standard_normal(step.size))  # some indent
    got, R = step.compiled_residuals(u)
    want, R_ref = _numpy_residuals(step, u)
    assert np.array_equal(R, R_ref)
    scale = (np.max(np.abs(u)) / step.length_scale
             + np.max(np.abs(R)) / (k * step.length_scale))
    for key in ("natural", "min_gap", "min_reaction"):
        assert abs(got[key] - want[key]) <= 8 * np.finfo(float).eps * max(scale, 1.0), key
    assert got["term_size"] == want["term_size"]


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
    assert reused.engine.startswith("increments driver (large N")
    assert np.array_equal(reused.alpha, new.alpha) and reused.total_force == new.total_force
    assert reused.converged == new.converged
