"""The whole static-image measurement (Sec. IV-D-1 to IV-D-7) on one photograph.

:func:`measure` runs undistort → marker scale → bearings/levelling → segmentation
→ centerline → inflection points → a circle fit per section → θ (eq. 38, with
atan2) and ℓ (eq. 39), and returns a :class:`Measurement` whose
:meth:`~Measurement.to_dict` is the JSON of ``lcpbench vision measure``.
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
    """One bending section: eq. (38) θ, eq. (39) ℓ, and its fitted circle (mm)."""

    theta_deg: float
    arc_length_mm: float
    radius_mm: float
    center_mm: list
    start_mm: list
    end_mm: list
    rms_mm: float

    def to_dict(self) -> dict:
        return {"theta_deg": self.theta_deg, "arc_length_mm": self.arc_length_mm,
                "radius_mm": self.radius_mm, "center_mm": self.center_mm,
                "start_mm": self.start_mm, "end_mm": self.end_mm, "fit_rms_mm": self.rms_mm}


@dataclass
class Measurement:
    """What one photograph gives (mm, levelled frame: origin at the left pin)."""

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

    @property
    def pin_span_mm(self) -> float:
        return float(np.hypot(*(self.bearings.right - self.bearings.left)) / self.px_per_mm)

    def to_dict(self) -> dict:
        mid = self.sections[self.middle]
        return {
            "px_per_mm": self.px_per_mm,
            "level_deg": self.level_deg,
            "pin_span_mm": self.pin_span_mm,
            "marker_id": self.marker.id,
            "hsv_range": [list(self.segmentation.lower), list(self.segmentation.upper)],
            "centerline_mm": np.round(self.centerline_mm, 5).tolist(),
            "inflection_points_mm": self.inflection_points_mm.tolist(),
            "sections": [s.to_dict() for s in self.sections],
            "middle": {"theta_deg": mid.theta_deg, "arc_length_mm": mid.arc_length_mm,
                       "index": self.middle},
        }


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


def measure(image, *, calibration=None, marker_mm: float = 25.0, sections: int = 3,
            diameter_mm: float = 3.0, hsv_lower=None, hsv_upper=None) -> Measurement:
    """Measure one photograph (a path or a BGR array) of the fixture.

    Parameters
    ----------
    image : path to a PNG/JPEG, or a BGR uint8 array.
    calibration : OpenCV camera calibration (dict or JSON path) to undistort with.
    marker_mm : side of the ArUco marker (paper: 25 mm).
    sections : number of bending sections k (default 3); the middle one is k // 2.
    diameter_mm : outer diameter of the tube (default 3 mm).
    hsv_lower, hsv_upper : the actuator's HSV range (OpenCV H 0-179); automatic if None.
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
    knots, secs = analyse_centerline(c_mm, span, sections)
    return Measurement(ppm, bearings.level_deg, c_mm, knots, secs, sections // 2, img,
                       marker, bearings, seg, c_px)
