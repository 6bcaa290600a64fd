"""Scenes of any section layout (issue 17, item 1): the chain they build and their checks."""

import math
from dataclasses import fields

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import ActuatorScene, ProblemError
from lcpbench.api import solve_internal
from lcpbench.model.chain import joint_angles, node_positions
from lcpbench.problems.sections import Section, SectionedScene, anchoring_actuator

ONE_SECTION = [
    {"theta": 150.0, "height": 3.0},
    {"theta": 150.0, "height": 3.0, "channel": True},
    {"theta": 97.3, "height": 2.1, "links": 33, "EI": 12.0, "weight": 0.01, "length": 41.3},
    {"theta": 40.0, "height": 1.0, "links": 30, "channel": True, "weight": 0.05},
    {"theta": 180.0, "height": 1.0, "links": 57},
]


def _one_section(kw: dict) -> SectionedScene:
    a = ActuatorScene(**kw)
    return SectionedScene(sections=[Section(a.theta, a.length, a.EI, a.weight)],
                          height=a.height, links=a.links, channel=a.channel)


@pytest.mark.parametrize("kw", ONE_SECTION)
def test_one_section_builds_the_actuator_scenes_chain_exactly(kw):
    expected, got = ActuatorScene(**kw).chain(), _one_section(kw).chain()
    for f in fields(expected):
        a, b = getattr(expected, f.name), getattr(got, f.name)
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and np.array_equal(a, b), f.name
        else:
            assert a == b, f.name


