"""Boundary validation: every bad input gets one ProblemError naming the parameter."""

import math

import numpy as np
import pytest

from lcpbench import ActuatorScene, CantileverScene, ProblemError
from lcpbench.problems import scenes
from lcpbench.problems.calibrations import linear_calibration
from lcpbench.problems.checks import check_choice, check_flag, check_number
from lcpbench.problems.sections import check_scene

#: Values that are not a real number, whatever the parameter.
NOT_NUMBERS = [
    pytest.param(None, id="None"), pytest.param(True, id="True"),
    pytest.param(np.bool_(False), id="np.False_"), pytest.param("3", id="str-3"),
    pytest.param(np.array([3.0]), id="array"), pytest.param([3.0], id="list"),
    pytest.param(np.array(3.0), id="0d-array"), pytest.param(3 + 0j, id="complex"),
    pytest.param(np.complex128(3), id="np.complex"), pytest.param(math.nan, id="nan"),
    pytest.param(math.inf, id="inf"), pytest.param(-math.inf, id="-inf"),
    pytest.param({"x": 3}, id="dict"),
]


@pytest.mark.parametrize("value", NOT_NUMBERS)
def test_check_number_refuses_non_numbers(value):
    with pytest.raises(ProblemError, match=r"^speed must be a number in \[0, 10\]"):
        check_number("speed", value, low=0.0, high=10.0)


def test_check_number_accepts_numpy_scalars_and_returns_builtins():
    x = check_number("x", np.float32(2.5), low=0.0)
    assert x == 2.5 and type(x) is float
    n = check_number("n", np.int64(7), low=4, integer=True)
    assert n == 7 and type(n) is int
    assert check_number("n", 140.0, integer=True) == 140  # integral float, as from JSON


@pytest.mark.parametrize("value,ok", [(0.0, False), (1e-9, True), (10.0, True), (10.1, False)])
def test_check_number_bounds_open_and_closed(value, ok):
    if ok:
        assert check_number("x", value, low=0.0, high=10.0, low_open=True) == value
    else:
        with pytest.raises(ProblemError, match=r"x must be a number in \(0, 10\]"):
            check_number("x", value, low=0.0, high=10.0, low_open=True)


def test_message_shows_the_value_as_written_without_a_type_name():
    """Issue 40, item 7: a type name never appears in a message."""
    with pytest.raises(ProblemError) as info:
        check_number("links", True, low=4, high=100000, integer=True, alternative="'auto'")
    assert str(info.value) == ("links must be an integer in [4, 100000] or 'auto', "
                               "got True")
    with pytest.raises(ProblemError) as info:
        check_number("height", np.float64(-3.0), low=0.0, high=10.0)
    assert str(info.value).endswith("got -3.0")
    with pytest.raises(ProblemError) as info:
        check_number("height", "3", low=0.0, high=10.0)
    assert str(info.value).endswith("got '3'")


def test_check_flag_only_real_bools():
    assert check_flag("scaled", True) is True
    assert check_flag("scaled", np.bool_(False)) is False
    for bad in ("no", "False", 0, 1, None, 1.0):
        with pytest.raises(ProblemError, match="scaled must be True or False, got"):
            check_flag("scaled", bad)


def test_check_choice_compares_type_too():
    assert check_choice("profile", "high", ("low", "high")) == "high"
    with pytest.raises(ProblemError, match="profile must be one of 'low', 'high', got 1"):
        check_choice("profile", 1, ("low", "high"))
    with pytest.raises(ProblemError, match="got True"):  # True == 1 must not pass for 1
        check_choice("n", True, (1, 2))


@pytest.mark.parametrize("scene,kind", [(None, "None"), ({"theta": 150}, "{'theta': 150}"),
                                        ("ActuatorScene()", "'ActuatorScene()'"), (42, "42")])
def test_check_scene_refuses_non_scenes(scene, kind):
    with pytest.raises(ProblemError) as info:
        check_scene(scene)
    assert str(info.value) == (f"scene must be an ActuatorScene, SectionedScene or "
                               f"CantileverScene, got {kind}")


def test_check_scene_refuses_the_class_and_accepts_instances():
    with pytest.raises(ProblemError, match="an instance is needed"):
        check_scene(ActuatorScene)
    for s in (ActuatorScene(), CantileverScene()):
        assert check_scene(s) is s


# -- every field of every scene ---------------------------------------------------------
ACTUATOR_FIELDS = ("theta", "height", "links", "length", "EI", "weight")
CANTILEVER_FIELDS = ("load", "height", "links", "length", "EI")


@pytest.mark.parametrize("value", NOT_NUMBERS)
@pytest.mark.parametrize("field", ACTUATOR_FIELDS)
def test_actuator_fields_refuse_non_numbers(field, value):
    with pytest.raises(ProblemError, match=rf"^{field} must be an? "):
        ActuatorScene(**{field: value})


@pytest.mark.parametrize("value", NOT_NUMBERS)
@pytest.mark.parametrize("field", CANTILEVER_FIELDS)
def test_cantilever_fields_refuse_non_numbers(field, value):
    with pytest.raises(ProblemError, match=rf"^{field} must be an? "):
        CantileverScene(**{field: value})


@pytest.mark.parametrize("value", [None, np.array([140]), 140 + 0j, True, "3", "AUTO", 3.5])
def test_links_refused_with_what_is_allowed(value):
    with pytest.raises(ProblemError, match=r"links must be an integer in \[4, 100000\] or "
                                           r"'auto', got "):
        ActuatorScene(links=value)


