"""lcpbench.stable_states: the stable states a cold start and the loading path reach,
each checked by central differences of the exact energy (tests/energy_oracle.py:
stationary, feasible, no negative curvature on the contact set)."""

import numpy as np
import pytest
from energy_oracle import fd_kkt_residual, fd_unstable_directions

import lcpbench
from lcpbench.errors import ProblemError


def _oracle_stable(scene, res):
    chain = scene.chain()
    fu = res.forces
    fl = res.forces_lower if res.forces_lower is not None else np.zeros_like(fu)
    y = res.y[chain.free_nodes]
    assert np.all(np.abs(y) <= chain.wall + 1e-9)
    assert fd_kkt_residual(chain, res.alpha, fu, fl) < 1e-5  # tol 1e-6 rad answers
    assert fd_unstable_directions(chain, res.alpha, fu, fl,
                                  res.judgement.contact_threshold) == 0


def test_a_channel_past_180_degrees_has_two_stable_states():
    # the folded state a cold start finds and the flat one the loading path finds
    scene = lcpbench.ActuatorScene(theta=300, height=0.8, channel=True, links=40)
    states = lcpbench.stable_states(scene, tol=1e-6)
    assert {s.start for s in states} == {"cold", "ramp"}
    assert states[0].energy < states[1].energy  # lowest first
    assert abs(states[0].result.total_force - states[1].result.total_force) > 1.0  # N
    for s in states:
        assert s.result.converged
        _oracle_stable(scene, s.result)


def test_one_state_is_reported_once():
    scene = lcpbench.ActuatorScene(theta=150, height=3.0, links=40)
    states = lcpbench.stable_states(scene, tol=1e-6)
    assert len(states) == 1
    _oracle_stable(scene, states[0].result)


def test_the_starts_are_its_own():
    with pytest.raises(ProblemError, match="start"):
        lcpbench.stable_states(lcpbench.ActuatorScene(), start="ramp")
