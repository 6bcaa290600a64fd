"""Photograph-like images of the fixture from a known shape, with the ground truth.

The test suite measures on these images like the paper's 54 printed ground-truth
shapes (Sec. V-A, Fig. 19). Every real-camera nuisance of the issue is a setting:
rotation, radial lens distortion (from a calibration), blur, sensor noise, JPEG
artefacts, uneven lighting, resolution.

World frame (mm): the left pin at the origin, x along the pin line, y up (the
wall at +h). The tube is drawn analytically (exact distance to its centerline,
anti-aliased to 1/2 px), so the truth is the shape given, not a raster of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
from scipy.spatial import cKDTree

from .errors import VisionError

#: OpenCV ArUco dictionary of the fixture's marker.
ARUCO_DICT = cv2.aruco.DICT_4X4_50
TUBE_BGR = (40, 110, 235)     # orange silicone
BACKGROUND = 225              # light grey board
BEARING_GREY = 30
WALL_GREY = 120


def arc_sections(theta_deg: float, length: float = 30.0, sections: int = 3,
                 spacing: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Centerline (mm) of an unconstrained k-section actuator and its inflection points.

    Each section is a circular arc of bend angle θ and length ℓ (eq. 2); consecutive
    sections bend in opposite directions and the middle one (index k // 2) bulges
    towards +y. Tangent continuity then puts the pins and every inflection point on
    the x axis, as in the paper's fixture.
    """
    theta = math.radians(theta_deg)
    if not (0 < theta < 2 * math.pi) or length <= 0 or sections < 1:
        raise VisionError("theta must be in (0, 360) deg, length > 0 and sections >= 1")
    mid = sections // 2
    pts, knots = [np.zeros((1, 2))], [np.zeros(2)]
    x0 = y0 = 0.0
    for j in range(sections):
        up = 1 if (j - mid) % 2 == 0 else -1        # the middle section bulges up
        phi0, kappa = up * theta / 2, -up * theta / length
        n = max(int(math.ceil(length / spacing)), 2)
        s = np.linspace(0, length, n + 1)[1:]
        x = x0 + (np.sin(phi0 + kappa * s) - math.sin(phi0)) / kappa
        y = y0 - (np.cos(phi0 + kappa * s) - math.cos(phi0)) / kappa
        pts.append(np.column_stack([x, y]))
        x0, y0 = float(x[-1]), float(y[-1])
        knots.append(np.array([x0, y0]))
    return np.vstack(pts), np.array(knots[1:-1])