@pytest.mark.parametrize("kw", ONE_SECTION[:4])
@pytest.mark.parametrize("solver", ["auto", "lemke"])  # the kernel; the compiled driver
def test_one_section_solves_exactly_as_the_actuator_scene(kw, solver):
    """One section builds the actuator's chain (above), so it is solved bit for bit as
    the actuator (kept: a promise of the construction) and to the scene's equilibrium."""
    a = solve_internal(ActuatorScene(**kw), solver=solver)
    b = solve_internal(_one_section(kw), solver=solver)
    assert a.converged and b.converged
    assert a.total_force == b.total_force
    for name in ("alpha", "x", "y", "forces", "gaps"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.engine == b.engine
    assert_solved(b)  # (tests/energy_oracle.py)


def test_rest_shape_is_the_joined_arcs_with_level_chord():
    """Property: every section is an arc of its own θ; tangents join; both pins on y = 0."""
    scene = SectionedScene(sections=[(120, 20), (-60, 10, 50.0), (30, 30, 5.0, 0.0)],
                           height=50.0, links=60)
    chain = scene.chain()
    x, y = node_positions(chain, chain.rest_alpha)
    assert abs(y[-1]) < 1e-12 * scene.length and x[-1] > 0
    counts = scene.section_links()
    assert counts.tolist() == [20, 10, 30]
    turns = np.diff(chain.rest_alpha)  # the rest joint angles are the turns of the rest shape
    assert np.allclose(turns, chain.rest_joint, atol=1e-14)
    assert np.allclose(joint_angles(chain, chain.rest_alpha), chain.rest_joint, atol=1e-14)
    # each section turns by -θ_k over its links (θ > 0 bends toward +y: clockwise)
    ends = np.concatenate(([0], np.cumsum(counts)))
    for k, sec in enumerate(scene.sections):
        inside = chain.rest_alpha[ends[k + 1] - 1] - chain.rest_alpha[ends[k]]
        per_link = math.radians(sec.theta) / counts[k]
        assert inside == pytest.approx(-per_link * (counts[k] - 1), abs=1e-13)


def test_boundary_joint_is_the_two_half_links_in_series():
    a = 1.0
    scene = SectionedScene(sections=[(30, 10, 10.0), (-45, 10, 40.0)], height=5, links=20)
    chain = scene.chain()
    assert chain.link_length == a
    assert chain.joint_stiffness[8] == pytest.approx(10.0 / a)
    assert chain.joint_stiffness[10] == pytest.approx(40.0 / a)
    # 1/k = (a/2)/EI1 + (a/2)/EI2
    assert chain.joint_stiffness[9] == pytest.approx(1.0 / (0.5 * a / 10.0 + 0.5 * a / 40.0))
    assert chain.rest_joint[9] == pytest.approx(-(math.radians(30) / 20 + math.radians(-45) / 20))


def test_weights_and_gravity_direction():
    secs = [(60, 10, 32.0, 1e-3), (60, 20, 32.0, 2e-3)]
    down = SectionedScene(sections=secs, height=5, links=30).chain()
    up = SectionedScene(sections=secs, height=5, links=30, gravity="+y").chain()
    assert np.allclose(down.link_load[:10], -1e-3) and np.allclose(down.link_load[10:], -2e-3)
    assert np.array_equal(up.link_load, -down.link_load)


def test_anchoring_actuator_is_three_alternating_sections_in_a_channel():
    scene = anchoring_actuator(150.0, 5.5)
    assert [s.theta for s in scene.sections] == [-150.0, 150.0, -150.0]
    assert scene.length == 90.0 and scene.links == 420 and scene.channel
    chain = scene.chain()
    x, y = node_positions(chain, chain.rest_alpha)
    nodes = scene.section_nodes()
    assert nodes == [(0, 140), (140, 280), (280, 420)]
    # symmetric layout: the section boundaries lie on the pin line; middle up, ends down
    assert np.allclose(y[[0, 140, 280, 420]], 0.0, atol=1e-12)
    assert y[210] > 0 and y[70] < 0 and y[350] < 0
    assert y[210] == pytest.approx(-y[70], rel=1e-12)


@pytest.mark.parametrize("kwargs,needle", [
    ({"sections": []}, "sections must list at least one section"),
    ({"sections": None}, "sections must be a list"),
    ({"sections": Section(30)}, "sections must be a list"),
    ({"sections": [(30, -1.0)]}, "sections[0].length"),
    ({"sections": [(30, 10), (30, math.nan)]}, "sections[1].length"),
    ({"sections": [(30, 10), (math.inf, 10)]}, "sections[1].theta"),
    ({"sections": [(400, 10)]}, "sections[0].theta"),
    ({"sections": [(30, 10, -5.0)]}, "sections[0].EI"),
    ({"sections": [(30, 10, 5.0, -1.0)]}, "sections[0].weight"),
    ({"sections": [{"theta": 30, "lenght": 5}]}, "sections[0] must have"),
    ({"sections": ["30:10"]}, "sections[0] must be a Section"),
    ({"sections": [(30, 10), (30, 20)], "length": 40.0}, "length: the sections add up to 30"),
    ({"sections": [(30, 10), (30, 20)], "links": 20}, "links: N = 20 does not put"),
    ({"sections": [(30, 10)], "links": 3}, "links must be an integer"),
    ({"sections": [(180, 10), (180, 10)]}, "closes on itself"),
    ({"sections": [(30, 10)], "height": -1.0}, "height must be"),
    ({"sections": [(30, 10)], "channel": "yes"}, "channel must be True or False"),
    ({"sections": [(30, 10)], "gravity": "down"}, "gravity must be one of"),
])
def test_bad_input_is_one_problem_error_naming_the_parameter(kwargs, needle):
    with pytest.raises(ProblemError) as info:
        SectionedScene(**kwargs)
    assert needle in str(info.value)


def test_links_error_names_the_nearest_that_fit():
    with pytest.raises(ProblemError, match=r"N = 99 or 102"):
        SectionedScene(sections=[(30, 10), (30, 10), (30, 10)], links=100)
    # the given total length is accepted when the sections add up
    assert SectionedScene(sections=[(30, 10), (30, 20)], length=30.0, links=30).length == 30.0


def test_anchoring_actuator_checks_theta_and_links():
    with pytest.raises(ProblemError, match="theta must be"):
        anchoring_actuator(-10.0)
    with pytest.raises(ProblemError, match="links: N = 100"):
        anchoring_actuator(150.0, links=100)


def test_summary_names_the_sections_not_one_theta():
    res = lcpbench.solve(anchoring_actuator(120.0, 5.5, links=60, gravity="+y"))
    line = res.summary().splitlines()[1]
    assert "sections -120:30,120:30,-120:30" in line and "weight toward" in line
    assert "θ = " not in line
