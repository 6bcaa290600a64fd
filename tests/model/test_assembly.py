"""The contact step: banded energy-based assembly against the paper's eqs. (3)–(31).

Expected values come from the paper's own equations (assembled independently
in lcpbench.reference.dense), from statics by hand (the lumped weights), and from
finite differences of the exact energy.
"""

import numpy as np
import pytest
from energy_oracle import assert_step_kkt
from hypothesis import given, settings
from hypothesis import strategies as st

from lcpbench import ActuatorScene, CantileverScene
from lcpbench.model.chain import alpha_from_heights, energy, heights
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.reference.dense import paper_step
from lcpbench.solvers.banded import solve_banded_qp
from lcpbench.solvers.lemke import lemke


def random_config(scene, seed, spread=0.3):
    chain = scene.chain()
    rng = np.random.default_rng(seed)
    return chain, chain.rest_alpha + spread * rng.standard_normal(chain.links)


def dense(scene, alpha, **kw):
    chain = scene.chain()
    return paper_step(alpha, EI=scene.EI, length=scene.length, weight=scene.weight,
                      height=scene.height, rest_joint=chain.rest_joint, **kw)


def banded_K_z(chain, alpha, height):
    step = assemble_step(chain, alpha)
    K = step.dense_hessian()
    z = -K @ np.full(step.size, height) - step.linear
    return K, z


@settings(max_examples=25, deadline=None)
@given(n=st.integers(4, 60), seed=st.integers(0, 2**31), theta=st.floats(5, 200))
def test_A_times_LM_is_twice_identity(n, seed, theta):
    scene = ActuatorScene(theta=theta, height=1.0, links=n)
    _, alpha = random_config(scene, seed)
    p = dense(scene, alpha)
    assert np.allclose(p.A @ p.L @ p.M, 2 * np.eye(n - 1), atol=1e-9 * np.abs(p.A).max())


@settings(max_examples=25, deadline=None)
@given(n=st.integers(4, 60), seed=st.integers(0, 2**31), theta=st.floats(5, 200),
       weight=st.sampled_from([0.0, 2.45e-4, 0.05]))
def test_banded_assembly_matches_paper_with_gravity(n, seed, theta, weight):
    scene = ActuatorScene(theta=theta, height=2.5, links=n, weight=weight)
    chain, alpha = random_config(scene, seed)
    p = dense(scene, alpha)
    K, z = banded_K_z(chain, alpha, scene.height)
    scale_K = np.abs(K).max()
    assert np.allclose(K, p.K, rtol=0, atol=1e-10 * scale_K)
    assert np.allclose(z, p.z, rtol=0, atol=1e-10 * scale_K * scene.height)


def test_stiffness_is_symmetric_positive_definite_pentadiagonal():
    chain, alpha = random_config(ActuatorScene(links=50), 1)
    K = assemble_step(chain, alpha).dense_hessian()
    assert np.allclose(K, K.T)
    assert np.linalg.eigvalsh(K).min() > 0
    i, j = np.indices(K.shape)
    assert np.all(K[np.abs(i - j) > 2] == 0)
    assert np.all(np.diag(K, 2) != 0)


def test_gravity_load_is_half_of_each_adjacent_link_weight():
    """Free-body statics: each interior node carries μ/2 from each neighbouring link."""
    scene_w = ActuatorScene(links=30, weight=0.01)
    scene_0 = ActuatorScene(links=30, weight=0.0)
    chain, alpha = random_config(scene_w, 3)
    mu = scene_w.weight * scene_w.length / scene_w.links
    dz = dense(scene_w, alpha).z - dense(scene_0, alpha).z
    assert np.allclose(dz, -mu, rtol=1e-9)


