"""Fitting EI to force-pressure data (studies/fit.py, issue 38 item 3): round trips
(data from a known EI, then the fit) and the refusals of bad data."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.errors import ProblemError
from lcpbench.problems.calibrations import get_calibration
from lcpbench.studies.fit import fit, read_data

CAL = get_calibration(1)
P = np.linspace(110.0, 170.0, 9)


def _forces(EI, heights=None, links=40):
    hs = np.full(P.size, 4.0) if heights is None else heights
    return np.array([lcpbench.solve(ActuatorScene(theta=float(CAL.theta(p)), height=float(h),
                                                  links=links, EI=EI), tol=1e-11).total_force
                     for p, h in zip(P, hs)])


def test_noise_free_data_give_back_the_stiffness_they_came_from():
    got = fit(ActuatorScene(theta=150, height=4.0, links=40, EI=25.0), P, _forces(40.0), CAL)
    assert got.EI == pytest.approx(40.0, rel=1e-7)
    assert np.max(np.abs(got.residuals)) <= 1e-8


def test_the_line_is_found_too_from_several_heights():
    """θ(P) and EI trade off at one height; forces at three heights separate them."""
    heights = np.tile([3.5, 4.0, 4.5], 3)
    true = get_calibration(1)
    y = _forces(40.0, heights)
    start = lcpbench.problems.calibrations.linear_calibration(true.slope * 1.03,
                                                              true.intercept - 2.0)
    got = fit(ActuatorScene(theta=150, height=4.0, links=40, EI=30.0), P, y, start,
              height=heights, fit_theta=True)
    assert got.EI == pytest.approx(40.0, rel=1e-5)
    assert got.slope == pytest.approx(true.slope, rel=1e-5)
    assert got.intercept == pytest.approx(true.intercept, abs=1e-4)


def test_the_interval_covers_the_truth_with_noise():
    rng = np.random.default_rng(7)
    covered = 0
    clean = _forces(40.0)
    for _ in range(10):
        y = clean * (1 + 0.05 * rng.standard_normal(P.size))
        got = fit(ActuatorScene(theta=150, height=4.0, links=40), P, y, CAL)
        covered += got.EI_low <= 40.0 <= got.EI_high
        assert abs(got.EI / 40.0 - 1) <= 0.08  # within 4.5 standard errors of 5 %/3
    assert covered >= 8


@pytest.mark.parametrize("text,match", [
    ("pressure_kpa,force_n\n100,0.1\n", "more points than parameters"),
    ("pressure_kpa,force_n\n100,nan\n120,0.2\n", "nan"),
    ("pressure_kpa,force_n\n100,-0.1\n120,0.2\n", "negative force"),
    ("p,f\n100,0.1\n120,0.2\n", "header pressure_kpa,force_n"),
    ("pressure_kpa,force_n\n100,abc\n", "not a number"),
])
def test_bad_data_is_one_clear_error(tmp_path, text, match):
    f = tmp_path / "d.csv"
    f.write_text(text)
    with pytest.raises(ProblemError, match=match):
        Pd, yd, hd = read_data(f)
        fit(ActuatorScene(theta=150, height=4.0, links=40), Pd, yd, CAL, height=hd)


def test_the_cli_prints_the_fit(tmp_path):
    f = tmp_path / "d.csv"
    f.write_text("pressure_kpa,force_n\n" + "".join(
        f"{p},{float(v)!r}\n" for p, v in zip(P, _forces(40.0, links=140))))
    run = subprocess.run([sys.executable, "-m", "lcpbench.cli", "fit", "--data", str(f),
                          "--height", "4", "--json"], capture_output=True, text=True, check=True)
    got = json.loads(run.stdout)
    assert got["EI"] == pytest.approx(40.0, rel=1e-6)
    assert got["EI_low"] <= 40.0 <= got["EI_high"]
    bad = subprocess.run([sys.executable, "-m", "lcpbench.cli", "fit", "--data",
                          str(tmp_path / "missing.csv")], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1


def test_without_weight_the_fit_is_the_mean_of_the_force_ratios():
    """Theory: with w = 0 the forces scale exactly with EI, F_i = EI c_i, so the fixed
    point of the reweighted fit, Σ c_i (EI c_i − y_i)/(EI c_i)² = 0, is
    EI = mean(y_i / c_i) — the efficient estimate under noise proportional to the force
    (scales read off the noisy y_i would give a different, biased weighting)."""
    P9 = np.linspace(130.0, 170.0, 9)  # every point presses well (F_i > 5 % of the largest)
    c = np.array([lcpbench.solve(ActuatorScene(theta=float(CAL.theta(p)), height=4.0,
                                               links=40, EI=1.0, weight=0.0),
                                 tol=1e-11).total_force for p in P9])
    assert np.all(c > 0.05 * c.max())
    e = np.array([0.04, -0.07, 0.02, 0.09, -0.03, -0.05, 0.06, 0.01, -0.08])
    y = 40.0 * c * (1 + e)
    got = fit(ActuatorScene(theta=150, height=4.0, links=40, weight=0.0), P9, y, CAL)
    assert got.EI == pytest.approx(40.0 * np.mean(1 + e), rel=1e-7)
