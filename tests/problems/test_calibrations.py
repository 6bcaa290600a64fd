"""Pressure → bend-angle calibrations of the paper (eqs. 40–42) and of users."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lcpbench import ActuatorScene, ProblemError
from lcpbench.problems.calibrations import (
    CALIBRATIONS,
    KPA_PER_PSI,
    Calibration,
    get_calibration,
    linear_calibration,
    scene_from_pressure,
)

# Hand arithmetic from the printed coefficients (θ in degrees, P in kPa), Sec. V-B:
#   (40) θ1 = 0.81 P + 9.78:  P = 50     -> 40.5 + 9.78 = 50.28
#                             P = 172.37 -> 0.81 * 172.37 = 137.896 + 1.7237 = 139.6197;
#                                           + 9.78 = 149.3997
#   (41) θ2 = 0.52 P + 7.84:  P = 50     -> 26.0 + 7.84 = 33.84
#                             P = 172.37 -> 0.52 * 172.37 = 86.185 + 3.4474 = 89.6324;
#                                           + 7.84 = 97.4724
#   (42) θ3 = 0.65 P + 12.1:  P = 50     -> 32.5 + 12.1 = 44.6
#                             P = 172.37 -> 0.65 * 172.37 = 86.185 + 25.8555 = 112.0405;
#                                           + 12.1 = 124.1405
HAND = {
    "1": {50.0: 50.28, 172.37: 149.3997},
    "2": {50.0: 33.84, 172.37: 97.4724},
    "3": {50.0: 44.6, 172.37: 124.1405},
}


@pytest.mark.parametrize("name", ["1", "2", "3"])
def test_paper_equations_at_two_pressures(name):
    cal = get_calibration(name)
    for pressure, theta in HAND[name].items():
        assert cal.theta(pressure) == pytest.approx(theta, abs=1e-12)


def test_paper_metadata():
    assert set(CALIBRATIONS) == {"1", "2", "3"}
    for name, eq in zip("123", (40, 41, 42)):
        cal = CALIBRATIONS[name]
        assert cal.name == name and f"({eq})" in cal.source
        assert cal.pressure_unit == "kPa"
        assert (cal.p_min, cal.p_max) == (0.0, 172.37)  # 0-25 psi, Sec. IV-C
        assert cal.EI == 32.01 and cal.weight == 2.45e-4  # Sec. IV-B
        assert cal.EI_range == (15.18, 41.80) and cal.weight_range == (2.37e-4, 2.47e-4)
    # the paper's kPa figures are its psi figures converted: 25 psi, 2.5 psi
    assert 25 * KPA_PER_PSI == pytest.approx(172.37, abs=5e-3)
    assert 2.5 * KPA_PER_PSI == pytest.approx(17.24, abs=5e-3)


def test_get_calibration_accepts_int_and_lists_names_on_error():
    assert get_calibration(2) is CALIBRATIONS["2"]
    with pytest.raises(ProblemError, match=r"name must be one of '1', '2', '3'"):
        get_calibration("4")
    for bad in (0, True, None, 1.0):
        with pytest.raises(ProblemError, match="name"):
            get_calibration(bad)


@pytest.mark.parametrize("name", ["1", "2", "3"])
@given(p=st.floats(0.0, 172.37))
def test_inverse_round_trip(name, p):
    cal = CALIBRATIONS[name]
    assert cal.pressure(cal.theta(p)) == pytest.approx(p, abs=1e-9)


@given(
    slope=st.floats(0.05, 5.0) | st.floats(-5.0, -0.05),
    intercept=st.floats(-50.0, 50.0),
    theta=st.floats(1.0, 359.0),
)
def test_inverse_round_trip_user_fit(slope, intercept, theta):
    cal = linear_calibration(slope, intercept)
    assert cal.theta(cal.pressure(theta)) == pytest.approx(theta, abs=1e-9)


@pytest.mark.parametrize("name", ["1", "2", "3"])
@given(p=st.floats(0.0, 172.37), q=st.floats(0.0, 172.37))
def test_theta_increases_with_pressure(name, p, q):
    cal = CALIBRATIONS[name]
    if p <= q:
        assert cal.theta(p) <= cal.theta(q)  # round-off can tie nearly equal pressures
    if q - p > 1e-9:
        assert cal.theta(p) < cal.theta(q)


def test_arrays():
    cal = CALIBRATIONS["1"]
    p = np.linspace(0, 172.37, 11)
    theta = cal.theta(p)
    assert isinstance(theta, np.ndarray) and np.all(np.diff(theta) > 0)
    assert np.allclose(cal.pressure(theta), p)
    assert isinstance(cal.theta(100), float)
    assert cal.theta_range == (9.78, pytest.approx(149.3997))


@pytest.mark.parametrize("pressure", [-1.0, 172.38, 500, math.nan, math.inf, "100", None,
                                      [10.0, 200.0], []])
def test_pressure_outside_the_fit_is_refused(pressure):
    with pytest.raises(ProblemError, match="pressure"):
        CALIBRATIONS["1"].theta(pressure)


def test_pressure_giving_theta_outside_0_360_is_refused():
    cal = linear_calibration(2.0, 10.0)
    assert cal.theta(100) == 210.0
    with pytest.raises(ProblemError, match=r"pressure 200 kPa gives theta = 410"):
        cal.theta(200)
    with pytest.raises(ProblemError, match="pressure"):
        cal.theta(-5)  # theta = 0


@pytest.mark.parametrize("theta", [0.0, 360.0, -5, math.nan, "90", 5.0, 150.0])
def test_theta_outside_the_fit_is_refused(theta):
    # actuator 1 reaches 9.78 .. 149.3997 degrees over 0 .. 172.37 kPa
    with pytest.raises(ProblemError, match="theta"):
        CALIBRATIONS["1"].pressure(theta)


@pytest.mark.parametrize(
    "kwargs,name",
    [
        ({"slope": 0.0}, "slope"), ({"slope": math.nan}, "slope"),
        ({"intercept": math.inf}, "intercept"), ({"p_min": 5, "p_max": 5}, "p_min"),
        ({"p_min": math.nan}, "p_min"), ({"EI": 0}, "EI"), ({"weight": -1e-4}, "weight"),
        ({"EI_range": (40, 50)}, "EI_range"), ({"EI_range": 3}, "EI_range"),
        ({"weight_range": (0, 1e-4)}, "weight_range"), ({"pressure_unit": ""}, "pressure_unit"),
        ({"name": ""}, "name"),
    ],
)
def test_bad_user_calibration_names_the_parameter(kwargs, name):
    args = {"slope": 0.8, "intercept": 10.0, **kwargs}
    with pytest.raises(ProblemError, match=name):
        linear_calibration(**args)


def test_calibration_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        CALIBRATIONS["1"].slope = 1.0
    assert isinstance(CALIBRATIONS["1"], Calibration)


def test_scene_from_pressure():
    scene = scene_from_pressure(137.9, "1", height=5.5, channel=True, links=50)
    assert isinstance(scene, ActuatorScene)
    assert scene.theta == pytest.approx(0.81 * 137.9 + 9.78)  # 111.699 + 9.78 = 121.479
    assert (scene.height, scene.channel, scene.links) == (5.5, True, 50)
    assert (scene.EI, scene.weight) == (32.01, 2.45e-4)
    # EI and weight can be overridden, e.g. by the paper's min/max (Sec. V-E)
    stiff = scene_from_pressure(100, 3, EI=41.80, weight=2.47e-4)
    assert (stiff.EI, stiff.weight, stiff.theta) == (41.80, 2.47e-4, pytest.approx(77.1))
    own = linear_calibration(1.2, 5.0, EI=20.0, weight=1e-4, p_min=0, p_max=100)
    scene = scene_from_pressure(50, own, height=2.0)
    assert (scene.theta, scene.EI, scene.weight) == (65.0, 20.0, 1e-4)


@pytest.mark.parametrize(
    "args,kwargs,name",
    [
        ((100, "x"), {}, "actuator"), ((100, 4), {}, "actuator"),
        ((200, "1"), {}, "pressure"), ((100, "1"), {"theta": 90}, "theta"),
        ((100, "1"), {"height": 0}, "height"), ((100, "1"), {"EI": -1}, "EI"),
    ],
)
def test_scene_from_pressure_errors(args, kwargs, name):
    with pytest.raises(ProblemError, match=name):
        scene_from_pressure(*args, **kwargs)
