"""The lean Python around the kernels (issue 19): what is kept, skipped or computed
late gives what the full computation gives.

- ContactResult's derived fields (x, y, gaps, indentation, pressure), computed at
  their first access, equal the same quantities from the definitions (forward
  kinematics summed link by link, h − y, R over the node's share of wall);
- a scene keeps its Chain, which equals a freshly built one and is not pickled;
- the scenes' ``consecutive`` flag agrees with the array test of the layout;
- the cheap test that skips the wall-free search is sufficient: whenever it says
  so, the arc crosses the wall by more than the search's bound;
- a batch line whose scenes differ in their walls (rigid and elastic) gives the
  results of one solve per scene.
"""

import dataclasses
import math
import pickle

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import ActuatorScene, CantileverScene
from lcpbench.api import solve_internal
from lcpbench.model.chain import node_positions
from lcpbench.model.kernel_call import _layout
from lcpbench.model.result import DERIVED
from lcpbench.model.wall_free import arc_far
from lcpbench.problems.sections import Section, SectionedScene
from lcpbench.thresholds import SAG_BOUND


def _positions(alpha, a):
    """Node coordinates by summing the links one by one (math.fsum)."""
    x = [math.fsum(a * math.cos(t) for t in alpha[:k]) for k in range(alpha.size + 1)]
    y = [math.fsum(a * math.sin(t) for t in alpha[:k]) for k in range(alpha.size + 1)]
    return np.array(x), np.array(y)


SCENES = [
    ActuatorScene(theta=150, height=3.0, links=40),
    ActuatorScene(theta=170, height=2.5, links=30, channel=True),
    ActuatorScene(theta=150, height=3.0, links=30, wall_stiffness=0.5),
    ActuatorScene(theta=40, height=6.0, links=30),  # touches no wall
]


@pytest.mark.parametrize("scene", SCENES, ids=["contact", "channel", "elastic", "free"])
@pytest.mark.parametrize("solver", ["auto", "lemke"])  # the lean result and a full one
def test_derived_fields_equal_their_definitions(scene, solver):
    res = solve_internal(scene, solver=solver)
    assert res.converged
    a = scene.length / scene.links
    x, y = _positions(res.alpha, a)
    assert np.allclose(res.x, x, rtol=0, atol=1e-12 * scene.length)
    assert np.allclose(res.y, y, rtol=0, atol=1e-12 * scene.length)
    yf = y[1:-1]  # the actuator's free nodes 2..N
    h = scene.height
    assert np.allclose(res.gaps, h - yf, rtol=0, atol=1e-12 * scene.length)
    if scene.channel:
        assert np.allclose(res.gaps_lower, yf + h, rtol=0, atol=1e-12 * scene.length)
    else:
        assert res.gaps_lower is None
    # an interior node's share of wall is one link a; p = (R₊ + R_lower₊) / a
    total = np.maximum(res.forces, 0) + (np.maximum(res.forces_lower, 0)
                                         if res.forces_lower is not None else 0)
    assert np.allclose(res.pressure, total / a, rtol=1e-14, atol=0)
    if math.isinf(scene.wall_stiffness):
        assert np.all(res.indentation == 0)
    else:  # the node pushes into the elastic wall by y − h where it is past it
        assert np.allclose(res.indentation, np.maximum(yf - h, 0), rtol=0, atol=1e-12)
        assert res.max_indentation > 0
    assert res.max_pressure == pytest.approx(float(np.max(total / a, initial=0)), rel=1e-14)


def test_derived_fields_are_computed_once_and_a_field_set_by_hand_stays():
    res = lcpbench.solve(ActuatorScene(theta=150, height=3.0, links=30))
    mine = np.arange(31.0)
    res.y = mine  # set before the derived fields are computed
    assert res.x is res.x  # computed once, then kept
    assert res.y is mine
    x, _ = node_positions(ActuatorScene(theta=150, height=3.0, links=30).chain(), res.alpha)
    assert np.array_equal(res.x, x)