def with_end_sections(middle: np.ndarray, length: float = 30.0, sections: int = 3,
                      spacing: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """A constrained middle section (mm, pins on y = 0) with unconstrained outer sections.

    Each outer section is the arc that continues the middle section's end tangent
    (angle φ_e) with bend angle 2·φ_e and length ℓ, so its far end is again on the
    pin line. Returns the whole centerline and the inflection points (the middle
    section's ends).
    """
    m = np.asarray(middle, float)
    if sections == 1:
        return m, np.zeros((0, 2))
    if sections != 3:
        raise VisionError("a constrained shape is drawn with 1 or 3 sections")
    phi_l = math.atan2(m[1, 1] - m[0, 1], m[1, 0] - m[0, 0])
    phi_r = math.atan2(m[-1, 1] - m[-2, 1], m[-1, 0] - m[-2, 0])
    n = max(int(math.ceil(length / spacing)), 2)
    s = np.linspace(0, length, n + 1)

    def arc(p0, phi0, kappa):
        if abs(kappa) < 1e-12:
            return p0 + np.column_stack([s * math.cos(phi0), s * math.sin(phi0)])
        x = p0[0] + (np.sin(phi0 + kappa * s) - math.sin(phi0)) / kappa
        y = p0[1] - (np.cos(phi0 + kappa * s) - math.cos(phi0)) / kappa
        return np.column_stack([x, y])

    right = arc(m[-1], phi_r, -2 * phi_r / length)
    # the left one, traced from the inflection point backwards, then reversed
    left = arc(m[0], phi_l + math.pi, -2 * phi_l / length)[::-1]
    return np.vstack([left[:-1], m, right[1:]]), np.array([m[0], m[-1]])


def default_calibration(width: int, height: int) -> dict:
    """A plausible camera: focal length 1.1 image widths, mild barrel distortion."""
    f = 1.1 * width
    return {"camera_matrix": [[f, 0.0, width / 2 + 3.3], [0.0, f, height / 2 - 2.1],
                              [0.0, 0.0, 1.0]],
            "dist_coeffs": [-0.12, 0.05, 0.0005, -0.0003, 0.0]}


@dataclass
class Nuisances:
    """Every real-camera nuisance of a rendered photograph (all off by default).

    rotation_deg: in-plane rotation of the fixture (the issue: up to ±10°);
    distort: apply the radial lens distortion of ``calibration`` (or of
    :func:`default_calibration`); blur: Gaussian σ (px); noise: σ of additive
    Gaussian sensor noise (grey levels); jpeg: JPEG quality (None: lossless);
    lighting: strength of the uneven illumination (0.3: ±15 % plus vignetting).
    """

    rotation_deg: float = 0.0
    distort: bool = False
    calibration: dict | None = None
    blur: float = 0.0
    noise: float = 0.0
    jpeg: int | None = None
    lighting: float = 0.0
    seed: int = 0
    extra: dict = field(default_factory=dict)

    @classmethod
    def all_on(cls, seed: int = 0) -> Nuisances:
        """Every nuisance on, at the strength of a careful bench photograph; the
        rotation drawn in ±10° from ``seed``."""
        rng = np.random.default_rng(seed)
        return cls(rotation_deg=float(rng.uniform(-10, 10)), distort=True, blur=1.0,
                   noise=4.0, jpeg=85, lighting=0.35, seed=seed)


def _coverage_polygon(xx, yy, corners):
    """Anti-aliased coverage of a convex polygon (corners counter-clockwise, px)."""
    d = np.full(xx.shape, -np.inf)
    for a, b in zip(corners, np.roll(corners, -1, axis=0)):
        e = b - a
        nrm = np.array([e[1], -e[0]]) / np.hypot(*e)   # outward for ccw in image coords
        d = np.maximum(d, (xx - a[0]) * nrm[0] + (yy - a[1]) * nrm[1])
    return np.clip(0.5 - d, 0, 1)


def _paint_polygon(img, corners, value) -> None:
    """Blend a convex polygon (px) of grey ``value`` into ``img``, in its bounding box."""
    x0, y0 = np.maximum(np.floor(corners.min(axis=0)).astype(int) - 2, 0)
    x1, y1 = np.ceil(corners.max(axis=0)).astype(int) + 3
    yy, xx = np.mgrid[y0:min(y1, img.shape[0]), x0:min(x1, img.shape[1])].astype(float)
    cov = _coverage_polygon(xx, yy, _ccw(corners))[..., None]
    win = img[y0:y0 + cov.shape[0], x0:x0 + cov.shape[1]]
    win *= 1 - cov
    win += value * cov


def _ccw(c):
    c = np.asarray(c, float)
    area = np.sum(c[:, 0] * np.roll(c[:, 1], -1) - np.roll(c[:, 0], -1) * c[:, 1])
    return c if area < 0 else c[::-1]  # image y is down: "ccw" on screen


def tube_colour(hue_deg: float) -> tuple[int, int, int]:
    """BGR of a tube of hue ``hue_deg`` (0-360) with the default tube's saturation
    and brightness (the default orange is hue ≈ 22°)."""
    s, v = cv2.cvtColor(np.uint8([[TUBE_BGR]]), cv2.COLOR_BGR2HSV_FULL)[0, 0, 1:]
    h = int(round(hue_deg / 360 * 256)) % 256
    return tuple(int(c) for c in cv2.cvtColor(np.uint8([[[h, s, v]]]),
                                              cv2.COLOR_HSV2BGR_FULL)[0, 0])


def render(centerline_mm, *, px_per_mm: float = 15.0, diameter: float = 3.0,
           bearing_diameter: float = 6.0, marker_mm: float = 25.0, tube_bgr=TUBE_BGR,
           wall_height: float | None = None, wall_span: tuple[float, float] | None = None,
           nuisances: Nuisances | None = None, margin_mm: float = 8.0,
           marker_id: int = 7) -> tuple[np.ndarray, dict]:
    """Draw the fixture around a centerline; returns (BGR uint8 image, ground truth).

    Parameters
    ----------
    centerline_mm : (n, 2) array, the tube's centerline in the world frame; its two
        ends are the pins (bearing centres).
    px_per_mm : resolution (the issue: 10-25 px/mm).
    diameter : outer diameter of the tube (mm).
    bearing_diameter : diameter of the dark pin-bearing discs (mm).
    marker_mm : side of the ArUco marker (DICT_4X4_50).
    wall_height : if given, two wall bars whose faces are at y = ±wall_height.
    wall_span : x range of the walls (default: the whole centerline).
    nuisances : see :class:`Nuisances` (default: none).
    tube_bgr : the tube's colour, BGR (default orange; :func:`tube_colour` gives any hue).

    Returns
    -------
    image : (H, W, 3) uint8, BGR (OpenCV's order).
    truth : dict with the pins, the marker corners and the transform world → pixel
        of the undistorted image, the calibration used (if distorted) and the settings.
    """
    nz = nuisances or Nuisances()
    c = np.asarray(centerline_mm, float)
    rng = np.random.default_rng(nz.seed)
    rad, rb = diameter / 2, bearing_diameter / 2
    lo = np.minimum(c.min(axis=0) - max(rad, rb), [np.inf, -(wall_height or 0) - 4])
    hi = np.maximum(c.max(axis=0) + max(rad, rb), [-np.inf, (wall_height or 0) + 4])
    mx = 0.5 * (c[0, 0] + c[-1, 0]) - marker_mm / 2
    my = lo[1] - 6.0 - marker_mm          # marker's lower-left corner, below everything
    lo = np.minimum(lo, [mx - 4, my - 4])
    hi = np.maximum(hi, [mx + marker_mm + 4, hi[1]])
    lo, hi = lo - margin_mm, hi + margin_mm
    ang = math.radians(nz.rotation_deg)
    rot = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
    box = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    flip = np.array([1.0, -1.0])

    def lin(p):  # world mm -> px before the offset: scale, flip y, rotate
        return (np.asarray(p, float) * flip) @ rot.T * px_per_mm

    pb = lin(box)
    off = -pb.min(axis=0)
    width, height = (np.ceil(pb.max(axis=0) + off)).astype(int) + 1

    def to_px(p):
        return lin(p) + off

    img = np.full((height, width, 3), float(BACKGROUND))

    # marker on a white card
    card = marker_mm * 0.2
    cc = to_px([[mx - card, my - card], [mx + marker_mm + card, my - card],
                [mx + marker_mm + card, my + marker_mm + card], [mx - card, my + marker_mm + card]])
    _paint_polygon(img, cc, 245.0)
    side = 600
    tag = cv2.aruco.generateImageMarker(cv2.aruco.getPredefinedDictionary(ARUCO_DICT),
                                        marker_id, side).astype(np.float32)
    shrink = side / (marker_mm * px_per_mm)
    tag = cv2.GaussianBlur(tag, (0, 0), max(0.5 * shrink, 0.3))
    corners = to_px([[mx, my + marker_mm], [mx + marker_mm, my + marker_mm],
                     [mx + marker_mm, my], [mx, my]])  # TL, TR, BR, BL as drawn
    a = cv2.getAffineTransform(np.float32([[-.5, -.5], [side - .5, -.5], [-.5, side - .5]]),
                               np.float32(corners[[0, 1, 3]]))
    x0, y0 = np.floor(corners.min(axis=0)).astype(int) - 2
    x1, y1 = np.ceil(corners.max(axis=0)).astype(int) + 3
    a[:, 2] -= (x0, y0)
    t_img = cv2.warpAffine(tag, a, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR)
    t_cov = cv2.warpAffine(np.ones_like(tag), a, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR)
    tone = 25 + t_img.astype(float) / 255 * 220
    win = img[y0:y1, x0:x1]
    win *= 1 - t_cov[..., None]
    win += (tone * t_cov)[..., None]

    # walls: bars 4 mm thick whose faces are at ±wall_height
    if wall_height is not None:
        x0, x1 = wall_span if wall_span is not None else (c[0, 0], c[-1, 0])
        for y0, y1 in ((wall_height, wall_height + 4), (-wall_height - 4, -wall_height)):
            wc = to_px([[x0 - 3, y0], [x1 + 3, y0], [x1 + 3, y1], [x0 - 3, y1]])
            _paint_polygon(img, wc, float(WALL_GREY))

    # the tube: exact distance to its centerline, shaded like a cylinder
    cpx = to_px(c)
    r_px = rad * px_per_mm
    band = np.zeros((height, width), np.uint8)
    cv2.polylines(band, [np.round(cpx * 16).astype(np.int32)], False, 255,
                  thickness=int(2 * r_px + 8), shift=4)
    iy, ix = np.nonzero(band)
    dense = _densify(cpx, 0.25)
    d, _ = cKDTree(dense).query(np.column_stack([ix, iy]), distance_upper_bound=r_px + 3)
    d = np.minimum(d, r_px + 3)
    cov = np.clip(r_px - d + 0.5, 0, 1)
    shade = 0.72 + 0.28 * np.sqrt(np.clip(1 - (d / r_px) ** 2, 0, 1))
    colour = np.asarray(tube_bgr, float)[None, :] * shade[:, None]
    img[iy, ix] = img[iy, ix] * (1 - cov[:, None]) + colour * cov[:, None]

    # the two pin bearings, on top of the tube's ends
    pins = to_px(c[[0, -1]])
    rbp = rb * px_per_mm
    for p in pins:
        x0, y0 = np.floor(p - rbp).astype(int) - 2
        x1, y1 = np.ceil(p + rbp).astype(int) + 3
        yy, xx = np.mgrid[y0:y1, x0:x1].astype(float)
        cov = np.clip(rbp - np.hypot(xx - p[0], yy - p[1]) + 0.5, 0, 1)[..., None]
        win = img[y0:y1, x0:x1]
        win *= 1 - cov
        win += BEARING_GREY * cov

    if nz.lighting:
        u = (np.arange(width) / width - 0.5)[None, :]
        v = (np.arange(height) / height - 0.5)[:, None]
        light = 1 + nz.lighting * (0.5 * u - 0.3 * v) - nz.lighting * 0.6 * (u ** 2 + v ** 2)
        img *= light[..., None]
    truth = {"px_per_mm": px_per_mm, "rotation_deg": nz.rotation_deg,
             "pins_px": pins.tolist(), "marker_corners_px": corners.tolist(),
             "marker_mm": marker_mm, "diameter_mm": diameter, "tube_bgr": list(tube_bgr),
             "bearing_diameter_mm": bearing_diameter, "wall_height_mm": wall_height,
             "image_size": [int(width), int(height)],
             "settings": {k: v for k, v in vars(nz).items() if k not in ("calibration", "extra")}}
    if nz.distort:
        calib = nz.calibration or default_calibration(int(width), int(height))
        img = distort(img, calib)
        truth["calibration"] = calib
    if nz.blur:
        img = cv2.GaussianBlur(img, (0, 0), nz.blur)
    if nz.noise:
        img = img + rng.normal(0, nz.noise, img.shape)
    out = np.clip(np.round(img), 0, 255).astype(np.uint8)
    if nz.jpeg is not None:
        ok, buf = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, int(nz.jpeg)])
        out = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return out, truth


