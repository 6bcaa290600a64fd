"""Plane geometry of the pipeline (Sec. IV-D-5 to IV-D-8): circle fit, bend angle
(eq. 38), arc length (eq. 39), inflection points and ICP registration.

numpy and scipy only: no image is touched here, so every function is tested on
exact curves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.optimize import least_squares
from scipy.spatial import cKDTree

from .errors import VisionError


@dataclass
class Circle:
    """A fitted circle: centre (x_c, y_c), radius r_c and the RMS geometric residual."""

    center: np.ndarray
    radius: float
    rms: float


def fit_circle(points: np.ndarray) -> Circle:
    """Least-squares circle through 2-D points (Sec. IV-D-6, ref. [38]).

    An algebraic (Kåsa) fit starts a geometric fit that minimises
    Σ (|p_i − c| − r)² (Levenberg–Marquardt); the geometric fit stays unbiased
    on short, shallow arcs where the algebraic one is not.

    Parameters
    ----------
    points : (n, 2) array, n >= 3, not all on one line.

    Returns
    -------
    Circle
    """
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise VisionError(f"a circle fit needs at least 3 points (n, 2), got shape {p.shape}")
    mean = p.mean(axis=0)
    q = p - mean
    scale = float(np.sqrt((q ** 2).sum(axis=1).mean())) or 1.0
    q = q / scale
    if np.linalg.svd(q, compute_uv=False)[-1] < 1e-9 * np.sqrt(len(q)):
        raise VisionError("the points lie on a straight line: no circle to fit")
    a = np.column_stack([q, np.ones(len(q))])
    b = (q ** 2).sum(axis=1)
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    c0 = sol[:2] / 2
    r0 = float(np.sqrt(max(sol[2] + c0 @ c0, 1e-12)))
    if not np.isfinite(r0) or r0 > 1e6:
        raise VisionError("the points lie on a straight line: no circle to fit")

    def resid(v):
        return np.hypot(q[:, 0] - v[0], q[:, 1] - v[1]) - v[2]

    def jac(v):
        d = np.hypot(q[:, 0] - v[0], q[:, 1] - v[1])
        d = np.where(d == 0, 1e-12, d)
        return np.column_stack([-(q[:, 0] - v[0]) / d, -(q[:, 1] - v[1]) / d, -np.ones(len(q))])

    out = least_squares(resid, np.array([c0[0], c0[1], r0]), jac=jac, method="lm",
                        xtol=1e-15, ftol=1e-15, gtol=1e-15)
    cx, cy, r = out.x
    r = abs(r)
    rms = float(np.sqrt(np.mean(out.fun ** 2))) * scale
    return Circle(np.array([cx, cy]) * scale + mean, float(r * scale), rms)


def bend_angle(p1, p2, center, through=None) -> float:
    """Bend angle θ (rad) of the arc from inflection point p1 to p2 about the fitted
    centre, eq. (38) with atan2.

    Eq. (38) as printed, arctan|(x₁c y₂c − x₂c y₁c)/(x₁c x₂c + y₁c y₂c)|, folds every
    angle into [0°, 90°] (docs/errata.md, 3). atan2(|cross|, dot) gives [0°, 180°];
    with ``through`` (any point of the arc between p1 and p2) an arc longer than a
    half circle, whose points lie on the far side of the chord from the short arc,
    gets 2π − that.
    """
    v1 = np.asarray(p1, float) - center
    v2 = np.asarray(p2, float) - center
    cross = v1[0] * v2[1] - v1[1] * v2[0]
    dot = v1 @ v2
    theta = float(np.arctan2(abs(cross), dot))
    if through is not None:
        chord = np.asarray(p2, float) - np.asarray(p1, float)
        t = np.asarray(through, float) - np.asarray(p1, float)
        side_arc = chord[0] * t[1] - chord[1] * t[0]
        side_centre = chord[0] * (center[1] - p1[1]) - chord[1] * (center[0] - p1[0])
        if side_arc * side_centre > 0:  # the arc bulges past the centre: > half a circle
            theta = 2 * np.pi - theta
    return theta


def bend_angle_printed(p1, p2, center) -> float:
    """Eq. (38) exactly as printed (arctan of the absolute ratio): at most π/2.

    Kept to document the erratum; :func:`bend_angle` is what the pipeline uses.
    """
    v1 = np.asarray(p1, float) - center
    v2 = np.asarray(p2, float) - center
    cross = v1[0] * v2[1] - v1[1] * v2[0]
    dot = v1 @ v2
    with np.errstate(divide="ignore"):
        return float(np.arctan(abs(cross / dot)))


def arc_length(radius: float, theta: float) -> float:
    """ℓ = r_c θ, eq. (39)."""
    return float(radius * theta)


def cumulative_length(points: np.ndarray) -> np.ndarray:
    """Arc length s_i along a polyline (s_0 = 0)."""
    d = np.hypot(*np.diff(np.asarray(points, float), axis=0).T)
    return np.concatenate([[0.0], np.cumsum(d)])


def resample(points: np.ndarray, n: int | None = None, step: float | None = None) -> np.ndarray:
    """Points equally spaced by arc length along a polyline (n points or a step)."""
    p = np.asarray(points, float)
    s = cumulative_length(p)
    if n is None:
        n = max(int(round(s[-1] / step)) + 1, 2)
    t = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(t, s, p[:, 0]), np.interp(t, s, p[:, 1])])


def tangent_angle(points: np.ndarray, sigma: float) -> np.ndarray:
    """Unwrapped tangent direction φ(s) (rad) of equally spaced points, smoothed with a
    Gaussian of ``sigma`` samples."""
    p = gaussian_filter1d(np.asarray(points, float), sigma, axis=0, mode="nearest")
    d = np.gradient(p, axis=0)
    return np.unwrap(np.arctan2(d[:, 1], d[:, 0]))


def inflection_indices(points: np.ndarray, sections: int, sigma: float) -> np.ndarray:
    """Indices of the k − 1 inflection points of a k-section centerline (Sec. IV-D-5).

    Consecutive sections bend in opposite directions, so the tangent angle φ(s)
    has alternating extrema at the inflection points (where the curvature changes
    sign). The j-th one is looked for within ± half a section of s = j·L/k, as a
    maximum or a minimum by the sense of the first section. Unlike zero crossings
    of a noisy curvature, this also holds for a constrained section with a
    flat (zero-curvature) stretch against a wall.
    """
    if sections < 2:
        return np.zeros(0, int)
    phi = tangent_angle(points, sigma)
    n = len(phi)
    first = phi[n // (2 * sections)] - phi[0]
    sign = 1.0 if first >= 0 else -1.0  # first section turns left: φ peaks at the 1st
    out = []
    for j in range(1, sections):
        lo = max(int((j - 0.5) * n / sections), 1)
        hi = min(int((j + 0.5) * n / sections), n - 1)
        window = sign * phi[lo:hi]
        out.append(lo + int(np.argmax(window)))
        sign = -sign
    return np.array(out, int)


def tangent_point(c1: Circle, c2: Circle) -> np.ndarray:
    """Where two externally tangent circles of neighbouring sections touch: the
    inflection point of an unconstrained multi-section actuator (Sec. IV-D-5)."""
    w = c1.radius / (c1.radius + c2.radius)
    return c1.center + w * (c2.center - c1.center)


def offset_curve(points: np.ndarray, distance: float) -> np.ndarray:
    """The parallel curve at ``distance`` on the right of the direction of travel
    (below a curve drawn left to right): the paper's offset of the model's
    centerline by the tube radius (Sec. IV-D-8)."""
    p = np.asarray(points, float)
    d = np.gradient(p, axis=0)
    d /= np.hypot(d[:, 0], d[:, 1])[:, None]
    return p + distance * np.column_stack([d[:, 1], -d[:, 0]])


@dataclass
class Registration:
    """ICP result: ``moving`` mapped by x ↦ R x + t onto ``fixed``; the distance of
    every fixed point to the moved curve after the last iteration."""

    rotation: np.ndarray
    translation: np.ndarray
    distances: np.ndarray
    iterations: int
    moved: np.ndarray

    @property
    def angle_deg(self) -> float:
        return float(np.degrees(np.arctan2(self.rotation[1, 0], self.rotation[0, 0])))


def rigid_fit(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares rotation R and translation t with R a_i + t ≈ b_i (Kabsch, 2-D)."""
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    h = (a - ca).T @ (b - cb)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    r = vt.T @ np.diag([1.0, d]) @ u.T
    return r, cb - r @ ca