def test_a_result_pickles_copies_and_serialises_with_its_derived_fields():
    scene = ActuatorScene(theta=150, height=3.0, links=30)
    lazy = lcpbench.solve(scene)
    eager = lcpbench.solve(scene)
    for name in DERIVED:  # one result with every field computed
        getattr(eager, name)
    back = pickle.loads(pickle.dumps(lazy))
    copy = dataclasses.replace(lcpbench.solve(scene))
    for other in (back, copy):
        for name in DERIVED:
            a, b = getattr(eager, name), getattr(other, name)
            assert (a is None and b is None) or np.array_equal(a, b), name
    assert lcpbench.solve(scene).to_dict()["pressure"] == eager.to_dict()["pressure"]


def test_a_scene_keeps_its_chain_which_equals_a_fresh_one():
    scene = ActuatorScene(theta=123.0, height=2.2, links=57, channel=True)
    chain = scene.chain()
    assert scene.chain() is chain
    again = pickle.loads(pickle.dumps(scene))
    assert again == scene and "_chain" not in again.__dict__
    fresh = again.chain()
    assert fresh is not chain
    for f in dataclasses.fields(chain):
        a, b = getattr(chain, f.name), getattr(fresh, f.name)
        assert np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b, f.name
    # the rest angles are the arc's, eq. (2): α_k = θ/2 − (k + ½) θ/N
    th = math.radians(123.0)
    expected = np.array([th / 2 - (k + 0.5) * th / 57 for k in range(57)])
    assert np.allclose(chain.rest_alpha, expected, rtol=0, atol=1e-15)


@pytest.mark.parametrize("scene", [
    ActuatorScene(theta=150, height=3.0, links=12),
    ActuatorScene(theta=300, height=3.0, links=9, channel=True),
    CantileverScene(load=0.01, height=1.0, links=10),
    SectionedScene(sections=(Section(theta=90, length=10), Section(theta=40, length=20)),
                   height=3.0, links=30),
], ids=["actuator", "channel", "cantilever", "sections"])
def test_the_scenes_consecutive_flag_agrees_with_the_array_test(scene):
    chain = scene.chain()
    assert chain.consecutive is True
    assert _layout(dataclasses.replace(chain, consecutive=None)) is True


def test_the_array_test_refuses_a_chain_that_is_not_consecutive():
    chain = dataclasses.replace(ActuatorScene(links=10).chain(), consecutive=None)
    shuffled = dataclasses.replace(chain, joint_links=chain.joint_links[::-1].copy())
    assert _layout(shuffled) is False


@pytest.mark.parametrize("weight", [0.0, 2e-5, 2.45e-4])
def test_the_cheap_wall_free_test_is_sufficient(weight):
    """Where the one-node test says the search finds nothing, the whole arc crosses a
    wall by more than the load could sag it: 5 w ℓ⁴ / (384 EI) (beam theory) times
    SAG_BOUND, from the node heights summed here."""
    said = 0
    for theta in range(10, 360, 25):
        for h in (0.3, 1.0, 2.0, 3.5, 5.0, 7.0, 12.0):
            for links in (5, 8, 33):
                chain = ActuatorScene(theta=theta, height=h, links=links, weight=weight,
                                      channel=theta % 2 == 0).chain()
                if not arc_far(chain):
                    continue
                said += 1
                u = _positions(chain.rest_alpha, chain.link_length)[1][chain.free_nodes]
                overlap = max(np.max(u - chain.upper), np.max(chain.lower - u))
                w = math.fsum(abs(x) for x in chain.link_load)
                EI = chain.force_scale * chain.length**2
                sag = 5.0 * w * chain.length**3 / (384.0 * EI)
                assert overlap > SAG_BOUND * sag and overlap >= 0, (theta, h, links)
    assert said > 20  # the test does say something on this grid


def test_a_batch_line_with_rigid_and_elastic_walls_gives_each_scenes_solve():
    scenes = [ActuatorScene(theta=t, height=3.0, links=30, wall_stiffness=k)
              for t, k in ((140, math.inf), (150, 0.5), (160, math.inf), (170, 0.5))]
    many = lcpbench.solve_many(scenes, tol=1e-8)
    for scene, res in zip(scenes, many, strict=True):
        one = lcpbench.solve(scene, tol=1e-8)
        assert res.converged and one.converged
        assert res.engine == one.engine
        assert res.total_force == pytest.approx(one.total_force, rel=1e-7, abs=1e-12)
        assert_solved(res)  # the equilibrium, rigid or Winkler (tests/energy_oracle.py)
