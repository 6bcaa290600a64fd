"""θ against pressure (eqs. 40-42): the fit and its uncertainty against scipy's
independent linear regression and against the line the data were drawn from."""

import numpy as np
import pytest
from scipy import stats

from lcpbench.vision.calibrate import (
    fit_theta_pressure,
    parse_pressures,
    read_pressure_csv,
)
from lcpbench.vision.errors import VisionError


def test_exact_line_is_recovered():
    p = np.array([0.0, 20, 40, 60, 80])
    fit = fit_theta_pressure(p, 0.81 * p + 9.78)  # eq. (40)
    assert fit.slope == pytest.approx(0.81) and fit.intercept == pytest.approx(9.78)
    assert fit.slope_se == pytest.approx(0, abs=1e-12) and fit.r2 == pytest.approx(1.0)
    assert fit.fit_arg == "0.81,9.78"


def test_uncertainty_matches_scipy_linregress():
    rng = np.random.default_rng(42)
    p = np.repeat([50.0, 75, 100, 125, 150, 175], 3)   # N = 3 repeats, as Fig. 20
    t = 0.52 * p + 7.84 + rng.normal(0, 1.5, p.size)   # eq. (41) with scatter
    fit = fit_theta_pressure(p, t)
    ref = stats.linregress(p, t)
    assert fit.slope == pytest.approx(ref.slope, rel=1e-12)
    assert fit.intercept == pytest.approx(ref.intercept, rel=1e-12)
    assert fit.slope_se == pytest.approx(ref.stderr, rel=1e-10)
    assert fit.intercept_se == pytest.approx(ref.intercept_stderr, rel=1e-10)
    assert fit.r2 == pytest.approx(ref.rvalue ** 2, rel=1e-12)
    lo, hi = fit.slope_ci95
    assert lo < 0.52 < hi


def test_two_pressures_give_no_uncertainty_and_one_is_an_error():
    fit = fit_theta_pressure([10, 20], [30, 40])
    assert fit.slope == pytest.approx(1.0) and np.isnan(fit.slope_se)
    with pytest.raises(VisionError, match="two or more different pressures"):
        fit_theta_pressure([10, 10], [30, 31])


def test_pressure_inputs(tmp_path):
    assert parse_pressures("10, 20,30") == [10.0, 20.0, 30.0]
    with pytest.raises(VisionError):
        parse_pressures("10,x")
    f = tmp_path / "p.csv"
    f.write_text("file,pressure\na.png,10\nb.png,20\n")
    rows = read_pressure_csv(str(f))
    assert [p for _, p in rows] == [10.0, 20.0] and rows[0][0].endswith("a.png")
