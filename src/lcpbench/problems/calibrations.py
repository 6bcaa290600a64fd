"""Pressure → bend-angle calibrations: from an input pressure P to the scene's θ.

The model's input is the unconstrained bend angle θ (Sec. II-A); in the lab
one sets a pressure. Sec. V-B of the paper fits a straight line θ = m P + b
(θ in degrees, P in kPa) to the unconstrained bend angle of each of its three
experimental actuators, eqs. (40)–(42):

====  ===============================  ==========
 no.  fit                              equation
====  ===============================  ==========
 1    θ₁ = 0.81 P + 9.78               (40)
 2    θ₂ = 0.52 P + 7.84               (41)
 3    θ₃ = 0.65 P + 12.1               (42)
====  ===============================  ==========

The fits are valid over the pressures they were measured at: 0 to 172.37 kPa
(0–25 psi, gauge) in 17.24-kPa (2.5-psi) steps (Sec. IV-C, "Data
Collection"). The paper gives one bending stiffness and one weight per length
for all three actuators, the averages of its free-fold tests,
EI = 32.01 N·mm² and w = 2.45e-4 N/mm (Sec. IV-B), with the overall
minimum/maximum EI = 15.18/41.80 N·mm² and w = 2.37e-4/2.47e-4 N/mm
(Sec. V-E); it does not give them per actuator.

:func:`scene_from_pressure` turns a pressure into an
:class:`~lcpbench.problems.scenes.ActuatorScene`; :func:`linear_calibration`
wraps a user's own straight-line fit the same way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError
from .checks import check_number, describe
from .scenes import DEFAULT_EI, DEFAULT_WEIGHT, EI_RANGE, WEIGHT_RANGE, ActuatorScene

KPA_PER_PSI = 6.894757293168361  # 1 psi in kPa

# Sec. V-C: pressures compared with the model, above the knee of force vs
# pressure, per constraint height (mm) -> (P_min, P_max) in kPa.
COMPARISON_PRESSURE_RANGES: dict[float, tuple[float, float]] = {
    4.5: (68.95, 172.37),
    5.5: (103.42, 172.37),
    6.5: (120.66, 172.37),
}

PAPER_EI_RANGE = (15.18, 41.80)  # N·mm², Sec. V-E
PAPER_WEIGHT_RANGE = (2.37e-4, 2.47e-4)  # N/mm, Sec. V-E
PAPER_PRESSURE_RANGE = (0.0, 172.37)  # kPa, Sec. IV-C (0–25 psi)

Number = float | np.ndarray


def _as_float_array(name: str, value, what: str) -> np.ndarray:
    """``value`` as a float array, or ProblemError naming ``name`` (strings are refused)."""
    try:
        if isinstance(value, (str, bytes)) or np.asarray(value).dtype.kind not in "iuf":
            raise TypeError  # strings, bools, complex values, None and objects
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"{name} must be {what}, got {describe(value)}") from exc
    if arr.size == 0 or not np.all(np.isfinite(arr)):
        raise ProblemError(f"{name} must be {what}, got {value!r}")
    return arr


def _range(name: str, value, centre: float, unit: str) -> tuple[float, float] | None:
    if value is None:
        return None
    if isinstance(value, (str, bytes)) or np.ndim(value) != 1 or len(value) != 2:
        raise ProblemError(f"{name} must be a pair (min, max) in {unit} or None, "
                           f"got {describe(value)}")
    lo, hi = (check_number(f"{name}[{k}]", v, unit=unit) for k, v in enumerate(value))
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= centre <= hi):
        raise ProblemError(f"{name} must be finite (min, max) {unit} with min <= {centre:g} "
                           f"<= max, got ({lo:g}, {hi:g})")
    return lo, hi


@dataclass(frozen=True)
class Calibration:
    """A straight-line fit θ = slope · P + intercept of bend angle against pressure.

    Parameters
    ----------
    name : str
        Label (the paper's actuator number for the built-in fits).
    slope : float
        m, degrees per ``pressure_unit``; nonzero.
    intercept : float
        b, degrees (the fit's θ at P = 0).
    pressure_unit : str
        Unit of P (the paper's: "kPa", gauge).
    p_min, p_max : float
        Pressures the fit is valid over (may be ±inf for a user's fit).
    EI : float
        Bending stiffness of this actuator (N·mm²).
    weight : float
        Weight per length w (N/mm), >= 0.
    EI_range, weight_range : (float, float) or None
        Measured minimum and maximum of EI and w, if known.
    source : str
        Where the numbers come from.
    """

    name: str
    slope: float
    intercept: float
    pressure_unit: str = "kPa"
    p_min: float = -math.inf
    p_max: float = math.inf
    EI: float = DEFAULT_EI
    weight: float = DEFAULT_WEIGHT
    EI_range: tuple[float, float] | None = None
    weight_range: tuple[float, float] | None = None
    source: str = ""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ProblemError(f"name must be a non-empty string, got {self.name!r}")
        slope = check_number("slope", self.slope, unit="degrees per unit pressure")
        if slope == 0:
            raise ProblemError("slope must be nonzero degrees per unit pressure (a constant "
                               "bend angle cannot be inverted), got 0")
        object.__setattr__(self, "slope", slope)
        object.__setattr__(self, "intercept", check_number("intercept", self.intercept,
                                                                unit="degrees"))
        if not isinstance(self.pressure_unit, str) or not self.pressure_unit:
            raise ProblemError(f"pressure_unit must be a non-empty string, "
                               f"got {self.pressure_unit!r}")
        for name in ("p_min", "p_max"):
            value = getattr(self, name)
            if not (isinstance(value, (float, np.floating)) and math.isinf(value)):
                value = check_number(name, value, alternative="±inf (no limit)")
            object.__setattr__(self, name, float(value))
        if not self.p_min < self.p_max:
            raise ProblemError(f"p_min must be < p_max, got p_min={self.p_min:g}, "
                               f"p_max={self.p_max:g} {self.pressure_unit}")
        EI = check_number("EI", self.EI, low=EI_RANGE[0], high=EI_RANGE[1], unit="N·mm²")
        object.__setattr__(self, "EI", EI)
        weight = check_number("weight", self.weight, low=WEIGHT_RANGE[0], high=WEIGHT_RANGE[1],
                              unit="N/mm")
        object.__setattr__(self, "weight", weight)
        object.__setattr__(self, "EI_range", _range("EI_range", self.EI_range, EI, "N·mm²"))
        object.__setattr__(self, "weight_range",
                           _range("weight_range", self.weight_range, weight, "N/mm"))

    @property
    def theta_range(self) -> tuple[float, float]:
        """Bend angles (deg) reached over [p_min, p_max], clipped to (0, 360)."""
        ends = sorted(self.slope * p + self.intercept for p in (self.p_min, self.p_max))
        return max(ends[0], 0.0), min(ends[1], 360.0)

    def _where(self) -> str:
        return f"calibration {self.name!r}"

    def theta(self, pressure: Number) -> Number:
        """Unconstrained bend angle θ (degrees) at ``pressure``.

        Parameters
        ----------
        pressure : float or array_like
            P in ``pressure_unit``, within [p_min, p_max].

        Returns
        -------
        float or ndarray
            θ = slope · P + intercept, in (0, 360) degrees.

        Raises
        ------
        ProblemError
            If a pressure is not finite, is outside [p_min, p_max], or gives a
            bend angle outside (0, 360) degrees.
        """
        p = _as_float_array("pressure", pressure, "a finite number")
        unit = self.pressure_unit
        bad = (p < self.p_min) | (p > self.p_max)
        if np.any(bad):
            worst = float(np.atleast_1d(p)[np.atleast_1d(bad)][0])
            raise ProblemError(
                f"pressure must be in [{self.p_min:g}, {self.p_max:g}] {unit}, the range "
                f"{self._where()} was fitted over; got {worst:g} {unit}"
            )
        theta = self.slope * p + self.intercept
        out = (theta <= 0.0) | (theta >= 360.0)
        if np.any(out):
            i = np.flatnonzero(np.atleast_1d(out))[0]
            raise ProblemError(
                f"pressure {np.atleast_1d(p)[i]:g} {unit} gives theta = "
                f"{np.atleast_1d(theta)[i]:g} deg with {self._where()}; theta must be in "
                f"(0, 360) deg"
            )
        return float(theta) if theta.ndim == 0 else theta

    def pressure(self, theta: Number) -> Number:
        """Pressure (``pressure_unit``) giving the bend angle ``theta`` (degrees).

        The inverse of :meth:`theta`: P = (θ − intercept) / slope.

        Raises
        ------
        ProblemError
            If a theta is not finite, not in (0, 360) degrees, or needs a
            pressure outside [p_min, p_max].
        """
        t = _as_float_array("theta", theta, "a finite number of degrees")
        if np.any((t <= 0.0) | (t >= 360.0)):
            raise ProblemError(f"theta must be in (0, 360) degrees, got {theta!r}")
        p = (t - self.intercept) / self.slope
        bad = (p < self.p_min) | (p > self.p_max)
        if np.any(bad):
            lo, hi = self.theta_range
            worst = float(np.atleast_1d(t)[np.atleast_1d(bad)][0])
            raise ProblemError(
                f"theta must be in [{lo:g}, {hi:g}] deg for {self._where()} (pressures "
                f"{self.p_min:g} to {self.p_max:g} {self.pressure_unit}); got {worst:g} deg"
            )
        return float(p) if p.ndim == 0 else p


def linear_calibration(
    slope: float,
    intercept: float,
    *,
    name: str = "custom",
    pressure_unit: str = "kPa",
    p_min: float = -math.inf,
    p_max: float = math.inf,
    EI: float = DEFAULT_EI,
    weight: float = DEFAULT_WEIGHT,
    EI_range: tuple[float, float] | None = None,
    weight_range: tuple[float, float] | None = None,
    source: str = "user fit",
) -> Calibration:
    """A user's own straight-line fit θ = slope · P + intercept (θ in degrees).

    Give ``p_min``/``p_max`` as the pressures the fit was measured over; by
    default any pressure is accepted whose θ lies in (0, 360) degrees. EI and
    weight default to the paper's averages (Sec. IV-B).
    """
    return Calibration(
        name=name, slope=slope, intercept=intercept, pressure_unit=pressure_unit,
        p_min=p_min, p_max=p_max, EI=EI, weight=weight, EI_range=EI_range,
        weight_range=weight_range, source=source,
    )


def _paper(number: str, slope: float, intercept: float, eq: int) -> Calibration:
    return Calibration(
        name=number,
        slope=slope,
        intercept=intercept,
        pressure_unit="kPa",
        p_min=PAPER_PRESSURE_RANGE[0],
        p_max=PAPER_PRESSURE_RANGE[1],
        EI=DEFAULT_EI,
        weight=DEFAULT_WEIGHT,
        EI_range=PAPER_EI_RANGE,
        weight_range=PAPER_WEIGHT_RANGE,
        source=f"paper Sec. V-B eq. ({eq}), actuator {number}; pressures tested 0-172.37 kPa "
               "(Sec. IV-C); EI, w: averages over all actuators (Sec. IV-B), "
               "min/max Sec. V-E",
    )


CALIBRATIONS: dict[str, Calibration] = {
    "1": _paper("1", 0.81, 9.78, 40),
    "2": _paper("2", 0.52, 7.84, 41),
    "3": _paper("3", 0.65, 12.1, 42),
}


def _lookup(name, param: str) -> Calibration:
    if isinstance(name, Calibration):
        return name
    key = str(name) if isinstance(name, (str, int)) and not isinstance(name, bool) else None
    if key not in CALIBRATIONS:
        names = ", ".join(repr(k) for k in CALIBRATIONS)
        raise ProblemError(
            f"{param} must be one of {names} (the paper's actuators, eqs. 40-42) or a "
            f"Calibration from linear_calibration(), got {name!r}"
        )
    return CALIBRATIONS[key]


def get_calibration(name: str | int, param: str = "name") -> Calibration:
    """The paper's calibration of actuator ``name`` ("1", "2" or "3"; an int works too).

    Raises
    ------
    ProblemError
        For any other name, naming ``param`` (the caller's name for it, e.g. the
        option "actuator"); the message lists the known ones.
    """
    return _lookup(name, param)


def scene_from_pressure(
    pressure: float,
    actuator: str | int | Calibration = "1",
    height: float = 3.0,
    **scene_kw,
) -> ActuatorScene:
    """The actuator scene at an input pressure.

    Parameters
    ----------
    pressure : float
        Input pressure P in the calibration's unit (kPa for the paper's).
    actuator : "1", "2", "3" or Calibration
        Which pressure → θ fit (eqs. 40–42) and material to use.
    height : float
        Wall height h (mm), as for :class:`ActuatorScene` (default 3 mm, the
        scene's default; the paper's fixture is a channel, ``channel=True``,
        at h = 4.5, 5.5 or 6.5 mm).
    **scene_kw
        Other :class:`ActuatorScene` fields (``links``, ``length``, ``channel``,
        ``EI``, ``weight``); ``EI`` and ``weight`` override the calibration's.

    Returns
    -------
    ActuatorScene
        With θ from the calibration and EI, w from it unless overridden.
    """
    cal = _lookup(actuator, "actuator")
    if "theta" in scene_kw:
        raise ProblemError("theta cannot be given with a pressure: the calibration sets it "
                           "(use ActuatorScene(theta=...) directly)")
    scene_kw.setdefault("EI", cal.EI)
    scene_kw.setdefault("weight", cal.weight)
    return ActuatorScene(theta=cal.theta(pressure), height=height, **scene_kw)
