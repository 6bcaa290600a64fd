"""A second, independent renderer of test photographs of the fixture (issue 41, item 4).

It shares no drawing code with :mod:`lcpbench.vision.render` (the pipeline's own
renderer), so a measurement checked on both is not checked against one
rasteriser's habits:

- **geometry** in closed form from the arcs' centres: section j is a circle of
  radius R = ℓ/θ about a centre below or above the pin line, the middle section
  (index k // 2) bulging up; the tube's outline is the two concentric arcs at
  R ± d/2 (exact offset curves), not a distance field;
- **rasteriser**: matplotlib's Agg (exact-area anti-aliasing of filled paths,
  snapping off), drawing into an RGBA buffer;
- **the fixture**: bearings as dark discs with a light hub, paper texture, a soft
  shadow band across the scene, a cylinder's limb darkening and highlight on the
  tube, the ArUco marker (DICT_4X4_50, drawn cell by cell from its bits as one
  compound path) above, below, left or right of the actuator, any tube hue;
- **camera**: in-plane rotation, radial and tangential lens distortion applied
  through OpenCV's iterative ``undistortPoints`` (not the fixed point of the
  other renderer) and scipy's cubic-spline resampling, Pillow's Gaussian blur and
  JPEG encoder, signal-dependent noise.

World frame (mm): the left pin at the origin, x along the pin line, y up.
Pixel coordinates are OpenCV's (the centre of the top-left pixel is (0, 0)).
Used by tests/vision/test_agg_photos.py and benchmarks/vision_accuracy.py.
"""

from __future__ import annotations

import colorsys
import io
import math
from dataclasses import asdict, dataclass

import cv2
import numpy as np

MARKER_SIDES = ("below", "above", "left", "right")


@dataclass
class Scene:
    """One photograph's settings: the actuator (θ per section, ℓ, diameter, k
    sections), the fixture and the camera. Every nuisance is on by default."""

    theta_deg: float
    length_mm: float = 30.0
    sections: int = 3
    diameter_mm: float = 3.0
    px_per_mm: float = 15.0
    hue_deg: float = 22.0          # tube hue, 0-360 (colour wheel)
    rotation_deg: float = 0.0
    marker_side: str = "below"
    marker_mm: float = 25.0
    marker_id: int = 7
    bearing_mm: float = 6.0
    hub_mm: float = 1.8            # light hub in the dark bearing
    texture: float = 5.0           # paper grain, grey levels
    shadow: bool = True            # a soft shadow band across the scene
    highlight: bool = True         # the cylinder's highlight, off the tube's axis
    occluder: tuple[float, float] | None = None   # a grey bar across the tube: (x, width) mm
    distortion: bool = True
    blur_px: float = 1.0
    noise: float = 3.0             # sensor noise at mid grey, grey levels
    jpeg: int | None = 88
    seed: int = 0

    @classmethod
    def varied(cls, theta_deg: float, seed: int, **kw) -> Scene:
        """A scene whose nuisances are drawn from ``seed``: ℓ in 20-35 mm, hue
        anywhere on the wheel, rotation in ±10°, marker side, 10-25 px/mm."""
        rng = np.random.default_rng(seed)
        base = dict(theta_deg=float(theta_deg), length_mm=float(rng.uniform(20, 35)),
                    hue_deg=float(rng.uniform(0, 360)),
                    rotation_deg=float(rng.uniform(-10, 10)),
                    marker_side=MARKER_SIDES[int(rng.integers(4))],
                    px_per_mm=float(rng.uniform(10, 25)), hub_mm=float(rng.uniform(1.2, 2.4)),
                    jpeg=int(rng.integers(80, 95)), seed=int(seed))
        base.update(kw)
        return cls(**base)


def arcs(theta_deg: float, length_mm: float, sections: int = 3) -> list[dict]:
    """Each section as a circle arc: centre, radius, start and end angle (rad, from
    the centre, counter-clockwise positive), and the pins it joins."""
    th = math.radians(theta_deg)
    if not (0 < th < 2 * math.pi) or length_mm <= 0 or sections < 1:
        raise ValueError("theta_deg must be in (0, 360), length_mm > 0, sections >= 1")
    r = length_mm / th
    chord = 2 * r * math.sin(th / 2)
    mid = sections // 2
    out = []
    for j in range(sections):
        a = j * chord
        if (j - mid) % 2 == 0:       # bulges up: centre below, traversed clockwise
            c = (a + chord / 2, -r * math.cos(th / 2))
            a0, a1 = math.pi / 2 + th / 2, math.pi / 2 - th / 2
        else:                        # bulges down: centre above, counter-clockwise
            c = (a + chord / 2, r * math.cos(th / 2))
            a0, a1 = 3 * math.pi / 2 - th / 2, 3 * math.pi / 2 + th / 2
        out.append({"centre": np.array(c), "radius": r, "a0": a0, "a1": a1,
                    "pins": np.array([[a, 0.0], [a + chord, 0.0]])})
    return out