def test_erratum_eq13_printed_gamma_is_off_by_a_over_2():
    """Eq. (13) as printed scales the gravity term by a/2: a length, so the units break."""
    scene_w = ActuatorScene(links=30, weight=0.01)
    scene_0 = ActuatorScene(links=30, weight=0.0)
    _, alpha = random_config(scene_w, 4)
    a = scene_w.length / scene_w.links
    printed = dense(scene_w, alpha, printed_gamma=True).z - dense(scene_0, alpha).z
    corrected = dense(scene_w, alpha).z - dense(scene_0, alpha).z
    assert np.allclose(printed, (a / 2) * corrected, rtol=1e-9)
    # Units: the same scene in metres (N·m², N/m) must give the same forces in N.
    metres = dict(length=scene_w.length * 1e-3, EI=scene_w.EI * 1e-6, weight=scene_w.weight * 1e3)
    chain = scene_w.chain()

    def grav(printed_gamma, units):
        kw = dict(height=1.0, rest_joint=chain.rest_joint, printed_gamma=printed_gamma)
        w = paper_step(alpha, **units, **kw).z
        return w - paper_step(alpha, **{**units, "weight": 0.0}, **kw).z

    mm = dict(length=scene_w.length, EI=scene_w.EI, weight=scene_w.weight)
    assert np.allclose(grav(False, mm), grav(False, metres), rtol=1e-9)
    assert not np.allclose(grav(True, mm), grav(True, metres), rtol=1e-3)


def test_erratum_eq25_v_is_not_divided_by_a():
    """At the linearisation point (21) must return α, and (25) must return Lα."""
    scene = ActuatorScene(links=20)
    chain, alpha = random_config(scene, 5, spread=0.1)
    a = scene.length / scene.links
    y = np.concatenate(([0.0], np.cumsum(a * np.sin(alpha))))
    # close the chain on the right pin so that û reproduces α exactly
    alpha[-1] = np.arcsin(-y[-2] / a)
    p = dense(scene, alpha)
    u = np.concatenate(([0.0], np.cumsum(a * np.sin(alpha))))[1:-1]
    v = np.tan(alpha) - alpha
    assert np.allclose(p.M @ u / a - v, alpha, atol=1e-12)  # eq. (21)
    printed_25 = p.L @ (p.M @ u - v) / a
    corrected_25 = p.L @ (p.M @ u / a - v)
    assert np.allclose(corrected_25, p.L @ alpha, atol=1e-12)
    assert not np.allclose(printed_25, p.L @ alpha, atol=1e-3)


@pytest.mark.parametrize("scene", [ActuatorScene(links=24, weight=0.01),
                                   CantileverScene(links=24)], ids=["actuator", "cantilever"])
def test_step_gradient_is_the_exact_energy_gradient(scene):
    """First-order linearisation is exact: ∇ of the step = finite differences of the energy."""
    chain = scene.chain()
    alpha = chain.rest_alpha + 0.05 * np.sin(np.arange(chain.links))
    u = heights(chain, alpha)
    if chain.free_nodes[-1] < chain.links:  # pinned: re-close the chain
        alpha = alpha_from_heights(chain, u, alpha)
    step = assemble_step(chain, alpha)
    grad = step.gradient(u)
    fd = np.empty_like(u)
    h = 1e-6
    for i in range(u.size):
        e = np.zeros_like(u)
        e[i] = h
        fd[i] = (energy(chain, alpha_from_heights(chain, u + e, alpha))
                 - energy(chain, alpha_from_heights(chain, u - e, alpha))) / (2 * h)
    assert np.allclose(grad, fd, rtol=1e-6, atol=1e-7 * np.abs(grad).max())
    assert np.allclose(grad, step.matvec(u) + step.linear, atol=1e-9 * np.abs(step.linear).max())


@pytest.mark.parametrize("channel", [False, True])
def test_lcp_form_and_qp_form_have_the_same_solution(channel):
    """Lemke on the (condensed) LCP and the active-set QP solver are independent methods."""
    scene = ActuatorScene(theta=170, height=1.0, links=40, channel=channel, weight=0.02)
    chain = scene.chain()
    step = assemble_step(chain, chain.rest_alpha)
    qp = solve_banded_qp(step)
    form = step.lcp()
    sol = lemke(form.M, form.q)
    assert qp.solved and sol.solved
    u = step.from_lcp(form, sol.z)
    assert np.allclose(u, qp.u, atol=1e-9)
    r = np.zeros(step.size)
    r[form.rows] = sol.w[: form.n_gap]
    assert np.allclose(r, qp.forces_upper, atol=1e-9 * max(1, r.max()))
    assert_step_kkt(step, qp.u)  # and the step's KKT conditions, written out
    # rows only where a node can reach the wall: never the ones within h of a pin
    assert np.all(np.isinf(step.upper[: int(scene.height / (scene.length / scene.links)) - 1]))
