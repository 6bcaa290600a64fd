"""Calibration from measurements: fit EI (and the θ(P) line) to force–pressure data.

Issue 38, item 3. Measured total forces y_i at pressures P_i (and heights h_i) are
matched by the model's F_i = F(θ(P_i), h_i; EI), θ(P) = slope·P + intercept (the
calibration given, or fitted too with ``fit_theta``), by Gauss–Newton on relative
residuals r_i = (F_i − y_i)/s_i (measurement noise proportional to the force), its
scales s_i = max(|F_i|, 5 % of max|F|) taken from the model at the start of each
iteration and held through its line search (iteratively reweighted least squares: the
fixed point solves Σ J_i (F_i − y_i)/s_i² = 0, the quasi-likelihood equation of noise
σ_i ∝ F_i; scales read off the noisy y_i instead weight the points that happened to
fall low more and make the estimate biased and less efficient), its Jacobian from :func:`lcpbench.sensitivities`
(dF/dEI; dF/dθ · P and dF/dθ for the line), each forward solve started from the
last iteration's answer at that point. The 95 % interval of each parameter is
± t(0.975, m − p) σ̂ √C_jj with C = (JᵀJ)⁻¹ at the optimum and σ̂² = Σr²/(m − p), the
Gauss–Newton covariance (linearised; the model is nearly linear in EI: F ∝ EI
without weight).
"""

from __future__ import annotations

import csv
import dataclasses
import math
from array import array
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..api import check_tol, solve
from ..errors import ProblemError
from ..model.sensitivity import sensitivities
from ..problems.calibrations import Calibration
from ..problems.scenes import ActuatorScene

MAX_BYTES = 10_000_000
MAX_ITER = 30
#: relative change of the parameters that ends the iteration
STEP_RTOL = 1e-10


@dataclass
class FitResult:
    """``EI`` (N mm²) with its 95 % interval ``EI_low``, ``EI_high``; ``slope`` and
    ``intercept`` of θ(P) (deg per kPa, deg) with theirs when fitted, else the
    calibration's; ``residuals`` (N) F_i − y_i; ``iterations``; ``solves``."""

    EI: float
    EI_low: float
    EI_high: float
    slope: float
    intercept: float
    slope_interval: tuple[float, float] | None
    intercept_interval: tuple[float, float] | None
    residuals: np.ndarray
    model_forces: np.ndarray
    iterations: int
    solves: int

    def as_json(self) -> dict:
        out = {"EI": self.EI, "EI_low": self.EI_low, "EI_high": self.EI_high,
               "slope": self.slope, "intercept": self.intercept,
               "residuals": self.residuals.tolist(), "iterations": self.iterations,
               "solves": self.solves}
        if self.slope_interval is not None:
            out["slope_low"], out["slope_high"] = self.slope_interval
            out["intercept_low"], out["intercept_high"] = self.intercept_interval
        return out