def _densify(p: np.ndarray, step: float) -> np.ndarray:
    seg = np.diff(p, axis=0)
    n = np.maximum(np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / step).astype(int), 1)
    t = np.concatenate([np.arange(k) / k for k in n])
    i = np.repeat(np.arange(len(seg)), n)
    return np.vstack([p[i] + t[:, None] * seg[i], p[-1:]])


def distort(img: np.ndarray, calibration: dict) -> np.ndarray:
    """What a lens with ``calibration`` makes of the ideal image ``img``: the inverse
    of OpenCV's ``undistort`` (same camera matrix)."""
    k = np.asarray(calibration["camera_matrix"], float)
    dist = np.asarray(calibration["dist_coeffs"], float)
    h, w = img.shape[:2]
    step = 8  # the map is smooth: computed every 8 px, interpolated (error < 0.01 px)
    gh, gw = h // step + 2, w // step + 2
    yy, xx = np.mgrid[0:gh, 0:gw].astype(np.float64) * step
    xd = (xx - k[0, 2]) / k[0, 0]
    yd = (yy - k[1, 2]) / k[1, 1]
    k1, k2, p1, p2, k3 = (list(dist) + [0.0] * 5)[:5]
    xu, yu = xd.copy(), yd.copy()
    for _ in range(20):  # fixed point of OpenCV's distortion model (x_d = f(x_u))
        r2 = xu * xu + yu * yu
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        dx = 2 * p1 * xu * yu + p2 * (r2 + 2 * xu * xu)
        dy = p1 * (r2 + 2 * yu * yu) + 2 * p2 * xu * yu
        xu, yu = (xd - dx) / radial, (yd - dy) / radial
    mapx = (xu * k[0, 0] + k[0, 2]).astype(np.float32)
    mapy = (yu * k[1, 1] + k[1, 2]).astype(np.float32)
    gx = np.broadcast_to((np.arange(w, dtype=np.float32) / step)[None, :], (h, w)).copy()
    gy = np.broadcast_to((np.arange(h, dtype=np.float32) / step)[:, None], (h, w)).copy()
    mapx = cv2.remap(mapx, gx, gy, cv2.INTER_LINEAR)
    mapy = cv2.remap(mapy, gx, gy, cv2.INTER_LINEAR)
    return cv2.remap(img.astype(np.float32), mapx, mapy, cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REPLICATE).astype(np.float64)