@pytest.mark.parametrize("value", [1e300, 1e-300, 1e-4, 2e5])
def test_length_out_of_range(value):
    with pytest.raises(ProblemError, match=r"length must be a number in \[0.001, 100000\] mm"):
        ActuatorScene(length=value)


@pytest.mark.parametrize("field,value", [("height", 1e-300), ("height", 1e300), ("EI", 1e-300),
                                         ("EI", 1e300), ("weight", 1e300), ("theta", 1e300)])
def test_extreme_values_refused(field, value):
    with pytest.raises(ProblemError, match=f"^{field} must be"):
        ActuatorScene(**{field: value})


@pytest.mark.parametrize("value", ["no", 0, 1, None, "True"])
def test_channel_must_be_a_real_bool(value):
    with pytest.raises(ProblemError, match="channel must be True or False"):
        ActuatorScene(channel=value)


def test_range_ends_are_valid_scenes():
    lo = ActuatorScene(length=scenes.LENGTH_RANGE[0], height=scenes.HEIGHT_RANGE[0],
                       EI=scenes.EI_RANGE[0], weight=0.0, links=scenes.MIN_LINKS)
    hi = ActuatorScene(length=scenes.LENGTH_RANGE[1], height=scenes.HEIGHT_RANGE[1],
                       EI=scenes.EI_RANGE[1], weight=scenes.WEIGHT_RANGE[1],
                       links=scenes.MAX_LINKS)
    assert lo.links == 4 and hi.links == 100_000 and hi.length == 1e5


def test_numpy_and_integral_values_are_normalised():
    s = ActuatorScene(theta=np.float64(150), links=np.int32(140), channel=np.bool_(True))
    assert type(s.theta) is float and type(s.links) is int and s.channel is True
    assert ActuatorScene(links=140.0).links == 140


def test_every_benchmark_scene_is_valid():
    """The paper grid and the hard suite build without error (ranges cover them)."""
    from lcpbench.bench.grid import PAPER_GRID, hard_scenes

    assert len(PAPER_GRID.scenes()) > 0
    assert len(hard_scenes()) > 0


def test_calibration_refuses_bools_and_strings():
    with pytest.raises(ProblemError, match="slope must be a number"):
        linear_calibration(True, 10.0)
    with pytest.raises(ProblemError, match="EI must be a number in"):
        linear_calibration(1.0, 10.0, EI="32")
    with pytest.raises(ProblemError, match="p_max must be a number"):
        linear_calibration(1.0, 10.0, p_max=True)
    cal = linear_calibration(1.0, 10.0)
    assert cal.p_max == math.inf
    for bad in (True, "100", 1j, None):
        with pytest.raises(ProblemError, match="pressure must be a finite number"):
            cal.theta(bad)


# Plain floats (the values most scenes are built from) just outside each range, and
# every other form a field may take: refused with the message of the field, as any
# other bad value (a scene of plain floats in range is checked in a few comparisons).
PLAIN_OUT_OF_RANGE = [
    ("theta", 0.0), ("theta", 360.0), ("theta", -1e-300), ("theta", math.nan),
    ("height", 0.0), ("height", 1.0000001e6), ("height", math.inf),
    ("length", 9.99e-4), ("length", 1.0000001e5), ("EI", 9.99e-7), ("EI", 1.0000001e9),
    ("weight", -5e-324), ("weight", 1000.0001), ("weight", -math.inf),
    ("wall_stiffness", 0.0), ("wall_stiffness", -1.0), ("wall_stiffness", math.nan),
    ("wall_stiffness", -math.inf), ("wall_stiffness", 1.0000001e12),
    ("links", 3), ("links", 100_001), ("friction", -1e-9), ("friction", math.nan),
    ("pull", math.nan), ("left_end", "Pinned"), ("right_end", "pinned ")]


@pytest.mark.parametrize("field,value", PLAIN_OUT_OF_RANGE)
def test_plain_floats_out_of_range_are_refused(field, value):
    with pytest.raises(ProblemError, match=f"^{field} must be"):
        ActuatorScene(**{field: value})


@pytest.mark.parametrize("field,value", [
    ("theta", -360.0), ("theta", 360.0), ("length", 0.0), ("EI", 2e9), ("weight", -1e-9),
    ("theta", math.nan), ("length", math.inf)])
def test_plain_section_floats_out_of_range_are_refused(field, value):
    from lcpbench.problems.sections import Section, SectionedScene

    with pytest.raises(ProblemError, match=rf"^section\.{field} must be"):
        Section(**{"theta": 30.0, field: value})
    with pytest.raises(ProblemError, match=rf"^sections\[1\]\.{field} must be"):
        SectionedScene(sections=[(30.0, 15.0), {"theta": 30.0, field: value}])


def test_the_frictional_defaults_in_any_form_are_the_papers():
    """0 (an int), a numpy zero, a one-element tuple per wall: checked and normalised to
    the paper's options, as the defaults themselves."""
    for kw in (dict(friction=0), dict(friction=np.float64(0.0), pull=0),
               dict(friction=(0.0,)), dict(friction=-0.0, pull=-0.0)):
        s = ActuatorScene(**kw)
        assert not s.frictional and s.wall_friction == (0.0, 0.0), kw
        assert type(s.pull) is float and type(s.friction) in (float, tuple)
    with pytest.raises(ProblemError, match="pull acts on the right end"):
        ActuatorScene(pull=1.0)