def _arc_points(arc: dict, offset: float, step_mm: float = 0.01) -> np.ndarray:
    """Points of the arc concentric with ``arc`` at radius R + offset (mm)."""
    n = max(int(abs(arc["a1"] - arc["a0"]) * arc["radius"] / step_mm), 8)
    a = np.linspace(arc["a0"], arc["a1"], n + 1)
    r = arc["radius"] + offset
    return arc["centre"] + r * np.column_stack([np.cos(a), np.sin(a)])


def _band(chain: list[dict], lo: float, hi: float) -> np.ndarray:
    """Closed outline (mm) of the strip between the signed offsets lo < hi from the
    centerline (+: to the left of the direction of travel)."""
    left, right = [], []
    for arc in chain:
        # travel clockwise (a1 < a0): left of travel is away from the centre
        sgn = 1.0 if arc["a1"] < arc["a0"] else -1.0
        left.append(_arc_points(arc, sgn * hi))
        right.append(_arc_points(arc, sgn * lo))
    return np.vstack([np.vstack(left), np.vstack(right)[::-1]])


def tube_rgb(hue_deg: float, value: float = 0.85) -> np.ndarray:
    """RGB (0-1) of a saturated silicone tube of hue ``hue_deg``."""
    return np.array(colorsys.hsv_to_rgb((hue_deg % 360) / 360, 0.82, value))


def _marker_cells(marker_id: int) -> np.ndarray:
    """The marker's 6 × 6 cells (1 white, 0 black; the outer ring is the black border)."""
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    return (cv2.aruco.generateImageMarker(d, marker_id, 6, borderBits=1) > 127).astype(int)


