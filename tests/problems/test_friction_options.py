"""The frictional options of a scene (issue 39): friction, end conditions, a pull."""

import math

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene, ProblemError


@pytest.mark.parametrize("kwargs,words", [
    (dict(friction=-0.1), "friction"),
    (dict(friction=math.nan), "friction"),
    (dict(friction=math.inf), "friction"),
    (dict(friction="0.3"), "friction"),
    (dict(friction=(0.1, 0.2)), "one per wall"),  # one wall here
    (dict(friction=(0.1, -0.2), channel=True), "friction"),
    (dict(left_end="clamped"), "left_end"),
    (dict(right_end="Slider"), "right_end"),
    (dict(pull=math.nan), "pull"),
    (dict(pull=0.1), "pull acts on the right end"),  # the right end is pinned
    (dict(pull=0.1, right_end="pinned", left_end="slider", friction=0.2), "right_end='pinned'"),
    (dict(left_end="free", right_end="free", friction=0.3), "both be 'free'"),
    (dict(left_end="slider", right_end="slider"), "nothing holds the chain along x"),
])
def test_bad_frictional_input_is_one_clear_error(kwargs, words):
    with pytest.raises(ProblemError, match=words) as info:
        ActuatorScene(**kwargs)
    assert "Traceback" not in str(info.value) and "\n" not in str(info.value)


def test_defaults_are_the_paper_model():
    scene = ActuatorScene()
    assert scene.friction == 0.0 and scene.pull == 0.0
    assert (scene.left_end, scene.right_end) == ("pinned", "pinned")
    assert not scene.frictional
    # the chain is built as before: the frictional fields do not enter it
    a = ActuatorScene(theta=120, height=4.0, links=30).chain()
    b = ActuatorScene(theta=120, height=4.0, links=30, friction=0.3).chain()
    for f in ("rest_alpha", "joint_stiffness", "link_load", "upper", "lower", "free_nodes"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))


def test_friction_per_wall():
    s = ActuatorScene(channel=True, friction=(0.1, 0.4))
    assert s.wall_friction == (0.1, 0.4) and s.frictional
    assert ActuatorScene(channel=True, friction=0.2).wall_friction == (0.2, 0.2)
    assert ActuatorScene(friction=0.2).wall_friction == (0.2, 0.0)
    assert ActuatorScene(friction=[0.3]).wall_friction == (0.3, 0.0)


def test_solve_refuses_a_frictional_scene_and_names_solve_path():
    scene = ActuatorScene(links=20, friction=0.3, right_end="slider", pull=0.01)
    with pytest.raises(ProblemError, match="solve_path"):
        lcpbench.solve(scene)


def test_friction_with_a_wall_profile_is_taken_and_a_free_end_refused():
    """Friction, sliders and a pull take a wall profile (docs/friction.md); a free end
    with one is refused in one line naming what is supported."""
    from lcpbench.problems.walls import WallProfile

    wall = WallProfile.from_table([0, 10, 20, 30], [3.0, 2.5, 2.5, 3.0])
    for kw in (dict(friction=0.3, right_end="slider"), dict(right_end="slider"),
               dict(right_end="slider", pull=0.01)):
        assert ActuatorScene(wall_profile=wall, **kw).frictional
    for kw in (dict(channel=True, friction=0.3, right_end="free"),
               dict(channel=True, friction=0.3, left_end="free")):
        with pytest.raises(ProblemError, match="free end cannot be combined with "
                                               "wall_profile") as info:
            ActuatorScene(wall_profile=wall, **kw)
        assert "\n" not in str(info.value)


def test_friction_takes_elastic_walls():
    """Elastic (Winkler) walls take friction, one μ or one per wall, in a channel too."""
    for kw in (dict(friction=0.3, right_end="slider"),
               dict(friction=(0.3, 0.1), channel=True, left_end="slider",
                    right_end="slider", pull=0.01)):
        scene = ActuatorScene(wall_stiffness=0.1, **kw)
        assert scene.frictional and scene.chain().elastic_walls


@pytest.mark.parametrize("make", [
    lambda: ActuatorScene(theta=150, height=3.0, links=40, friction=0.3, left_end="slider",
                          right_end="slider"),
    lambda: ActuatorScene(theta=180, height=2.0, links=40, channel=True, friction=(0.3, 0.1),
                          left_end="slider", right_end="slider", pull=0.02),
    lambda: lcpbench.anchoring_actuator(friction=0.2, left_end="slider", right_end="slider"),
])
def test_with_pull_is_replace_checking_the_pull_only(make):
    from dataclasses import replace

    scene = make()
    # the oracle: dataclasses.replace, which runs every check of the scene again
    for pull in (0.0, 0.05, 1.5):
        assert scene.with_pull(pull) == replace(scene, pull=pull)
        assert scene.with_pull(pull).frictional == replace(scene, pull=pull).frictional
    for bad in (math.nan, math.inf, "0.1"):
        with pytest.raises(ProblemError, match="pull") as want:
            replace(scene, pull=bad)
        with pytest.raises(ProblemError, match="pull") as got:
            scene.with_pull(bad)
        assert str(got.value) == str(want.value)
    assert scene.pull == make().pull  # the scene itself is not changed


def test_with_pull_on_a_pinned_end_is_the_same_error():
    from dataclasses import replace

    scene = ActuatorScene(friction=0.3)  # both ends pinned
    with pytest.raises(ProblemError) as want:
        replace(scene, pull=0.1)
    with pytest.raises(ProblemError) as got:
        scene.with_pull(0.1)
    assert str(got.value) == str(want.value)


def test_a_pulls_states_share_the_chain_of_their_scene():
    from lcpbench.model.friction_path import with_pull

    scene = ActuatorScene(theta=150, height=3.0, links=30, friction=0.3, left_end="slider",
                          right_end="slider")
    states = [with_pull(scene, p) for p in (0.01, 0.02, 0.03)]
    assert all(s.chain() is scene.chain() for s in states)
    # the chain a scene with that pull builds on its own has the same arrays
    fresh = ActuatorScene(theta=150, height=3.0, links=30, friction=0.3, left_end="slider",
                          right_end="slider", pull=0.02).chain()
    for name in ("free_nodes", "upper", "lower"):
        np.testing.assert_array_equal(getattr(fresh, name), getattr(states[1].chain(), name))
