"""Issue 6, target 6: a scene that touches no wall is answered without any LCP.

The unconstrained shape of a loaded chain is the equilibrium of the chain
without walls (banded solves only); when it clears every wall it is the
answer. Checked against the exact energy minimiser with the walls in place
(SLSQP, an independent method), and by a step solver that fails the test if
the driver ever calls it.
"""

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
import lcpbench.api as api
from lcpbench import ActuatorScene
from lcpbench.problems.walls import WallProfile
from lcpbench.reference.energy import minimise_energy


@pytest.fixture
def no_lcp(monkeypatch):
    """Any contact step handed to a back-end fails the test."""
    real = api.make_step_solver

    def guarded(solver, settings, scaled, *form):
        real(solver, settings, scaled, *form)  # still validates the names

        def step(*_):
            raise AssertionError("a contact step (LCP) was solved")

        return step

    monkeypatch.setattr(api, "make_step_solver", guarded)


CLEAR = [
    pytest.param({"theta": 40, "height": 3, "links": 40}, id="arc-clears-gravity-on"),
    pytest.param({"theta": 30, "height": 3, "links": 40, "channel": True, "weight": 1e-3},
                 id="channel-clears"),
    # the arc crosses the wall at h = 3 mm, the heavy chain sags below it
    pytest.param({"theta": 150, "height": 3, "links": 40, "weight": 0.05}, id="heavy-sags-off"),
    # a wall profile (a stenosis at x = 14 mm): the search runs on the chain without walls
    pytest.param({"theta": 30, "height": 3, "links": 40, "wall_profile": WallProfile.from_table(
        [0, 10, 14, 18, 30], [3.0, 3.0, 2.4, 3.0, 3.0])}, id="profile-clears"),
    pytest.param({"theta": 150, "height": 3, "links": 40, "weight": 0.05,
                  "wall_profile": WallProfile.from_table([0, 10, 14, 18, 30],
                                                         [3.0, 3.0, 2.6, 3.0, 3.0])},
                 id="heavy-sags-off-a-profile"),
]


@pytest.mark.parametrize("kwargs", CLEAR)
def test_clearing_scene_needs_no_lcp_and_is_the_energy_minimiser(kwargs, no_lcp):
    scene = ActuatorScene(**kwargs)
    res = lcpbench.solve(scene, solver="lemke", tol=1e-10)
    assert res.converged, res.reason
    assert res.reason.startswith("no contact")
    assert res.total_force == 0 and res.inner_iterations == 0
    assert res.certificate.min_gap > 0
    ref = minimise_energy(scene)  # with its walls: no wall is active there either
    assert ref.success, ref.message
    assert ref.total_force == 0
    assert np.max(np.abs(res.alpha - ref.alpha)) < 1e-7
    assert np.allclose(res.y, ref.y, atol=1e-8 * scene.length)


def test_a_scene_that_touches_is_still_solved_with_its_walls():
    scene = ActuatorScene(theta=150, height=3, links=40)  # the paper's scene: contact
    res = lcpbench.solve(scene, solver="active-set", tol=1e-10)
    assert res.converged and res.total_force > 0
    assert not res.reason.startswith("no contact")
    assert res.inner_iterations > 0


def test_every_back_end_gives_the_same_clearing_answer():
    """No LCP is solved, so back-ends that fail on contact (PGS at N = 140) agree exactly."""
    scene = ActuatorScene(theta=30, height=5)
    a = lcpbench.solve(scene, solver="active-set")
    b = lcpbench.solve(scene, solver="pgs")
    assert a.converged and b.converged
    assert np.array_equal(a.alpha, b.alpha)
    assert_solved(b)  # the free equilibrium, clear of the walls (tests/energy_oracle.py)


def test_chain_that_cannot_hang_is_not_answered_by_the_free_path():
    """4000x the paper's weight: no wall-free equilibrium on the branch of the height
    steps (links pass the vertical); the steps in the link angles answer it (issue 19,
    target 8; tests/model/test_heavy_chains.py checks them against the energy minimum)."""
    res = lcpbench.solve(ActuatorScene(theta=150, height=3, links=100, weight=1.0), tol=1e-9)
    assert res.converged and res.total_force == 0
    assert "link angles" in res.reason and "banded solves" not in res.reason


@pytest.mark.parametrize("theta,height", [(60, 4.0), (90, 6.0)])
def test_a_loaded_clearing_chain_at_large_n_is_accepted(theta, height):
    # at N >= LARGE_N the wall-free search's banded solves in heights carry round-off
    # of ~1e-4 F₀ per node (cond ~ N⁴), which the judge rejected at tol 1e-3; the
    # increment driver answers instead. Checked against the wall-free answer at
    # N = 3000 (the compiled banded search, an independent path): the same clearance
    # up to the O(N⁻²) discretisation error, and no force
    big = lcpbench.solve(ActuatorScene(theta, height, links=10_000), tol=1e-3)
    small = lcpbench.solve(ActuatorScene(theta, height, links=3000), tol=1e-3)
    assert small.converged and "no contact" in small.reason
    assert big.converged, big.reason
    assert abs(big.total_force) <= 1e-9 * big.judgement.force_unit
    assert abs(float(np.min(big.gaps)) - float(np.min(small.gaps))) <= 1e-5