def read_data(path) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(pressure_kpa, force_n, height_mm or None) from a CSV with those columns (the
    height optional); one ProblemError naming the file and row for anything else."""
    p = Path(path)
    cols: dict[str, array] = {}
    try:
        with p.open(newline="") as fh:
            if p.stat().st_size > MAX_BYTES:
                raise ProblemError(f"--data: {p.name} is over {MAX_BYTES} bytes")
            rows = csv.reader(fh)
            header = next((r for r in rows if r and not r[0].lstrip().startswith("#")), None)
            names = [h.strip() for h in header] if header else []
            if not {"pressure_kpa", "force_n"} <= set(names) or \
                    not set(names) <= {"pressure_kpa", "force_n", "height_mm"}:
                raise ProblemError(f"--data: {p.name} needs a header pressure_kpa,force_n "
                                   f"(and optionally height_mm), got {','.join(names)!r}")
            cols = {n: array("d") for n in names}
            for k, row in enumerate(rows, start=2):
                if not row or row[0].lstrip().startswith("#"):
                    continue
                if len(row) != len(names):
                    raise ProblemError(f"--data: {p.name} line {k} has {len(row)} values, "
                                       f"the header {len(names)}")
                for n, v in zip(names, row):
                    try:
                        x = float(v)
                    except ValueError:
                        raise ProblemError(f"--data: {p.name} line {k}: {n} is not a number "
                                           f"({v.strip()!r})") from None
                    if not math.isfinite(x):
                        raise ProblemError(f"--data: {p.name} line {k}: {n} is {v.strip()}")
                    if n == "force_n" and x < 0:
                        raise ProblemError(f"--data: {p.name} line {k}: a negative force "
                                           f"({x:g} N); forces are the wall's push, >= 0")
                    cols[n].append(x)
    except OSError as exc:
        raise ProblemError(f"--data: cannot read {str(p)!r} ({exc.strerror})") from exc
    h = np.asarray(cols["height_mm"]) if "height_mm" in cols else None
    return np.asarray(cols["pressure_kpa"]), np.asarray(cols["force_n"]), h


def fit(scene: ActuatorScene, pressure, force, calibration: Calibration, *, height=None,
        fit_theta: bool = False, tol: float = 1e-10) -> FitResult:
    """Fit EI (and with ``fit_theta`` the line θ = slope·P + intercept, starting from
    ``calibration``) to the forces ``force`` (N) measured at ``pressure`` (the
    calibration's unit) and ``height`` (mm; default the scene's); the scene gives the
    rest (N, ℓ, w, walls) and the starting EI."""
    if not (isinstance(scene, ActuatorScene) and scene.wall_profile is None):
        what = "a wall profile" if isinstance(scene, ActuatorScene) else type(scene).__name__
        raise ProblemError(f"fit covers actuator scenes with flat walls (one wall or a "
                           f"channel, rigid or elastic); got {what}")
    tol = check_tol(tol)
    P, y = np.asarray(pressure, dtype=float), np.asarray(force, dtype=float)
    h = np.full(P.size, scene.height) if height is None else np.asarray(height, dtype=float)
    nparam = 3 if fit_theta else 1
    if not (P.size == y.size == h.size):
        raise ProblemError("fit: pressure, force and height need one value per measurement")
    if P.size <= nparam:
        raise ProblemError(f"fit: {P.size} measurements for {nparam} parameter"
                           f"{'s' if nparam > 1 else ''}: give more points than parameters")
    if not (np.all(np.isfinite(P)) and np.all(np.isfinite(y)) and np.all(np.isfinite(h))):
        raise ProblemError("fit: the data hold a NaN or an infinity")
    if np.any(y < 0):
        raise ProblemError("fit: a negative force; forces are the wall's push, >= 0 N")
    if not np.any(y > 0):
        raise ProblemError("fit: every force is 0: no contact, nothing to fit EI to")

    def scales(F):  # s_i of the module docstring, from the model's forces
        return np.maximum(np.abs(F), 0.05 * np.max(np.abs(F)))

    x = np.array([scene.EI, calibration.slope, calibration.intercept][:nparam], dtype=float)
    last: list = [None] * P.size
    solves = 0

    def model(x):
        nonlocal solves
        EI = x[0]
        slope, intercept = (x[1], x[2]) if fit_theta else (calibration.slope,
                                                           calibration.intercept)
        F, J = np.empty(P.size), np.empty((P.size, nparam))
        for i in range(P.size):
            sc = dataclasses.replace(scene, EI=float(EI), theta=float(slope * P[i] + intercept),
                                     height=float(h[i]))
            start = last[i] if last[i] is not None and last[i].converged else None
            res = solve(sc, tol=tol, start=start)
            solves += 1
            if not res.converged:
                raise ProblemError(f"fit: the forward solve at P = {P[i]:g} (theta "
                                   f"{sc.theta:.4g} deg, h {h[i]:g} mm, EI {EI:.4g}) did not "
                                   f"converge ({res.reason})")
            last[i] = res
            F[i] = res.total_force
            d = sensitivities(res, wrt=("EI", "theta_deg")).total_force
            J[i, 0] = d["EI"]
            if fit_theta:
                J[i, 1], J[i, 2] = d["theta_deg"] * P[i], d["theta_deg"]
        return F, J

    def cost(F, s):
        r = (F - y) / s
        return float(r @ r)

    def admissible(x):
        if x[0] <= 0:
            return False
        if fit_theta:  # every θ(P_i) in (0, 360) deg
            theta = x[1] * P + x[2]
            return bool(np.all((theta > 0) & (theta < 360)))
        return True

    F, J = model(x)
    it = 0
    while it < MAX_ITER:  # Gauss–Newton, the step halved until the cost falls
        it += 1
        s = scales(F)
        dx, *_ = np.linalg.lstsq(J / s[:, None], -(F - y) / s, rcond=None)
        t, moved = 1.0, False
        while t >= 1e-6:
            x_try = x + t * dx
            if admissible(x_try):
                try:
                    F_try, J_try = model(x_try)
                except ProblemError:  # a forward solve out of its range: a shorter step
                    F_try = None
                if F_try is not None and cost(F_try, s) <= cost(F, s) * (1 + 1e-12):
                    x, F, J, moved = x_try, F_try, J_try, True
                    break
            t *= 0.5
        if not moved or np.all(np.abs(t * dx) <= STEP_RTOL * np.maximum(np.abs(x), 1.0)):
            break
    s = scales(F)
    r, Js = (F - y) / s, J / s[:, None]
    dof = P.size - nparam
    sigma2 = float(r @ r) / dof
    cov = sigma2 * np.linalg.pinv(Js.T @ Js)
    from scipy.stats import t as student

    half = student.ppf(0.975, dof) * np.sqrt(np.maximum(np.diag(cov), 0.0))
    slope, intercept = (x[1], x[2]) if fit_theta else (calibration.slope, calibration.intercept)
    return FitResult(float(x[0]), float(x[0] - half[0]), float(x[0] + half[0]), float(slope),
                     float(intercept),
                     (float(x[1] - half[1]), float(x[1] + half[1])) if fit_theta else None,
                     (float(x[2] - half[2]), float(x[2] + half[2])) if fit_theta else None,
                     F - y, F, it, solves)


__all__ = ["FitResult", "fit", "read_data"]
