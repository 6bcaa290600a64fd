"""The image stages of the paper's pipeline (Sec. IV-D-1 to IV-D-4), each callable alone.

undistort → marker scale → pin bearings and levelling → segmentation → centerline.
Pixel coordinates are OpenCV's (x right, y down, origin at the top-left pixel's centre).
"""

from __future__ import annotations

import json
import math
import os
from collections import deque
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.ndimage import gaussian_filter1d

from .errors import VisionError
from .geometry import resample

ARUCO_DICT = cv2.aruco.DICT_4X4_50


# -- input ----------------------------------------------------------------------
def load_image(path: str | os.PathLike) -> np.ndarray:
    """Read a colour photograph (PNG, JPEG, ...) as BGR uint8; VisionError if it is not one."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise VisionError(f"{path}: no such file")
    img = cv2.imread(path, cv2.IMREAD_COLOR)
    if img is None:
        raise VisionError(f"{path}: not an image OpenCV can read (give a PNG or JPEG photograph)")
    return img


def load_calibration(source) -> dict:
    """An OpenCV camera calibration: a JSON file (or dict) with ``camera_matrix`` (3×3)
    and ``dist_coeffs`` [k1, k2, p1, p2, k3] (4, 5 or 8 numbers accepted).

    Raises VisionError, naming the field to fix, on any other shape.
    """
    name = "calibration"
    if not isinstance(source, dict):
        name = os.fspath(source)
        try:
            with open(name) as fh:
                source = json.load(fh)
        except (OSError, ValueError) as exc:
            raise VisionError(f"calibration {name}: not a readable JSON file ({exc})") from None
    try:
        k = np.asarray(source["camera_matrix"], float)
        d = np.asarray(source["dist_coeffs"], float).ravel()
    except (KeyError, TypeError, ValueError):
        raise VisionError(f"calibration {name}: needs 'camera_matrix' (3x3 numbers) and "
                          f"'dist_coeffs' ([k1, k2, p1, p2, k3])") from None
    if k.shape != (3, 3) or not np.all(np.isfinite(k)) or k[0, 0] <= 0 or k[1, 1] <= 0 \
            or not np.allclose(k[2], [0, 0, 1]):
        raise VisionError(f"calibration {name}: camera_matrix must be 3x3 [[fx,0,cx],[0,fy,cy],"
                          f"[0,0,1]] with fx, fy > 0, got shape {k.shape}")
    if d.size not in (4, 5, 8) or not np.all(np.isfinite(d)):
        raise VisionError(f"calibration {name}: dist_coeffs must be [k1, k2, p1, p2, k3] "
                          f"(4, 5 or 8 numbers), got {d.size}")
    return {"camera_matrix": k.tolist(), "dist_coeffs": d.tolist()}


def undistort(img: np.ndarray, calibration: dict) -> np.ndarray:
    """Rectify the lens distortion (Sec. IV-D-1; OpenCV ``undistort``, same camera matrix)."""
    cal = load_calibration(calibration)
    return cv2.undistort(img, np.asarray(cal["camera_matrix"]), np.asarray(cal["dist_coeffs"]))


# -- marker scale ----------------------------------------------------------------
@dataclass
class Marker:
    """The ArUco marker: corners (4, 2) px (its own order), id, and px per mm."""

    corners: np.ndarray
    id: int
    px_per_mm: float


def detect_marker(img: np.ndarray, marker_mm: float = 25.0) -> Marker:
    """Scale from the ArUco marker (DICT_4X4_50) of side ``marker_mm`` (Sec. IV-D-2).

    Corners are refined to sub-pixel; px/mm is the mean of the four side lengths
    over the side in mm. With several markers the largest is used.
    """
    if not (marker_mm > 0 and math.isfinite(marker_mm)):
        raise VisionError(f"--marker-mm must be a positive length, got {marker_mm}")
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    params.cornerRefinementWinSize = 7
    params.cornerRefinementMaxIterations = 100
    params.cornerRefinementMinAccuracy = 0.001
    det = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(ARUCO_DICT), params)
    gray = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    corners, ids, _ = det.detectMarkers(gray)
    if ids is None or len(ids) == 0:
        raise VisionError("no ArUco marker (DICT_4X4_50) found: put the marker flat in the "
                          "actuator's plane, in view and in focus")
    sides = [np.hypot(*np.diff(np.vstack([c[0], c[0][:1]]), axis=0).T) for c in corners]
    best = int(np.argmax([s.mean() for s in sides]))
    quad = _refine_quad(gray.astype(np.float32), corners[best][0].astype(float))
    side = np.hypot(*np.diff(np.vstack([quad, quad[:1]]), axis=0).T)
    return Marker(quad, int(np.ravel(ids)[best]), float(side.mean() / marker_mm))


def _refine_quad(gray: np.ndarray, quad: np.ndarray) -> np.ndarray:
    """Corners of the marker's black square as intersections of straight lines fitted
    to its four outer edges (sub-pixel edge points along each side, the middle 70 %):
    hundreds of edge points per side instead of one corner window each."""
    g = cv2.GaussianBlur(gray, (0, 0), 0.8)
    centre = quad.mean(axis=0)
    lines = []
    for a, b in zip(quad, np.roll(quad, -1, axis=0)):
        e = b - a
        length = float(np.hypot(*e))
        u = e / length
        n = np.array([-u[1], u[0]])
        if n @ (a - centre) < 0:
            n = -n                                   # outward
        s = np.linspace(0.15, 0.85, max(int(0.7 * length), 10))
        t = np.arange(-6, 6.01, 0.25)
        base = a[None, :] + s[:, None] * e[None, :]
        mx = (base[:, 0:1] + t[None, :] * n[0]).astype(np.float32)
        my = (base[:, 1:2] + t[None, :] * n[1]).astype(np.float32)
        prof = cv2.remap(g, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        lo, hi = prof[:, :8].mean(axis=1), prof[:, -8:].mean(axis=1)
        level = 0.5 * (lo + hi)
        above = prof >= level[:, None]
        j = np.argmax(above, axis=1)
        ok = above.any(axis=1) & (j > 0) & (hi - lo > 20)
        if ok.sum() < 5:
            return quad
        i = np.nonzero(ok)[0]
        j = j[ok]
        p0, p1 = prof[i, j - 1], prof[i, j]
        off = t[j - 1] + (level[i] - p0) / np.where(p1 == p0, 1e-9, p1 - p0) * 0.25
        pts = base[i] + off[:, None] * n[None, :]
        mean = pts.mean(axis=0)
        _, _, vt = np.linalg.svd(pts - mean)
        lines.append((mean, vt[0]))
    out = []
    for k in range(4):
        (p, d), (q, f) = lines[k - 1], lines[k]
        m = np.column_stack([d, -f])
        if abs(np.linalg.det(m)) < 1e-6:
            return quad
        a_, _ = np.linalg.solve(m, q - p)
        out.append(p + a_ * d)
    return np.array(out)


# -- pin bearings and levelling ---------------------------------------------------
@dataclass
class Bearings:
    """Centres (px) of the left and right pin bearings, their radius (px) and the
    angle of the pin line in the image (deg; + turns x towards +y of the image)."""

    left: np.ndarray
    right: np.ndarray
    radius_px: float
    level_deg: float


def _flat_field(v: np.ndarray, size_px: int) -> np.ndarray:
    """Brightness of the background (dark objects closed away), smooth."""
    f = 4
    small = cv2.resize(v, (max(v.shape[1] // f, 1), max(v.shape[0] // f, 1)),
                       interpolation=cv2.INTER_AREA)
    k = max(int(size_px / f) | 1, 3)
    bg = cv2.morphologyEx(small, cv2.MORPH_CLOSE, cv2.getStructuringElement(
        cv2.MORPH_ELLIPSE, (k, k)))
    bg = cv2.GaussianBlur(bg, (0, 0), k / 2)
    return cv2.resize(bg, (v.shape[1], v.shape[0]), interpolation=cv2.INTER_LINEAR)


def find_bearings(img: np.ndarray, px_per_mm: float, marker: Marker | None = None,
                  min_diameter_mm: float = 2.0) -> Bearings:
    """The two pin bearings (Sec. IV-D-1) and the levelling angle.

    The paper uses Hough circles. Here: dark, round blobs of a flat-fielded
    brightness image (V < 0.4 of the local background), away from the marker,
    at least ``min_diameter_mm`` across and round (area ≥ 0.8 of the enclosing
    circle); the two largest are the bearings, their centres the blobs'
    centroids. A centroid averages every edge pixel (≈ 0.05 px on rendered discs); a
    Hough accumulator is quantised to its bin.
    """
    v = img.max(axis=2).astype(np.float32)
    bg = _flat_field(v, int(15 * px_per_mm))
    dark = (v < 0.4 * np.maximum(bg, 1)).astype(np.uint8)
    if marker is not None:
        hull = marker.corners.mean(axis=0) + 1.6 * (marker.corners - marker.corners.mean(axis=0))
        cv2.fillConvexPoly(dark, np.round(hull).astype(np.int32), 0)
    n, lab, stats, cents = cv2.connectedComponentsWithStats(dark, connectivity=8)
    found = []
    min_area = math.pi * (min_diameter_mm * px_per_mm / 2) ** 2
    for i in range(1, n):
        area = stats[i, cv2.CC_STAT_AREA]
        if area < min_area:
            continue
        x, y, w, h = stats[i, :4]
        ys, xs = np.nonzero(lab[y:y + h, x:x + w] == i)
        (_, _), r = cv2.minEnclosingCircle(np.column_stack([xs, ys]).astype(np.float32))
        if area >= 0.8 * math.pi * r * r:
            found.append((area, cents[i], math.sqrt(area / math.pi)))
    if len(found) < 2:
        raise VisionError(f"found {len(found)} of the 2 pin bearings (dark round discs at the "
                          "actuator's ends): check the lighting and that both are in view")
    found.sort(key=lambda t: -t[0])
    a, b = found[0][1], found[1][1]
    left, right = (a, b) if a[0] <= b[0] else (b, a)
    ang = math.degrees(math.atan2(right[1] - left[1], right[0] - left[0]))
    return Bearings(np.asarray(left, float), np.asarray(right, float),
                    0.5 * (found[0][2] + found[1][2]), ang)


def to_mm(points_px: np.ndarray, bearings: Bearings, px_per_mm: float) -> np.ndarray:
    """Pixel → mm in the levelled frame: origin at the left bearing, x along the pin
    line, y up (Sec. IV-D-2). The coordinates are rotated, not the image, so no
    resampling blurs the measurement."""
    a = math.radians(bearings.level_deg)
    u = np.asarray(points_px, float) - bearings.left
    x = (u[..., 0] * math.cos(a) + u[..., 1] * math.sin(a)) / px_per_mm
    y = -(-u[..., 0] * math.sin(a) + u[..., 1] * math.cos(a)) / px_per_mm
    return np.stack([x, y], axis=-1)


def to_px(points_mm: np.ndarray, bearings: Bearings, px_per_mm: float) -> np.ndarray:
    """Inverse of :func:`to_mm`."""
    a = math.radians(bearings.level_deg)
    p = np.asarray(points_mm, float) * px_per_mm
    ux, uy = p[..., 0], -p[..., 1]
    return np.stack([ux * math.cos(a) - uy * math.sin(a),
                     ux * math.sin(a) + uy * math.cos(a)], axis=-1) + bearings.left


# -- segmentation ------------------------------------------------------------------
#: Pieces of the actuator seen between occluders: every component of the HSV mask
#: with at least this fraction of the largest one's area is kept; :func:`centerline`
#: chains them from the left bearing across gaps up to MAX_GAP_MM.
PIECE_FRACTION = 0.05
MAX_GAP_MM = 15.0


@dataclass
class Segmentation:
    """Binary mask of the actuator (its pieces, see PIECE_FRACTION), the HSV range
    used, and a continuous membership image (0 background … 1 actuator) for sub-pixel
    edges."""

    mask: np.ndarray
    lower: tuple[int, int, int]
    upper: tuple[int, int, int]
    membership: np.ndarray


def auto_hsv_range(hsv: np.ndarray) -> tuple[tuple[int, int, int], tuple[int, int, int]]:
    """The automatic HSV range: the dominant hue of the strongly saturated, not dark
    pixels (OpenCV H in 0-179), ± 12, with S ≥ 70 and V ≥ 50."""
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    sel = (s > 90) & (v > 60)
    if sel.sum() < 50:
        raise VisionError("segmentation is empty: no saturated colour in the image; give the "
                          "actuator's colour with --hsv-lower H,S,V --hsv-upper H,S,V")
    hist = np.bincount(h[sel].ravel(), minlength=180).astype(float)
    hist = np.convolve(np.concatenate([hist[-5:], hist, hist[:5]]), np.ones(5), "same")[5:-5]
    peak = int(np.argmax(hist))
    return (peak - 12, 70, 50), (peak + 12, 255, 255)


def segment(img: np.ndarray, lower=None, upper=None) -> Segmentation:
    """HSV segmentation (Sec. IV-D-3): pixels in [lower, upper] (OpenCV H 0-179; a hue
    range may wrap, e.g. lower H = -10), the largest connected component kept with
    every other one at least PIECE_FRACTION of its area (the actuator cut by occluders)."""
    blur = cv2.GaussianBlur(img, (0, 0), 1.0)
    hsv = cv2.cvtColor(blur, cv2.COLOR_BGR2HSV)
    if lower is None or upper is None:
        lower, upper = auto_hsv_range(hsv)
    lower, upper = tuple(int(v) for v in lower), tuple(int(v) for v in upper)
    if len(lower) != 3 or len(upper) != 3:
        raise VisionError("HSV bounds are three numbers H,S,V")
    h0, h1 = lower[0], upper[0]
    if h0 < 0 or h1 > 179:  # a hue range across red wraps
        a = cv2.inRange(hsv, (max(h0 % 180, 0), lower[1], lower[2]), (179, upper[1], upper[2]))
        b = cv2.inRange(hsv, (0, lower[1], lower[2]), (h1 % 180, upper[1], upper[2]))
        mask = a | b
    else:
        mask = cv2.inRange(hsv, lower, upper)
    mask = cv2.morphologyEx(mask, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    n, lab, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
    if n < 2 or stats[1:, cv2.CC_STAT_AREA].max() < 100:
        raise VisionError(f"segmentation is empty: no actuator pixels in HSV {lower}-{upper}; "
                          "set --hsv-lower H,S,V --hsv-upper H,S,V to the actuator's colour")
    areas = stats[1:, cv2.CC_STAT_AREA]
    mask = np.isin(lab, 1 + np.nonzero(areas >= PIECE_FRACTION * areas.max())[0])
    # membership: projection of the colour on the line background -> actuator colour
    f = cv2.GaussianBlur(img.astype(np.float32), (0, 0), 0.8)
    inner = cv2.erode(mask.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    ring = cv2.dilate(mask.astype(np.uint8), np.ones((15, 15), np.uint8)).astype(bool) & ~mask
    fg = np.median(f[inner if inner.any() else mask], axis=0)
    bgc = np.median(f[ring], axis=0)
    d = fg - bgc
    memb = ((f - bgc) @ d) / max(float(d @ d), 1e-6)
    return Segmentation(mask, lower, upper, memb.astype(np.float32))


# -- centerline ----------------------------------------------------------------------
def _longest_path(skel: np.ndarray) -> np.ndarray:
    """The longest geodesic path through a skeleton (two breadth-first searches), as
    (n, 2) px (x, y)."""
    ys, xs = np.nonzero(skel)
    index = {(int(y), int(x)): i for i, (y, x) in enumerate(zip(ys, xs))}
    nbrs = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx]

    def bfs(start):
        parent = {start: -1}
        q, last = deque([start]), start
        while q:
            last = q.popleft()
            y, x = int(ys[last]), int(xs[last])
            for dy, dx in nbrs:
                j = index.get((y + dy, x + dx))
                if j is not None and j not in parent:
                    parent[j] = last
                    q.append(j)
        return last, parent

    far, _ = bfs(0)
    other, parent = bfs(far)
    path, j = [], other
    while j != -1:
        path.append(j)
        j = parent[j]
    return np.column_stack([xs[path], ys[path]]).astype(float)


def refine_centerline(points: np.ndarray, membership: np.ndarray, radius_px: float,
                      iterations: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Sub-pixel centerline: each point moves to the midpoint of the actuator's two
    edges along its normal.

    This is the paper's "average of the top and bottom edges" (Sec. IV-D-4) taken
    across the local normal instead of down a pixel column, so it holds where the
    tangent passes vertical. Each edge is where the membership profile crosses
    halfway between the actuator's level and that side's background level (linear
    interpolation). A symmetric blur, lighting or threshold bias moves both edges
    alike and leaves the midpoint. Returns the points and the local widths (px).
    """
    p = resample(points, step=1.0)
    half = radius_px * 1.7 + 3
    t = np.arange(-half, half + 1e-9, 0.25)
    width = np.zeros(len(p))
    for _ in range(iterations):
        sm = gaussian_filter1d(p, max(radius_px * 0.3, 2), axis=0, mode="nearest")
        d = np.gradient(sm, axis=0)
        d /= np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)[:, None]
        n = np.column_stack([-d[:, 1], d[:, 0]])
        mx = (p[:, 0:1] + t[None, :] * n[:, 0:1]).astype(np.float32)
        my = (p[:, 1:2] + t[None, :] * n[:, 1:2]).astype(np.float32)
        prof = cv2.remap(membership, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        c = len(t) // 2
        core = np.abs(t) <= 0.25 * radius_px
        level_in = prof[:, core].mean(axis=1)
        out_m = prof[:, t <= -(radius_px + 2.5)].mean(axis=1)
        out_p = prof[:, t >= radius_px + 2.5].mean(axis=1)
        edge_p = _crossing(prof[:, c:], t[c:], 0.5 * (level_in + out_p))
        edge_m = _crossing(prof[:, c::-1], t[c::-1], 0.5 * (level_in + out_m))
        shift = 0.5 * (edge_p + edge_m)
        width = edge_p - edge_m
        ok = np.isfinite(shift) & (np.abs(width - 2 * radius_px) < 0.35 * 2 * radius_px)
        p = p[ok] + shift[ok, None] * n[ok]
        width = width[ok]
        if len(p) < 10:
            raise VisionError("the actuator's edges were not found along its centerline: "
                              "check the segmentation (--hsv-lower/--hsv-upper) and --diameter")
        if _ < iterations - 1:
            p = resample(gaussian_filter1d(p, 1.0, axis=0, mode="nearest"), step=1.0)
    return p, width


def _crossing(prof: np.ndarray, t: np.ndarray, level: np.ndarray) -> np.ndarray:
    """First t (from index 0 on) where each row of prof falls below its level."""
    below = prof < level[:, None]
    below[:, 0] = False
    first = np.argmax(below, axis=1)
    out = np.full(len(prof), np.nan)
    ok = below.any(axis=1)
    i = np.nonzero(ok)[0]
    j = first[ok]
    a, b = prof[i, j - 1], prof[i, j]
    frac = (a - level[i]) / np.where(a - b == 0, 1e-9, a - b)
    out[i] = t[j - 1] + frac * (t[j] - t[j - 1])
    return out


def centerline(seg: Segmentation, bearings: Bearings, px_per_mm: float,
               diameter_mm: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """Ordered sub-pixel centerline (px), left bearing to right, and local widths (px).

    Method (docs/vision.md): skeleton of the mask (scikit-image), the longest path
    of each of its pieces, the pieces chained from the left bearing (each next piece
    the one with an end nearest the chain's end, within MAX_GAP_MM: the actuator seen
    between occluders), each smoothed and refined along its normals
    (:func:`refine_centerline`). Points hidden by or touching a bearing are dropped.
    """
    from scipy.ndimage import label
    from skimage.morphology import skeletonize

    skel = skeletonize(seg.mask)
    if skel.sum() < 10:
        raise VisionError("segmentation is empty: the actuator mask has no centerline")
    lab, n = label(skel, structure=np.ones((3, 3)))
    paths = [_longest_path(lab == i) for i in range(1, n + 1) if (lab == i).sum() >= 10]
    r_px = diameter_mm / 2 * px_per_mm
    pts, width = [], []
    for path in _chain(paths, bearings.left, MAX_GAP_MM * px_per_mm):
        path = gaussian_filter1d(path, max(r_px * 0.5, 2), axis=0, mode="nearest")
        try:
            p, w = refine_centerline(path, seg.membership, r_px)
        except VisionError:
            continue
        pts.append(p)
        width.append(w)
    if not pts:
        raise VisionError("the actuator's edges were not found along its centerline: "
                          "check the segmentation (--hsv-lower/--hsv-upper) and --diameter")
    pts, width = np.vstack(pts), np.concatenate(width)
    clear = bearings.radius_px + r_px + 3
    keep = (np.hypot(*(pts - bearings.left).T) > clear) & \
        (np.hypot(*(pts - bearings.right).T) > clear)
    return pts[keep], width[keep]


def _chain(paths: list[np.ndarray], start: np.ndarray, max_gap: float) -> list[np.ndarray]:
    """The paths in order from ``start``, each oriented: first the one with an end
    nearest ``start``, then each time the one with an end nearest the last one's end,
    if within ``max_gap`` (px)."""
    left, out, end = list(paths), [], np.asarray(start, float)
    while left:
        gaps = [min(np.hypot(*(p[0] - end)), np.hypot(*(p[-1] - end))) for p in left]
        k = int(np.argmin(gaps))
        if out and gaps[k] > max_gap:
            break
        p = left.pop(k)
        if np.hypot(*(p[-1] - end)) < np.hypot(*(p[0] - end)):
            p = p[::-1]
        out.append(p)
        end = p[-1]
    return out
