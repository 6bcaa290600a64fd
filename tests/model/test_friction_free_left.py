"""A free left end (issue 39, docs/friction.md, free ends): solved as the mirror image of
a free right end. Expectations: symmetry (the mirrored scene, solved with its right end
free, gives the mirrored answer), Coulomb's law and the balance read off each node
(tests/friction_oracle.py), and the shape as the minimiser of the chain's exact energy
under the answer's tangential loads and the pull (SLSQP, written out here with node 1's
height free and node N+1 on y = 0)."""

from dataclasses import replace

import numpy as np
import pytest
from friction_oracle import coulomb_holds

import lcpbench
from lcpbench import ActuatorScene, ProblemError
from lcpbench.model.chain import joint_angles, node_positions
from lcpbench.problems.sections import SectionedScene

KW = dict(height=2.0, links=20, channel=True, friction=0.3)
STATES = [{}, {"theta": 130}, {"friction": 0.5}]


def _mirrored(a, b):
    """b is a seen from behind: per node arrays reversed, x, T and slip negated."""
    scale = max(np.max(a.forces + a.forces_lower), 1e-300)
    np.testing.assert_allclose(b.forces[::-1], a.forces, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(b.forces_lower[::-1], a.forces_lower, rtol=0,
                               atol=1e-9 * scale)
    np.testing.assert_allclose(-b.tangential_forces[::-1], a.tangential_forces, rtol=0,
                               atol=1e-9 * scale)
    np.testing.assert_allclose(b.y[::-1], a.y, rtol=0, atol=1e-9)
    shift = a.x + b.x[::-1]  # x_a = c − x_b reversed, for one c
    assert np.ptp(shift) <= 1e-9
    np.testing.assert_allclose(-b.slip[::-1], a.slip, rtol=0, atol=1e-9)


@pytest.mark.parametrize("held", ["pinned", "slider"])
@pytest.mark.parametrize("kind", ["actuator", "row"])
def test_a_free_left_end_gives_the_mirrored_answer(kind, held):
    if kind == "actuator":
        right = ActuatorScene(theta=120, left_end=held, right_end="free", **KW)
        left = replace(right, left_end="free", right_end=held)
    else:  # an unsymmetric row, and the same row in reverse order
        secs = [(120, 12.0), (60, 18.0, 20.0)]
        right = SectionedScene(sections=secs, left_end=held, right_end="free", **KW)
        left = replace(right, sections=secs[::-1], left_end="free", right_end=held)
    states = STATES if kind == "actuator" else [{}, {"theta": 130}]
    for a, b in zip(lcpbench.solve_path(right, states, tol=1e-10),
                    lcpbench.solve_path(left, states, tol=1e-10), strict=True):
        assert a.converged and b.converged, (a.reason, b.reason)
        _mirrored(a, b)
        coulomb_holds(b)
        assert abs(abs(b.y[0]) - b.scene.height) <= 1e-9  # the tip rests on a wall
        assert b.y[-1] == 0.0 or abs(b.y[-1]) <= 1e-12
        assert b.forces.size == b.scene.links  # nodes 1..N: the tip too


def _minimiser(scene, T, pull, x0, start):
    """SLSQP on the exact energy: springs, link loads at the link centres, and the loads
    T (per node 1..N) and the pull (node N+1) along x as fixed loads; node 1's height
    follows from node N+1 on y = 0; every node between the walls."""
    from scipy.optimize import minimize

    chain = scene.chain()

    def positions(alpha):
        x, y = node_positions(chain, alpha)
        return x + x0, y - y[-1]

    def total(alpha):
        x, y = positions(alpha)
        spring = 0.5 * float(np.sum(chain.joint_stiffness
                                    * (joint_angles(chain, alpha) - chain.rest_joint) ** 2))
        loads = float(chain.link_load @ (0.5 * (y[:-1] + y[1:])))
        return spring - loads - float(T @ x[:-1]) - pull * x[-1]

    walls = [{"type": "ineq", "fun": lambda a: scene.height - np.abs(positions(a)[1][:-1])}]
    res = minimize(total, start, method="SLSQP", constraints=walls,
                   options={"ftol": 1e-16, "maxiter": 3000})
    return res.x


def test_a_free_left_end_under_a_pull_is_the_energy_minimiser():
    scene = ActuatorScene(theta=120, left_end="free", right_end="slider", **KW)
    path = lcpbench.solve_path(scene, [{}, {"pull": 0.02}], tol=1e-10)
    for res in path:
        assert res.converged, res.reason
        coulomb_holds(res)
        assert abs(np.sum(res.tangential_forces) + res.pull) <= 1e-9 * res.total_force
    res = path[-1]
    placed = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                    right_end="pinned"))  # a start away from the answer
    alpha = _minimiser(scene, res.tangential_forces, 0.02, res.x[0], placed.alpha)
    np.testing.assert_allclose(alpha, res.alpha, rtol=0, atol=1e-6)


def test_the_step_itself_frees_the_right_end_only():
    from lcpbench.model.friction_driver import FrictionState, solve_state

    scene = ActuatorScene(theta=120, left_end="free", right_end="slider", **KW)
    rest = FrictionState(scene.chain().rest_alpha.copy())
    with pytest.raises(ProblemError, match="solve_path mirrors it"):
        solve_state(scene, rest, rest.positions(scene.chain())[0], tol=1e-8)
