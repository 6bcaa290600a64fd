"""θ against pressure (Sec. V-B, eqs. 40-42): θ = slope · P + intercept, with its
uncertainty, from the middle-section bend angles of several photographs."""

from __future__ import annotations

import csv
import math
import os
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .errors import VisionError


@dataclass
class PressureFit:
    """Least-squares line θ = slope · P + intercept (θ in degrees).

    ``slope_se`` and ``intercept_se`` are standard errors from the residual
    variance (n − 2 degrees of freedom); the ``*_ci95`` are the 95 % Student-t
    intervals; ``rmse_deg`` the residual RMS. With two pressures the line is
    exact and the uncertainties are NaN.
    """

    slope: float
    intercept: float
    slope_se: float
    intercept_se: float
    slope_ci95: tuple[float, float]
    intercept_ci95: tuple[float, float]
    r2: float
    rmse_deg: float
    n: int
    p_min: float
    p_max: float

    @property
    def fit_arg(self) -> str:
        """The ``--fit SLOPE,INTERCEPT`` string ``lcpbench solve`` accepts."""
        return f"{self.slope:.6g},{self.intercept:.6g}"

    def to_dict(self) -> dict:
        return {"model": "theta_deg = slope * P + intercept", "slope": self.slope,
                "intercept": self.intercept, "slope_se": self.slope_se,
                "intercept_se": self.intercept_se, "slope_ci95": list(self.slope_ci95),
                "intercept_ci95": list(self.intercept_ci95), "r2": self.r2,
                "rmse_deg": self.rmse_deg, "n": self.n, "p_min": self.p_min,
                "p_max": self.p_max, "fit": self.fit_arg}


def fit_theta_pressure(pressure, theta_deg) -> PressureFit:
    """Fit θ = slope · P + intercept (eqs. 40-42) to paired measurements.

    Parameters
    ----------
    pressure : pressures P (any unit; the paper's kPa), repeats allowed.
    theta_deg : measured middle-section bend angles θ (deg).
    """
    p = np.asarray(pressure, float).ravel()
    t = np.asarray(theta_deg, float).ravel()
    if p.shape != t.shape or p.size < 2 or np.unique(p).size < 2:
        raise VisionError("the fit needs bend angles at two or more different pressures "
                          f"(got {np.unique(p).size} pressure(s) for {t.size} image(s))")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(t))):
        raise VisionError("pressures and angles must be finite numbers")
    n = p.size
    a = np.column_stack([p, np.ones(n)])
    (slope, icpt), *_ = np.linalg.lstsq(a, t, rcond=None)
    res = t - a @ [slope, icpt]
    dof = n - 2
    if dof > 0:
        s2 = float(res @ res) / dof
        cov = s2 * np.linalg.inv(a.T @ a)
        se_s, se_i = (float(math.sqrt(max(v, 0.0))) for v in np.diag(cov))
        q = float(stats.t.ppf(0.975, dof))
    else:
        se_s = se_i = q = math.nan
    ss_tot = float(((t - t.mean()) ** 2).sum())
    r2 = 1 - float(res @ res) / ss_tot if ss_tot > 0 else math.nan
    return PressureFit(float(slope), float(icpt), se_s, se_i,
                       (slope - q * se_s, slope + q * se_s), (icpt - q * se_i, icpt + q * se_i),
                       r2, float(np.sqrt(np.mean(res ** 2))), n, float(p.min()), float(p.max()))


def parse_pressures(text: str) -> list[float]:
    """``"10,20,30"`` → [10.0, 20.0, 30.0]."""
    try:
        return [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise VisionError(f"--pressures must be numbers separated by commas, got {text!r}") \
            from None


def read_pressure_csv(path: str) -> list[tuple[str, float]]:
    """Rows ``file,pressure`` (a header row is skipped); files relative to the CSV."""
    rows = []
    try:
        with open(path, newline="") as fh:
            for k, row in enumerate(csv.reader(fh)):
                if not row or row[0].strip().startswith("#"):
                    continue
                try:
                    rows.append((os.path.join(os.path.dirname(path), row[0].strip()),
                                 float(row[1])))
                except (IndexError, ValueError):
                    if k == 0:
                        continue  # header
                    raise VisionError(f"{path}: row {k + 1} is not file,pressure") from None
    except OSError as exc:
        raise VisionError(f"{path}: cannot read ({exc.strerror})") from None
    if not rows:
        raise VisionError(f"{path}: no file,pressure rows")
    return rows
