"""Inverse queries (studies/design.py, issue 38 item 2), checked by round trips:
design, then an independent cold forward solve at the answer and 0.01° beyond it;
and the height of first touch against the rest arc's closed form."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.errors import ProblemError
from lcpbench.problems.calibrations import get_calibration
from lcpbench.studies.design import design

SCENE = ActuatorScene(theta=150, height=4.0, links=140)


@pytest.mark.parametrize("target", [0.05, 0.3])
def test_max_force_is_the_largest_angle_below_the_limit(target):
    got = design(SCENE, max_force=target)
    assert got.solves <= 10  # issue 38, target 2
    cold = lcpbench.solve(ActuatorScene(theta=got.theta_deg, height=4.0, links=140), tol=1e-10)
    assert cold.converged
    assert target * (1 - 1e-6) <= cold.total_force <= target * (1 + 1e-9)
    past = lcpbench.solve(ActuatorScene(theta=got.theta_deg + 0.01, height=4.0, links=140),
                          tol=1e-10)
    assert past.total_force > target


def test_min_force_is_the_smallest_angle_that_reaches_it():
    got = design(SCENE, min_force=0.2)
    cold = lcpbench.solve(ActuatorScene(theta=got.theta_deg, height=4.0, links=140), tol=1e-10)
    assert 0.2 * (1 - 1e-9) <= cold.total_force <= 0.2 * (1 + 1e-6)
    before = lcpbench.solve(ActuatorScene(theta=got.theta_deg - 0.01, height=4.0, links=140),
                            tol=1e-10)
    assert before.total_force < 0.2


def test_the_peak_pressure_limit_and_the_calibrated_pressure():
    cal = get_calibration(1)
    got = design(SCENE, max_force=0.05, peak=True, calibration=cal)
    assert got.pressure == pytest.approx((got.theta_deg - cal.intercept) / cal.slope, rel=1e-12)
    cold = lcpbench.solve(ActuatorScene(theta=got.theta_deg, height=4.0, links=140), tol=1e-10)
    assert 0.05 * (1 - 1e-6) <= cold.max_pressure <= 0.05 * (1 + 1e-9)


@pytest.mark.parametrize("theta,links", [(150.0, 140), (90.0, 40)])
def test_first_touch_is_the_rest_arcs_sagitta_without_weight(theta, links):
    """Without weight the rest chain's nodes lie on a circle of radius a / (2 sin(θ/2N));
    the middle node (N even) is the highest, at ρ (1 − cos(θ/2)) above the pins."""
    scene = ActuatorScene(theta=theta, height=3.0, links=links, weight=0.0)
    got = design(scene, touch=True)
    a, t = scene.length / links, math.radians(theta)
    rho = a / (2 * math.sin(t / (2 * links)))
    assert got.height_mm == pytest.approx(rho * (1 - math.cos(t / 2)), rel=1e-9)
    assert got.value == 0.0 and got.beyond > 0.0  # touching at it, pressed just below


def test_refusals_name_the_problem():
    with pytest.raises(ProblemError, match="no bend angle in"):
        design(SCENE, min_force=5.0)
    with pytest.raises(ProblemError, match="exactly one"):
        design(SCENE, max_force=0.1, touch=True)
    with pytest.raises(ProblemError, match="max_force must be"):
        design(SCENE, max_force=-1.0)


def test_the_cli_prints_the_answer_as_json_and_refuses_in_one_line():
    run = subprocess.run([sys.executable, "-m", "lcpbench.cli", "design", "--max-force", "0.05",
                          "--height", "4", "--by-pressure", "--json"], capture_output=True,
                         text=True, check=True)
    got = json.loads(run.stdout)
    assert {"theta_deg", "pressure_kpa", "total_force", "solves"} <= set(got)
    assert got["total_force"] <= 0.05
    bad = subprocess.run([sys.executable, "-m", "lcpbench.cli", "design", "--min-force", "5",
                          "--height", "4"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1
    assert "largest total force found" in bad.stderr


@pytest.mark.parametrize("query", ["max_force", "min_force"])
def test_a_limit_passed_at_the_smallest_angle_is_one_clear_error(query):
    """A wall 0.01 mm above the pins: the arc of 1° (sagitta ℓθ/8 ≈ 0.065 mm) already
    presses it, with more than 1e-9 N."""
    scene = ActuatorScene(theta=5.0, height=0.01, links=40, weight=0.0)
    with pytest.raises(ProblemError, match="already .* at the smallest bend angle searched"):
        design(scene, **{query: 1e-9})


def test_max_force_against_a_wall_profile():
    """A stenosis (a Gaussian narrowing): the answer checked by independent cold solves
    at it and 0.01° beyond, as on a flat wall."""
    import numpy as np

    from lcpbench.problems.walls import WallProfile

    wall = WallProfile.from_function(lambda x: 3.0 - 0.8 * np.exp(-((x - 14.0) / 3.0) ** 2),
                                     x_range=(-5.0, 40.0), name="stenosis")
    scene = ActuatorScene(theta=150, links=60, wall_profile=wall)
    got = design(scene, max_force=0.2)
    assert got.solves <= 10
    at = lcpbench.solve(ActuatorScene(theta=got.theta_deg, links=60, wall_profile=wall),
                        tol=1e-10)
    assert 0.2 * (1 - 1e-6) <= at.total_force <= 0.2 * (1 + 1e-9)
    past = lcpbench.solve(ActuatorScene(theta=got.theta_deg + 0.01, links=60,
                                        wall_profile=wall), tol=1e-10)
    assert past.total_force > 0.2
    with pytest.raises(ProblemError, match="touch.*flat wall"):
        design(scene, touch=True)
