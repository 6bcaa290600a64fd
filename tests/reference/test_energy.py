"""The SLSQP minimiser of the exact energy is an independent reference for the LCP driver."""

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene, CantileverScene
from lcpbench.model.chain import energy
from lcpbench.model.result import certify
from lcpbench.reference.energy import (
    WallRows,
    closure,
    energy_gradient,
    energy_hessian,
    lagrangian_hessian,
    minimise_energy,
    walls,
)


def _central(fun, alpha, h=1e-6):
    """Central finite differences of a scalar or vector function (columns = ∂/∂α_j)."""
    cols = []
    for j in range(alpha.size):
        e = np.zeros_like(alpha)
        e[j] = h
        cols.append((np.asarray(fun(alpha + e)) - np.asarray(fun(alpha - e))) / (2 * h))
    return np.stack(cols, axis=-1)


def _chains():
    yield ActuatorScene(theta=150, height=3.0, links=12, weight=0.01).chain()
    yield ActuatorScene(theta=120, height=2.0, links=11, channel=True, weight=0.02).chain()
    yield CantileverScene(links=10, load=0.01).chain()


@pytest.mark.parametrize("chain", list(_chains()), ids=["actuator", "channel", "cantilever"])
def test_analytic_derivatives_match_finite_differences(chain):
    rng = np.random.default_rng(3)
    alpha = chain.rest_alpha + 0.2 * rng.standard_normal(chain.links)
    e0 = chain.force_scale * chain.length
    # energy gradient and Hessian
    g = energy_gradient(chain, alpha)
    assert np.allclose(g, _central(lambda al: energy(chain, al), alpha), rtol=1e-7, atol=1e-8 * e0)
    hess = energy_hessian(chain, alpha)
    assert np.allclose(hess, hess.T)
    fd = _central(lambda al: energy_gradient(chain, al), alpha)
    assert np.allclose(hess, fd, rtol=1e-6, atol=1e-7 * e0)
    # constraint Jacobians
    c, jc = closure(chain, alpha)
    assert np.allclose(jc, _central(lambda al: closure(chain, al)[0], alpha), atol=1e-9)
    assert c.size == (1 if chain.free_nodes[-1] < chain.links else 0)
    rows = WallRows.of(chain)
    gap, jg = walls(chain, alpha, rows)
    assert gap.size == np.isfinite(chain.upper).sum() + np.isfinite(chain.lower).sum() > 0
    assert np.allclose(jg, _central(lambda al: walls(chain, al, rows)[0], alpha), atol=1e-9)
    # Hessian of the Lagrangian E − λc − μ·g
    lam = rng.standard_normal(c.size)
    mu = rng.random(gap.size)

    def lagrangian_gradient(al):
        return (energy_gradient(chain, al) - closure(chain, al)[1].T @ lam
                - walls(chain, al, rows)[1].T @ mu)

    hl = lagrangian_hessian(chain, alpha, lam, mu, rows)
    assert np.allclose(hl, _central(lagrangian_gradient, alpha), rtol=1e-6, atol=1e-7 * e0)


SCENES = [
    *[pytest.param({"theta": t, "height": h, "links": 30}, id=f"theta{t}-h{h}")
      for t in (90, 120, 150, 170) for h in (2, 3, 5)],
    pytest.param({"theta": 150, "height": 3, "links": 40, "channel": True}, id="channel"),
    pytest.param({"theta": 40, "height": 1, "links": 30, "channel": True, "weight": 0.05},
                 id="channel-lower-wall"),
    pytest.param({"theta": 60, "height": 5, "links": 30}, id="no-contact"),
]


@pytest.mark.parametrize("kwargs", SCENES)
def test_lcp_driver_matches_the_exact_energy_minimiser(kwargs):
    scene = ActuatorScene(**kwargs)
    ref = minimise_energy(scene)
    assert ref.success and ref.polished, ref.message
    res = lcpbench.solve(scene, tol=1e-12, settings="high")
    assert res.converged, res.reason
    assert np.max(np.abs(res.alpha - ref.alpha)) < 1e-8
    assert abs(res.total_force - ref.total_force) <= 1e-6 * max(ref.total_force, 1e-9)
    # per-node reactions: same ordering and sign as ContactResult.forces
    assert ref.forces.shape == res.forces.shape
    assert np.allclose(ref.forces, res.forces, rtol=1e-6, atol=1e-9 * ref.total_force + 1e-15)
    if scene.channel:
        assert np.allclose(ref.forces_lower, res.forces_lower, rtol=1e-6, atol=1e-12)
    else:
        assert ref.forces_lower is None
    assert np.allclose(ref.y, res.y, atol=1e-8 * scene.length)


def test_no_contact_scene_has_no_reaction():
    ref = minimise_energy(ActuatorScene(theta=60, height=5, links=30))
    assert ref.success and ref.total_force == 0.0
    assert np.max(ref.y) < 5.0


def test_lower_wall_reaction_pushes_up():
    ref = minimise_energy(ActuatorScene(theta=40, height=1, links=30, channel=True, weight=0.05))
    assert ref.success
    assert ref.total_force == 0.0
    assert ref.forces_lower.sum() > 0 and np.min(ref.forces_lower) >= -1e-15
    assert np.min(ref.y) == pytest.approx(-1.0, abs=1e-12)


def test_reference_satisfies_exact_statics():
    """The multipliers are the wall reactions: the exact-geometry certificate accepts them."""
    scene = ActuatorScene(theta=150, height=2, links=30)
    ref = minimise_energy(scene)
    chain = scene.chain()
    lower = np.zeros_like(ref.forces)
    cert = certify(chain, ref.alpha, ref.forces, lower)
    assert cert.relative_torque_residual < 1e-10
    assert cert.closure < 1e-12 * scene.length
    assert cert.min_gap > -1e-12 * scene.length
    assert cert.min_force >= -1e-12
    assert ref.energy == pytest.approx(energy(chain, ref.alpha))


def test_reference_works_beyond_180_degrees():
    """Where the linearised driver stops (theta > 180), the reference still finds a KKT point."""
    scene = ActuatorScene(theta=200, height=3, links=30)
    ref = minimise_energy(scene)
    assert ref.success, ref.message
    cert = certify(scene.chain(), ref.alpha, ref.forces, np.zeros_like(ref.forces))
    assert cert.relative_torque_residual < 1e-10 and ref.total_force > 0


def test_cantilever_has_no_closure_and_matches_the_driver():
    scene = CantileverScene(links=30)
    ref = minimise_energy(scene)
    res = lcpbench.solve(scene, tol=1e-12, settings="high")
    assert ref.success and ref.pin_reaction == 0.0
    assert np.max(np.abs(res.alpha - ref.alpha)) < 1e-8
    assert ref.total_force == pytest.approx(res.total_force, rel=1e-6)


def test_slsqp_alone_is_close_and_reports_itself():
    scene = ActuatorScene(theta=150, height=3, links=30)
    raw = minimise_energy(scene, polish=False, ftol=1e-16)
    polished = minimise_energy(scene)
    assert not raw.polished and raw.newton_iterations == 0 and raw.nit > 0
    assert np.max(np.abs(raw.alpha - polished.alpha)) < 1e-7
    assert raw.kkt_residual > polished.kkt_residual