def draw(scene: Scene) -> tuple[np.ndarray, dict]:
    """Draw the photograph of ``scene``; returns (BGR uint8 image, truth).

    truth: θ (deg) and ℓ (mm) of every section, the pins (px in the undistorted
    image), px/mm, the calibration the image was distorted with (None if not) and
    the scene's settings.
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle, PathPatch, Polygon
    from matplotlib.path import Path

    s = scene
    if s.marker_side not in MARKER_SIDES:
        raise ValueError(f"marker_side must be one of {MARKER_SIDES}, got {s.marker_side!r}")
    rng = np.random.default_rng(s.seed)
    chain = arcs(s.theta_deg, s.length_mm, s.sections)
    rad, rb = s.diameter_mm / 2, s.bearing_mm / 2
    outline = _band(chain, -rad, rad)
    span = chain[-1]["pins"][1, 0]
    lo = np.minimum(outline.min(axis=0), [-rb, -rb])
    hi = np.maximum(outline.max(axis=0), [span + rb, rb])
    m, gap, card = s.marker_mm, 7.0, 0.2 * s.marker_mm
    cx, cy = 0.5 * (lo + hi)
    corner = {"below": (cx - m / 2, lo[1] - gap - card - m),
              "above": (cx - m / 2, hi[1] + gap + card),
              "left": (lo[0] - gap - card - m, cy - m / 2),
              "right": (hi[0] + gap + card, cy - m / 2)}[s.marker_side]
    mx, my = corner
    lo = np.minimum(lo, [mx - card, my - card])
    hi = np.maximum(hi, [mx + m + card, my + m + card])
    lo, hi = lo - 7.0, hi + 7.0

    ang = math.radians(s.rotation_deg)
    rot = np.array([[math.cos(ang), math.sin(ang)], [-math.sin(ang), math.cos(ang)]])

    def lin(p):   # mm -> px before the offset: y flipped (image y down), then rotated
        q = np.asarray(p, float) * [1.0, -1.0] * s.px_per_mm
        return q @ rot.T

    box = lin([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    off = -box.min(axis=0) + 2.0
    w, h = (np.ceil(box.max(axis=0) + off + 2.0)).astype(int)

    def px(p):
        return lin(p) + off

    dpi = 100.0
    fig = Figure(figsize=(w / dpi, h / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1))
    ax.set_axis_off()
    ax.set_xlim(-0.5, w - 0.5)     # OpenCV: pixel i covers [i - 1/2, i + 1/2]
    ax.set_ylim(h - 0.5, -0.5)

    def poly(points_mm, colour, **kw):
        ax.add_artist(Polygon(px(points_mm), closed=True, facecolor=colour, edgecolor="none",
                             antialiased=True, snap=False, **kw))

    paper = np.array([0.87, 0.86, 0.83])
    fig.patch.set_facecolor(paper)
    ax.set_facecolor(paper)
    # marker: a white card, the black square, its white cells as one compound path
    poly([[mx - card, my - card], [mx + m + card, my - card], [mx + m + card, my + m + card],
          [mx - card, my + m + card]], (0.97, 0.97, 0.96))
    poly([[mx, my], [mx + m, my], [mx + m, my + m], [mx, my + m]], (0.08, 0.08, 0.08))
    cells = _marker_cells(s.marker_id)
    cell, verts, codes = m / 6, [], []
    for i, j in zip(*np.nonzero(cells)):          # row i from the top, column j
        x0, y0 = mx + j * cell, my + m - (i + 1) * cell
        sq = px([[x0, y0], [x0 + cell, y0], [x0 + cell, y0 + cell], [x0, y0 + cell], [x0, y0]])
        verts += sq.tolist()
        codes += [Path.MOVETO] + [Path.LINETO] * 3 + [Path.CLOSEPOLY]
    if verts:
        ax.add_artist(PathPatch(Path(verts, codes), facecolor=(0.96, 0.96, 0.95),
                               edgecolor="none", snap=False))
    # the tube: limb darkening, body, an off-centre highlight
    base = tube_rgb(s.hue_deg)
    poly(outline, base * 0.78)
    poly(_band(chain, -0.75 * rad, 0.75 * rad), base * 0.92)
    poly(_band(chain, -0.45 * rad, 0.45 * rad), base)
    if s.highlight:
        poly(_band(chain, 0.05 * rad, 0.35 * rad), np.minimum(base * 0.75 + 0.25, 1))
    if s.occluder is not None:    # a bar across the pin line's upper side (not the marker)
        x, bw = s.occluder
        top = outline[:, 1].max() + 1.0
        poly([[x - bw / 2, -1.0], [x + bw / 2, -1.0], [x + bw / 2, top], [x - bw / 2, top]],
             (0.45, 0.45, 0.46))
    # bearings with a light hub, over the tube's ends
    pins_mm = np.array([[0.0, 0.0], [span, 0.0]])
    for p in px(pins_mm):
        ax.add_artist(Circle(p, rb * s.px_per_mm, facecolor=(0.12, 0.12, 0.13),
                            edgecolor="none", snap=False))
        ax.add_artist(Circle(p, s.hub_mm / 2 * s.px_per_mm, facecolor=(0.72, 0.72, 0.70),
                            edgecolor="none", snap=False))
    canvas.draw()
    rgb = np.asarray(canvas.buffer_rgba())[..., :3].astype(np.float64)

    # paper grain and a shadow band (multiplicative: they darken everything under them)
    if s.texture:
        g = rng.normal(0, 1, (h, w))
        g = cv2.GaussianBlur(g, (0, 0), 0.7) * s.texture / 0.4
        rgb += g[..., None]
    if s.shadow:
        yy, xx = np.mgrid[0:h, 0:w].astype(float)
        t = rng.uniform(0.2, 0.8) * w + rng.uniform(-0.3, 0.3) * (yy - h / 2)
        width, soft = rng.uniform(0.08, 0.2) * w, 0.03 * w
        inside = 1 / (1 + np.exp(-(xx - t) / soft)) * 1 / (1 + np.exp((xx - t - width) / soft))
        rgb *= (1 - 0.3 * inside)[..., None]
    truth = {"theta_deg": [s.theta_deg] * s.sections, "arc_length_mm": [s.length_mm] * s.sections,
             "middle": s.sections // 2, "pins_px": px(pins_mm).tolist(),
             "px_per_mm": s.px_per_mm, "image_size": [int(w), int(h)], "calibration": None,
             "scene": asdict(s)}
    if s.distortion:
        calib = {"camera_matrix": [[0.95 * w, 0.0, 0.5 * w - 4.1], [0.0, 0.95 * w, 0.5 * h + 2.7],
                                   [0.0, 0.0, 1.0]],
                 "dist_coeffs": [-0.09, 0.03, -0.0004, 0.0006, 0.0]}
        rgb = _distort(rgb, calib)
        truth["calibration"] = calib
    img = np.clip(rgb, 0, 255)
    from PIL import Image, ImageFilter

    im = Image.fromarray(np.round(img).astype(np.uint8))
    if s.blur_px:
        im = im.filter(ImageFilter.GaussianBlur(s.blur_px))
    img = np.asarray(im).astype(np.float64)
    if s.noise:     # shot noise grows with the signal: σ = noise at grey 128
        img += rng.normal(0, 1, img.shape) * s.noise * np.sqrt(np.maximum(img, 1) / 128)
    im = Image.fromarray(np.clip(np.round(img), 0, 255).astype(np.uint8))
    if s.jpeg is not None:
        buf = io.BytesIO()
        im.save(buf, format="JPEG", quality=int(s.jpeg))
        buf.seek(0)
        im = Image.open(buf).convert("RGB")
    return np.ascontiguousarray(np.asarray(im)[..., ::-1]), truth


def _distort(rgb: np.ndarray, calib: dict) -> np.ndarray:
    """The image a lens with ``calib`` makes of the ideal image: each output pixel
    samples the ideal image (cubic spline, scipy) where OpenCV's iterative
    undistortion sends it. Not ``cv2.remap``: it rounds positions to 1/32 px, which
    biased θ by up to 0.03 % here (three times the pipeline's standard error)."""
    from scipy.ndimage import map_coordinates

    k = np.asarray(calib["camera_matrix"], float)
    d = np.asarray(calib["dist_coeffs"], float)
    h, w = rgb.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    pts = np.column_stack([xx.ravel(), yy.ravel()]).reshape(-1, 1, 2)
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10)
    und = cv2.undistortPoints(pts, k, d, None, None, k, crit).reshape(h, w, 2)
    return np.dstack([map_coordinates(rgb[..., c], [und[..., 1], und[..., 0]], order=3,
                                      mode="nearest") for c in range(3)])
