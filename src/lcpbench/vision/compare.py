"""Model against photograph (Sec. IV-D-8, Fig. 23): the constrained centerline that
lcpbench.solve predicts, registered to the photographed one by ICP."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..problems.scenes import ActuatorScene
from .errors import VisionError
from .geometry import Registration, cumulative_length, icp, offset_curve, resample, rigid_fit
from .measure import Measurement

#: The paper's discretisation for the comparison (Sec. IV-D-8).
COMPARE_LINKS = 200


@dataclass
class Comparison:
    """Point-pair distances (mm and % of the model's span in x, eq. 43), the predicted
    contact force (N), the aligned curves (mm) and the model's result."""

    distances_mm: np.ndarray
    percent: np.ndarray
    span_mm: float
    force_n: float
    model_mm: np.ndarray
    photo_mm: np.ndarray
    registration: Registration
    result: object
    theta_deg: float
    wall_face_mm: float
    radius_mm: float = 1.5

    def to_dict(self) -> dict:
        d, pc = self.distances_mm, self.percent
        return {
            "theta_deg": self.theta_deg, "wall_face_mm": self.wall_face_mm,
            # the model's centre-line wall height h, as in ``lcpbench solve --height``
            "height_mm": float(self.result.scene.height),
            "links": len(self.model_mm) - 1,
            "mean_distance_mm": float(d.mean()), "sd_distance_mm": float(d.std()),
            "max_distance_mm": float(d.max()), "mean_percent": float(pc.mean()),
            "sd_percent": float(pc.std()), "max_percent": float(pc.max()),
            "model_span_mm": self.span_mm, "contact_force_n": self.force_n,
            "model_converged": bool(self.result.converged),
            "icp_iterations": self.registration.iterations,
            "icp_rotation_deg": self.registration.angle_deg,
            "icp_translation_mm": self.registration.translation.tolist(),
            "point_pair_distance_mm": d.tolist(),
        }


def model_centerline(theta_deg: float, wall_face: float, *, diameter_mm: float = 3.0,
                     offset: str = "wall", channel: bool = True, links: int = COMPARE_LINKS,
                     **scene_kw):
    """The model's constrained centerline of the tube (mm) and its ContactResult.

    ``wall_face`` is the distance from the pin line to the wall's face (mm). The
    model is a line; the tube's centerline stays a radius r from the wall.
    ``offset="wall"`` solves with the walls at the centre-line height
    h = wall_face − r (exact for a flat wall: the tube touches where its centerline
    is r away); ``offset="curve"`` solves at h = ``wall_face`` and offsets the
    model's centerline by r, as the paper did (Sec. IV-D-8).
    """
    from ..api import solve

    r = diameter_mm / 2
    if offset not in ("wall", "curve"):
        raise VisionError(f"offset must be 'wall' or 'curve', got {offset!r}")
    h = wall_face - r if offset == "wall" else wall_face
    if h <= 0:
        raise VisionError(f"--wall-face must exceed the tube radius {r:g} mm, got "
                          f"{wall_face:g}")
    res = solve(ActuatorScene(theta=theta_deg, height=h, links=links, channel=channel,
                              **scene_kw))
    pts = np.column_stack([res.x, res.y])
    if offset == "curve":
        pts = offset_curve(pts, r)
    return pts, res


def compare(meas: Measurement, theta_deg: float, wall_face: float, *, diameter_mm: float = 3.0,
            offset: str = "wall", channel: bool = True, links: int = COMPARE_LINKS,
            **scene_kw) -> Comparison:
    """Register the model's constrained middle section to the photographed one.

    The photographed middle section (between the inflection points, extended by
    10 % of its length each side so no model point lacks a partner) is resampled
    every 0.01 mm; ICP moves it onto the model's N + 1 points (paper: N = 200,
    threshold 1e-7, at most 2000 iterations). The distance of each model point to
    the moved photographed curve is its point-pair distance; eq. (43) divides it
    by the model's span in x.
    """
    model, res = model_centerline(theta_deg, wall_face, diameter_mm=diameter_mm, offset=offset,
                                  channel=channel, links=links, **scene_kw)
    c = meas.centerline_mm
    k = len(meas.sections)
    if k > 1:
        full = np.vstack([[0.0, 0.0], c, [meas.pin_span_mm, 0.0]])
        s = cumulative_length(full)
        # the paper's inflection points (tangent-angle extrema): they hold for a
        # constrained middle section, which is not an arc of the joint fit's chain
        mid = (meas.circle_fits or meas.sections)[meas.middle]
        s1 = s[np.argmin(np.hypot(*(full - mid.start_mm).T))]
        s2 = s[np.argmin(np.hypot(*(full - mid.end_mm).T))]
        ext = 0.1 * (s2 - s1)
        sel = (s >= s1 - ext) & (s <= s2 + ext)
        photo = full[sel]
        p1, p2 = np.asarray(mid.start_mm), np.asarray(mid.end_mm)
    else:
        photo = c
        p1, p2 = c[0], c[-1]
    photo = resample(photo, step=0.01)
    # start: the photographed section's ends onto the model's pins
    r0, t0 = rigid_fit(np.array([p1, p2]), model[[0, -1]])
    start = photo @ r0.T + t0
    reg = icp(model, start)
    r_tot = reg.rotation @ r0
    reg.translation = reg.rotation @ t0 + reg.translation
    reg.rotation = r_tot
    span = float(model[:, 0].max() - model[:, 0].min())
    return Comparison(reg.distances, 100 * reg.distances / span, span,
                      float(res.total_force), model, reg.moved, reg, res, float(theta_deg),
                      float(wall_face), diameter_mm / 2)


def theta_from_pressure(pressure: float, fit: str | None, actuator: str = "1") -> float:
    """θ at a pressure from ``--fit SLOPE,INTERCEPT`` or one of the paper's actuators."""
    from ..problems.calibrations import get_calibration, linear_calibration

    if fit is not None:
        try:
            slope, icpt = (float(v) for v in fit.split(","))
        except ValueError:
            raise VisionError(f"--fit must be SLOPE,INTERCEPT (two numbers), got {fit!r}") \
                from None
        cal = linear_calibration(slope, icpt)
    else:
        cal = get_calibration(actuator)
    th = float(cal.theta(pressure))
    if not (0 < th < 360 and math.isfinite(th)):
        raise VisionError(f"the calibration gives theta = {th:g} deg at P = {pressure:g}")
    return th
