"""The hard-case suite (`lcpbench sweep --grid hard`): the globalised driver converges on all.

Expected values come from properties: the exact-geometry certificate, monotonicity
of the force in EI (linear in EI when gravity is negligible), zero force where
nothing touches.
"""

import pytest

import lcpbench
from lcpbench.bench.grid import _grazing_height, hard_scenes

SCENES = hard_scenes()


@pytest.fixture(scope="module")
def solved():
    return {s: lcpbench.solve(s, tol=1e-8) for s in SCENES}


@pytest.mark.parametrize("scene", SCENES, ids=lambda s: f"th{s.theta:g}-h{s.height:.4g}-N{s.links}"
                         f"-w{s.weight:g}-EI{s.EI:g}{'-ch' if s.channel else ''}")
def test_globalised_driver_converges_and_is_certified(solved, scene):
    res = solved[scene]
    assert res.converged, res.reason
    c = res.certificate
    assert c.min_gap >= -1e-6 * scene.length and c.min_force >= -1e-9
    assert c.relative_torque_residual < 1e-6 and c.closure < 1e-6 * scene.length


def test_grazing_pair_brackets_first_contact(solved):
    clear, touch = [s for s in SCENES if s.weight == 0.0 and s.theta == 120.0]
    peak = _grazing_height(120.0, clear.links)
    assert clear.height > peak > touch.height
    assert solved[clear].total_force == 0.0
    # 1e-9 mm of interference: a force of order K * 1e-9, tiny but not negative
    assert 0.0 <= solved[touch].total_force < 1e-6


def test_no_contact_and_heavy_chain_have_no_force(solved):
    for s in SCENES:
        if s.theta == 40.0 or s.weight >= 0.05:
            assert solved[s].total_force == 0.0


def test_force_grows_with_stiffness(solved):
    by_ei = {s.EI: solved[s].total_force for s in SCENES
             if s.theta == 150.0 and s.height == 3.0 and s.links == 140 and s.weight < 1e-3}
    base = lcpbench.solve(lcpbench.ActuatorScene(theta=150.0, height=3.0), tol=1e-8)
    assert by_ei[1.0] < base.total_force < by_ei[1000.0]
    # without gravity the energy is EI times a function of the shape alone, so the
    # reactions are exactly proportional to EI, from EI = 1 to 1000
    light = [lcpbench.solve(lcpbench.ActuatorScene(theta=150.0, height=3.0, EI=ei, weight=0.0),
                            tol=1e-10) for ei in (1.0, 1000.0)]
    assert light[1].total_force / light[0].total_force == pytest.approx(1000.0, rel=1e-8)
