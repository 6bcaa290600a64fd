"""lcpbench.stable_states: the stable states a cold start and the loading path reach,
each checked by central differences of the exact energy (tests/energy_oracle.py:
stationary, feasible, no negative curvature on the contact set); and a solve's
``states``, where its own starts (an escape's restarts, the loading path) reach
several, each checked by a minimisation of the exact energy (SLSQP) from it."""

import numpy as np
import pytest
from energy_oracle import fd_kkt_residual, fd_unstable_directions

import lcpbench
from lcpbench.errors import ProblemError
from lcpbench.model.chain import energy
from lcpbench.reference.energy import minimise_energy


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


@pytest.mark.parametrize("scene, tol", [
    # the two-state scene (the cold start a saddle at 67.50 N): at tol 1e-4 the
    # escape reaches the folded state, the loading path the flat one
    (lcpbench.ActuatorScene(theta=300, height=0.8, channel=True, links=40), 1e-4),
    # the first reproducer, at the default tol
    (lcpbench.ActuatorScene(theta=270, height=0.5, channel=True, links=140), 1e-3),
])
def test_a_solve_whose_starts_reach_two_stable_states_says_so(scene, tol):
    res = lcpbench.solve(scene, tol=tol)
    assert res.converged and res.retried("escaped") is not None
    assert len(res.states) == 2 and [s.answer for s in res.states].count(True) == 1
    assert [s.energy for s in res.states] == sorted(s.energy for s in res.states)
    answer = next(s for s in res.states if s.answer)
    other = next(s for s in res.states if not s.answer)
    assert answer.start == "escape" and other.start == "loading path"
    assert answer.total_force == res.total_force
    assert np.array_equal(answer.alpha, res.alpha)
    assert "2 reached" in res.summary() and "result.states" in res.retried("escaped")
    # each is a local minimum of the exact energy with the energy and force it reports:
    # SLSQP on the exact energy (reference.energy), started from its angles,
    # stays there
    chain = scene.chain()
    for state in res.states:
        assert state.energy == pytest.approx(energy(chain, state.alpha), rel=1e-12)
        ref = minimise_energy(chain, start=state.alpha)
        assert ref.success
        assert ref.energy == pytest.approx(state.energy, rel=1e-3)
        assert ref.total_force == pytest.approx(state.total_force, rel=10 * tol)
    ref_low, ref_high = (minimise_energy(chain, start=s.alpha) for s in res.states)
    assert ref_high.energy - ref_low.energy > 0.5 * (answer.energy - other.energy)


def test_one_start_reaching_one_state_lists_none():
    res = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links=40))
    assert res.converged and res.states == () and res.to_dict()["states"] == []
