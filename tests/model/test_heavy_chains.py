"""Heavy chains (issue 19, target 8): wℓ³/EI up to 10⁴ converge, checked against an
independent energy minimisation (SLSQP + Newton polish, reference/energy.py)."""

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene, CantileverScene
from lcpbench.model.angle_step import heavy, load_parameter, solve_in_angles
from lcpbench.reference.energy import minimise_energy

ELL, EI = 30.0, 32.01


def _scenes(count, links, seed):
    rng = np.random.default_rng(seed)
    for k in range(count):
        q = 10 ** rng.uniform(np.log10(40.0), 4.0)
        yield ActuatorScene(theta=rng.uniform(60, 180), height=rng.uniform(0.5, 8.0),
                            links=links, weight=q * EI / ELL**3, channel=bool(k % 2))


def _totals(forces_upper, forces_lower):
    lower = 0.0 if forces_lower is None else float(np.sum(forces_lower))
    return float(np.sum(forces_upper)), lower


def _check(scene, tight=1e-8):
    paper = lcpbench.solve(scene)  # the paper's tolerance, 1e-3 rad
    assert paper.converged, paper.reason
    assert paper.outer_iterations <= 30
    res = lcpbench.solve(scene, tol=tight)  # the judge certifies to force_tol(tight)
    ref = minimise_energy(scene)
    assert ref.success, ref.message
    assert res.converged, res.reason
    f, f_lo = _totals(res.forces, res.forces_lower)
    r, r_lo = _totals(ref.forces, ref.forces_lower)
    scale = max(abs(r), abs(r_lo), EI / ELL**2)
    assert abs(f - r) <= 1e-6 * scale and abs(f_lo - r_lo) <= 1e-6 * scale
    # the same shape: node heights to 1e-6 ℓ
    assert np.max(np.abs(res.y - ref.y)) <= 1e-6 * ELL
    return res, ref


def test_the_load_parameter_is_w_ell_cubed_over_ei():
    scene = ActuatorScene(theta=150, height=3.0, links=20, weight=1000 * EI / ELL**3)
    assert load_parameter(scene.chain()) == pytest.approx(1000, rel=1e-12)
    assert heavy(scene.chain())
    assert not heavy(ActuatorScene(theta=150, height=3.0, links=20).chain())  # the paper's


@pytest.mark.parametrize("scene", list(_scenes(22, 24, seed=7)),
                         ids=lambda s: f"q{s.weight * ELL**3 / EI:.0f}-ch{int(s.channel)}")
def test_heavy_scenes_converge_and_agree_with_the_energy_minimum(scene):
    _check(scene)


def test_the_heaviest_chain_hangs_and_drapes():
    # wℓ³/EI = 10⁴: off the single wall (no reaction), onto the channel's lower wall
    free, _ = _check(ActuatorScene(theta=150, height=3.0, links=30, weight=1e4 * EI / ELL**3))
    assert free.total_force == 0.0
    drape, ref = _check(ActuatorScene(theta=150, height=3.0, links=30, channel=True,
                                      weight=1e4 * EI / ELL**3))
    # the lower wall carries (nearly) the whole weight of the chain: vertical balance
    # with the pins' reactions, which the reference reports separately
    assert np.sum(drape.forces_lower) > 0.5 * 1e4 * EI / ELL**2


def test_angle_steps_converge_quadratically():
    chain = ActuatorScene(theta=140, height=3.0, links=40, weight=3000 * EI / ELL**3).chain()
    out = solve_in_angles(chain, tol=1e-12)
    assert out.converged
    s = [x for x in out.step_sizes if x > 0]
    # the last steps: each at most a constant times the square of the one before
    tail = [(a, b) for a, b in zip(s[:-1], s[1:], strict=True) if 1e-12 < b < a < 1e-2]
    assert tail and all(b <= 10 * a * a for a, b in tail)


def test_a_heavy_cantilever_agrees_with_the_energy_minimum():
    scene = CantileverScene(links=24, load=500 * EI / ELL**3)
    assert heavy(scene.chain())
    res = lcpbench.solve(scene, tol=1e-8)
    ref = minimise_energy(scene)
    assert ref.success and res.converged, res.reason
    scale = max(abs(ref.total_force), EI / ELL**2)
    assert abs(res.total_force - ref.total_force) <= 1e-6 * scale


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_many_heavy_scenes_at_n_140(seed):
    # tol 1e-6: at 1e-8 the judge's own height step at N = 140 carries 1/cos²α ~ 1e4
    # for links a degree from the vertical, and its round-off (~1e-6 F₀) passes the
    # allowance at wℓ³/EI ~ 8000 (2 of 60 scenes); the agreement with the energy
    # minimum is still asserted to 1e-6 of the force
    for scene in _scenes(30, 140, seed):
        _check(scene, tight=1e-6)
