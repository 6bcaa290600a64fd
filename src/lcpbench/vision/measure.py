"""The whole static-image measurement (Sec. IV-D-1 to IV-D-7) on one photograph.

:func:`measure` runs undistort → marker scale → bearings/levelling → segmentation
→ centerline, then two analyses of the centerline:

- the **joint fit** (:mod:`.jointfit`): one least-squares chain of k arcs between
  the pins; its θ and ℓ per section are the measurement, with a confidence;
- the paper's **per-section circle fits**: inflection points → a circle per
  section → θ (eq. 38, with atan2) and ℓ (eq. 39), kept for comparison.

It returns a :class:`Measurement` whose :meth:`~Measurement.to_dict` is the JSON of
``lcpbench vision measure``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .errors import VisionError
from .geometry import (
    Circle,
    arc_length,
    bend_angle,
    cumulative_length,
    fit_circle,
    inflection_indices,
    resample,
    tangent_point,
)
from .jointfit import Confidence, JointFit, check, fit_chain
from .stages import (
    Bearings,
    Marker,
    Segmentation,
    centerline,
    detect_marker,
    find_bearings,
    load_image,
    segment,
    to_mm,
    undistort,
)


@dataclass
class Section:
    """One bending section: θ, ℓ, and its circle (mm). For the joint fit also the
    standard errors of θ and ℓ (1 s.e.); for a circle fit, eq. (38) θ and eq. (39) ℓ."""

    theta_deg: float
    arc_length_mm: float
    radius_mm: float
    center_mm: list
    start_mm: list
    end_mm: list
    rms_mm: float
    theta_se_deg: float | None = None
    arc_length_se_mm: float | None = None

    def to_dict(self) -> dict:
        d = {"theta_deg": self.theta_deg, "arc_length_mm": self.arc_length_mm,
             "radius_mm": self.radius_mm, "center_mm": self.center_mm,
             "start_mm": self.start_mm, "end_mm": self.end_mm, "fit_rms_mm": self.rms_mm}
        if self.theta_se_deg is not None:
            d.update(theta_se_deg=self.theta_se_deg, arc_length_se_mm=self.arc_length_se_mm)
        return d


@dataclass
class Measurement:
    """What one photograph gives (mm, levelled frame: origin at the left pin).

    ``sections`` and ``inflection_points_mm`` are the joint fit's (the measurement);
    ``circle_fits`` and ``circle_knots_mm`` the paper's per-section circle fits
    (eqs. 38-39), for comparison (None if they failed); ``confidence`` the joint
    fit's residual, standard errors, section-length spread and warnings.
    """

    px_per_mm: float
    level_deg: float
    centerline_mm: np.ndarray
    inflection_points_mm: np.ndarray
    sections: list[Section]
    middle: int
    image: np.ndarray = field(repr=False)
    marker: Marker = field(repr=False)
    bearings: Bearings = field(repr=False)
    segmentation: Segmentation = field(repr=False)
    centerline_px: np.ndarray = field(repr=False)
    circle_fits: list[Section] | None = None
    circle_knots_mm: np.ndarray | None = None
    joint: JointFit | None = field(default=None, repr=False)
    confidence: Confidence | None = None

    @property
    def pin_span_mm(self) -> float:
        return float(np.hypot(*(self.bearings.right - self.bearings.left)) / self.px_per_mm)

    @property
    def warnings(self) -> list[str]:
        return list(self.confidence.warnings) if self.confidence is not None else []

    def to_dict(self) -> dict:
        mid = self.sections[self.middle]
        d = {
            "px_per_mm": self.px_per_mm,
            "level_deg": self.level_deg,
            "pin_span_mm": self.pin_span_mm,
            "marker_id": self.marker.id,
            "hsv_range": [list(self.segmentation.lower), list(self.segmentation.upper)],
            "centerline_mm": np.round(self.centerline_mm, 5).tolist(),
            "method": "joint fit" + (" (equal sections)" if self.joint is not None
                                     and self.joint.equal_sections else ""),
            "inflection_points_mm": self.inflection_points_mm.tolist(),
            "sections": [s.to_dict() for s in self.sections],
            "middle": {"theta_deg": mid.theta_deg, "arc_length_mm": mid.arc_length_mm,
                       "theta_se_deg": mid.theta_se_deg,
                       "arc_length_se_mm": mid.arc_length_se_mm, "index": self.middle},
            "confidence": self.confidence.to_dict() if self.confidence is not None else None,
            "warnings": self.warnings,
            "circle_fits": None,
        }
        if self.circle_fits is not None:
            cm = self.circle_fits[self.middle]
            d["circle_fits"] = {
                "inflection_points_mm": self.circle_knots_mm.tolist(),
                "sections": [s.to_dict() for s in self.circle_fits],
                "middle": {"theta_deg": cm.theta_deg, "arc_length_mm": cm.arc_length_mm}}
        return d


def analyse_centerline(c: np.ndarray, span: float, sections: int = 3,
                       sigma_mm: float = 0.5, trim: float = 0.08,
                       refine: bool = True) -> tuple[np.ndarray, list[Section]]:
    """Inflection points and per-section circle fits of a levelled centerline (mm).

    Parameters
    ----------
    c : (n, 2) visible centerline, ordered from the left pin (0, 0) to the right
        pin (span, 0); the pins themselves close it.
    sections : k, the number of bending sections.
    sigma_mm : smoothing of the tangent angle that locates the inflection points.
    trim : fraction of a section's points left out at each inflection point when
        its circle is fitted (the transition there is not a circle's).
    refine : move each inflection point to where the neighbouring fitted circles
        touch (exact for the unconstrained actuator, where consecutive arcs are
        tangent); kept only when the two circles are close to tangent.

    Returns
    -------
    knots : (k − 1, 2) inflection points.
    sections : list of :class:`Section`, left to right.
    """
    full = np.vstack([[0.0, 0.0], c, [span, 0.0]])
    dense = resample(full, step=0.05)
    idx = inflection_indices(dense, sections, sigma_mm / 0.05)
    knots = dense[idx]
    s_full = cumulative_length(dense)
    s_pts = _project(c, dense, s_full)
    bounds = np.concatenate([[0.0], s_full[idx], [s_full[-1]]])
    circles = []
    for j in range(sections):
        a, b = bounds[j], bounds[j + 1]
        m = trim * (b - a)
        lo = a + (m if j > 0 else 0.0)
        hi = b - (m if j < sections - 1 else 0.0)
        sel = (s_pts >= lo) & (s_pts <= hi)
        if sel.sum() < 10:
            raise VisionError(f"section {j + 1} of {sections} has too few centerline points: "
                              "check --sections and that the actuator is fully in view")
        circles.append(fit_circle(c[sel]))
    if refine:
        for j in range(sections - 1):
            c1, c2 = circles[j], circles[j + 1]
            gap = np.hypot(*(c2.center - c1.center)) - (c1.radius + c2.radius)
            if abs(gap) < 0.02 * (c1.radius + c2.radius):
                knots[j] = tangent_point(c1, c2)
    ends = np.vstack([[0.0, 0.0], knots, [span, 0.0]])
    out = []
    for j, circ in enumerate(circles):
        p1, p2 = ends[j], ends[j + 1]
        between = (s_pts > bounds[j]) & (s_pts < bounds[j + 1])
        through = c[between][len(c[between]) // 2] if between.any() else None
        th = bend_angle(p1, p2, circ.center, through)
        out.append(_section(circ, th, p1, p2))
    return knots, out


def _section(circ: Circle, theta: float, p1, p2) -> Section:
    return Section(math.degrees(theta), arc_length(circ.radius, theta), circ.radius,
                   circ.center.tolist(), list(map(float, p1)), list(map(float, p2)), circ.rms)


def _project(points: np.ndarray, dense: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Arc length along ``dense`` of the nearest point of each of ``points``."""
    from scipy.spatial import cKDTree

    _, i = cKDTree(dense).query(points)
    return s[i]


def joint_sections(fit: JointFit) -> list[Section]:
    """The joint fit's arcs as :class:`Section` rows (with standard errors)."""
    c = fit.confidence
    return [Section(math.degrees(a.theta), a.length, a.radius, a.center.tolist(),
                    a.start.tolist(), a.end.tolist(), fit.section_rms_mm(j),
                    c.theta_se_deg[j], c.arc_length_se_mm[j])
            for j, a in enumerate(fit.arcs)]


def marker_scale_sd(marker: Marker) -> float:
    """Relative 1-σ of the marker's px/mm: the spread of its four sides over √4."""
    q = np.asarray(marker.corners, float)
    side = np.hypot(*np.diff(np.vstack([q, q[:1]]), axis=0).T)
    return float(side.std(ddof=1) / 2 / side.mean())


def measure(image, *, calibration=None, marker_mm: float = 25.0, sections: int = 3,
            diameter_mm: float = 3.0, hsv_lower=None, hsv_upper=None,
            equal_sections: bool = False) -> Measurement:
    """Measure one photograph (a path or a BGR array) of the fixture.

    Parameters
    ----------
    image : path to a PNG/JPEG, or a BGR uint8 array.
    calibration : OpenCV camera calibration (dict or JSON path) to undistort with.
    marker_mm : side of the ArUco marker (paper: 25 mm).
    sections : number of bending sections k (default 3); the middle one is k // 2.
    diameter_mm : outer diameter of the tube (default 3 mm).
    hsv_lower, hsv_upper : the actuator's HSV range (OpenCV H 0-179); automatic if None.
    equal_sections : the joint fit shares one θ among the sections (ℓ stays per section).
    """
    if not (isinstance(sections, int) and sections >= 1):
        raise VisionError(f"--sections must be an integer >= 1, got {sections!r}")
    if not (diameter_mm > 0):
        raise VisionError(f"--diameter must be positive, got {diameter_mm}")
    img = load_image(image) if not isinstance(image, np.ndarray) else image
    if img.ndim != 3 or img.shape[2] != 3:
        raise VisionError("the image must be a colour (3-channel) photograph")
    if calibration is not None:
        img = undistort(img, calibration)
    marker = detect_marker(img, marker_mm)
    ppm = marker.px_per_mm
    bearings = find_bearings(img, ppm, marker)
    seg = segment(img, hsv_lower, hsv_upper)
    c_px, _ = centerline(seg, bearings, ppm, diameter_mm)
    c_mm = to_mm(c_px, bearings, ppm)
    span = float(np.hypot(*(bearings.right - bearings.left)) / ppm)
    fit, circles, knots = analyse(c_mm, span, sections, ppm, diameter_mm, equal_sections,
                                  marker_scale_sd(marker))
    return Measurement(ppm, bearings.level_deg, c_mm, fit.inflection_points,
                       joint_sections(fit), sections // 2, img, marker, bearings, seg, c_px,
                       circles, knots, fit, fit.confidence)


def analyse(c_mm: np.ndarray, span: float, sections: int = 3, px_per_mm: float = 1.0,
            diameter_mm: float = 3.0, equal_sections: bool = False, scale_sd: float = 0.0
            ) -> tuple[JointFit, list[Section] | None, np.ndarray | None]:
    """Both analyses of a levelled centerline (mm): the joint fit (the measurement,
    its warnings in ``fit.confidence.warnings``) and the paper's per-section circle
    fits and inflection points (None if they fail), which also start the joint fit."""
    middle = sections // 2
    try:
        knots, circles = analyse_centerline(c_mm, span, sections)
        start = (np.radians([s.theta_deg for s in circles]), [s.arc_length_mm for s in circles])
    except VisionError:
        knots = circles = start = None
    fit = fit_chain(c_mm, span, sections, start=start, equal_sections=equal_sections,
                    px_per_mm=px_per_mm, scale_rel_sd=scale_sd)
    ref = None if circles is None else (circles[middle].theta_deg,
                                        circles[middle].arc_length_mm)
    fit.confidence.warnings = check(fit, middle, diameter_mm, px_per_mm, ref)
    if circles is None:
        fit.confidence.warnings.append("the per-section circle fits (eqs. 38-39) failed: "
                                       "no comparison with the paper's method")
    return fit, circles, knots