def icp(fixed: np.ndarray, moving: np.ndarray, *, max_iter: int = 2000,
        tol: float = 1e-7) -> Registration:
    """Iterative closest point (Sec. IV-D-8, ref. [39]): move ``moving`` (the
    photographed centerline, dense) onto ``fixed`` (the model's points).

    Each iteration pairs every fixed point with its nearest moving point and
    applies the least-squares rigid motion of those pairs; it stops when the mean
    pair distance changes by less than ``tol`` or after ``max_iter`` iterations
    (the paper's 1e-7 and 2000). Give ``moving`` densely sampled (spacing well
    below the accuracy wanted): the reported distance is to its nearest point.
    """
    fixed = np.asarray(fixed, float)
    cur = np.asarray(moving, float).copy()
    r_tot, t_tot = np.eye(2), np.zeros(2)
    prev = np.inf
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is returned
        dist, idx = cKDTree(cur).query(fixed)
        mean = float(dist.mean())
        if abs(prev - mean) < tol:
            break
        prev = mean
        r, t = rigid_fit(cur[idx], fixed)
        cur = cur @ r.T + t
        r_tot, t_tot = r @ r_tot, r @ t_tot + t
    dist, _ = cKDTree(cur).query(fixed)
    return Registration(r_tot, t_tot, dist, it, cur)