def render_unconstrained(theta_deg: float, *, length: float = 30.0, sections: int = 3,
                         **kw) -> tuple[np.ndarray, dict]:
    """An unconstrained actuator of bend angle θ per section (the paper's printed
    ground truth); the truth adds θ, ℓ, the radius ℓ/θ and the inflection points."""
    c, knots = arc_sections(theta_deg, length, sections)
    img, truth = render(c, **kw)
    truth.update(theta_deg=theta_deg, arc_length_mm=length, sections=sections,
                 radius_mm=length / math.radians(theta_deg),
                 inflection_points_mm=knots.tolist())
    return img, truth


def render_constrained(x, y, *, wall_height: float, length: float = 30.0,
                       sections: int = 3, **kw) -> tuple[np.ndarray, dict]:
    """A constrained middle section given by its centerline points (e.g. a
    :class:`lcpbench.ContactResult`'s x, y), between walls whose faces are at
    ±wall_height, with the unconstrained outer sections that continue it."""
    mid = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    c, knots = with_end_sections(mid, length, sections)
    img, truth = render(c, wall_height=wall_height, wall_span=(mid[0, 0], mid[-1, 0]), **kw)
    truth.update(sections=sections, middle_mm=mid.tolist(),
                 inflection_points_mm=knots.tolist())
    return img, truth
