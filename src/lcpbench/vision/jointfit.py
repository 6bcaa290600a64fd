"""One least-squares fit of the whole actuator: a chain of k circular arcs of
alternating curvature between the two pins, fitted to the sub-pixel centerline.

The paper (Sec. IV-D-5 to 7) finds the inflection points first and then fits a
circle to each section alone (eqs. 38-39). On a flat section that circle is
ill-conditioned, and an inflection point placed from a noisy curvature drifts.
Here the inflection points follow from the fit instead:

- **the model**: k arcs, section j of bend angle θ_j and arc length ℓ_j, its
  curvature ±θ_j/ℓ_j alternating in sign, tangent-continuous, starting at the
  left pin A and ending at the right pin B (the bearings' centres, held fixed);
- **the unknowns**: θ_j (or one shared θ, ``equal_sections``) and the length
  ratios ℓ_j/ℓ_k. The start tangent and the overall scale are then fixed by the
  pins (the chain drawn from A is rotated and scaled so it ends at B), so the
  fit has k + (k − 1) unknowns (1 + (k − 1) with a shared θ);
- **the residual** of a centerline point: its signed distance to the chain (the
  nearest arc, or the nearest arc end past the last one).

Confidence (:class:`Confidence`): the RMS residual; standard errors of every θ_j
and ℓ_j from the fit's Jacobian, with (i) the residual variance inflated by the
residuals' correlation along the curve (neighbouring centerline points share
pixels), (ii) the bearings' centres' uncertainty (``PIN_SIGMA_PX``) carried through
the fit, and (iii) the marker scale's uncertainty on ℓ; the spread of the section
lengths; and warnings past the thresholds below (docs/vision.md, "Confidence").

numpy and scipy only: tested on exact and noisy curves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from .errors import VisionError

#: 1-σ uncertainty of a bearing's centre (px) carried into the standard errors:
#: the blob centroid is within 0.06 px of the truth on the test renders; real
#: bearings (hubs, shadows, a printed disc slightly off its pin) are allowed more.
PIN_SIGMA_PX = 0.08

#: Warning thresholds (docs/vision.md, "Confidence"). A warning is raised when
#: the RMS residual exceeds RMS_PX px or RMS_DIAMETER of the tube's diameter; when the
#: relative standard error of the middle section's θ or ℓ exceeds REL_SE (so its
#: 2-s.e. interval is wider than ±1 %); when the section lengths spread by more
#: than LENGTH_SPREAD of their mean ((max − min)/mean; the paper's actuator has equal
#: sections); when the joint fit and the per-section circle fits (eqs. 38-39)
#: disagree on the middle section by more than METHODS_DIFFER; and when more than
#: OUTLIERS of the centerline points were left out as outliers, or a section has
#: fewer than MIN_POINTS of them.
RMS_PX = 1.0
RMS_DIAMETER = 0.05
REL_SE = 0.005
LENGTH_SPREAD = 0.03
METHODS_DIFFER = 0.01
OUTLIERS = 0.05
#: fewer centerline points than this on a section: it is not seen, no standard error.
MIN_POINTS = 20


@dataclass
class Arc:
    """One fitted section in the levelled frame (mm): start point, start tangent
    angle φ (rad), signed curvature κ (1/mm, > 0 turning left), length ℓ and bend
    angle θ = |κ| ℓ."""

    start: np.ndarray
    phi: float
    kappa: float
    length: float

    @property
    def theta(self) -> float:
        return abs(self.kappa) * self.length

    @property
    def radius(self) -> float:
        return 1.0 / abs(self.kappa)

    @property
    def center(self) -> np.ndarray:
        return self.start + np.array([-math.sin(self.phi), math.cos(self.phi)]) / self.kappa

    @property
    def end(self) -> np.ndarray:
        return self.point(self.length)

    def point(self, s) -> np.ndarray:
        """Points at arc length s (scalar or array) from the start."""
        s = np.asarray(s, float)
        k, p = self.kappa, self.phi
        x = self.start[0] + (np.sin(p + k * s) - math.sin(p)) / k
        y = self.start[1] - (np.cos(p + k * s) - math.cos(p)) / k
        return np.stack([x, y], axis=-1)


def chain(thetas, lengths, turn: int, a=(0.0, 0.0), b=(1.0, 0.0)) -> list[Arc]:
    """The k arcs of bend angles ``thetas`` (rad, > 0) and relative lengths
    ``lengths``, alternating in sense (the first turns left if ``turn`` = +1), drawn
    from pin ``a`` and rotated and scaled about it so the chain ends at pin ``b``."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    pts, phis, kappas = [], [], []
    p, phi, sense = np.zeros(2), 0.0, float(turn)
    for th, ln in zip(thetas, lengths):
        k = sense * th / ln
        pts.append(p)
        phis.append(phi)
        kappas.append(k)
        p = p + np.array([math.sin(phi + k * ln) - math.sin(phi),
                          -(math.cos(phi + k * ln) - math.cos(phi))]) / k
        phi += k * ln
        sense = -sense
    d = b - a
    alpha = math.atan2(d[1], d[0]) - math.atan2(p[1], p[0])
    lam = math.hypot(*d) / max(math.hypot(*p), 1e-300)
    rot = np.array([[math.cos(alpha), -math.sin(alpha)], [math.sin(alpha), math.cos(alpha)]])
    return [Arc(a + lam * (rot @ q), f + alpha, k / lam, lam * ln)
            for q, f, k, ln in zip(pts, phis, kappas, lengths)]


def signed_distance(points: np.ndarray, arcs: list[Arc], which: bool = False):
    """Signed distance of each point to the chain (> 0 on the left of the direction
    of travel): to the nearest arc if the point projects inside it, else to the
    nearest arc end. With ``which``, also the index of that nearest arc."""
    q = np.asarray(points, float)
    best = np.full(len(q), np.inf)
    out = np.zeros(len(q))
    idx = np.zeros(len(q), int)
    for j, arc in enumerate(arcs):
        c, r, sg = arc.center, arc.radius, math.copysign(1.0, arc.kappa)
        v = q - c
        rho = np.hypot(v[:, 0], v[:, 1])
        a0 = math.atan2(arc.start[1] - c[1], arc.start[0] - c[0])
        amid = a0 + sg * arc.theta / 2
        rel = np.angle(np.exp(1j * (np.arctan2(v[:, 1], v[:, 0]) - amid)))
        inside = np.abs(rel) <= arc.theta / 2
        d = sg * (r - rho)
        ends = np.stack([arc.start, arc.end])
        de = np.hypot(q[:, None, 0] - ends[None, :, 0], q[:, None, 1] - ends[None, :, 1]).min(1)
        d = np.where(inside, d, np.copysign(de, d))
        better = np.abs(d) < best
        best = np.where(better, np.abs(d), best)
        out = np.where(better, d, out)
        idx = np.where(better, j, idx)
    return (out, idx) if which else out


@dataclass
class Confidence:
    """How far a joint fit can be trusted (mm, deg; 1 standard error)."""

    rms_mm: float
    rms_px: float
    theta_se_deg: list[float]
    arc_length_se_mm: list[float]
    length_spread: float            # (max − min) / mean of the section lengths
    length_sd_mm: float
    correlation: float              # variance inflation for correlated residuals
    points: int
    outliers: int
    section_points: list[int] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"rms_mm": self.rms_mm, "rms_px": self.rms_px,
                "theta_se_deg": self.theta_se_deg, "arc_length_se_mm": self.arc_length_se_mm,
                "length_spread": self.length_spread, "length_sd_mm": self.length_sd_mm,
                "residual_correlation": self.correlation, "points": self.points,
                "outliers": self.outliers, "section_points": self.section_points,
                "warnings": list(self.warnings)}


@dataclass
class JointFit:
    """The fitted chain: arcs left to right, inflection points (k − 1, 2) mm, the
    residuals, the parameters' covariance and the :class:`Confidence`."""

    arcs: list[Arc]
    turn: int
    equal_sections: bool
    residuals_mm: np.ndarray
    section_of: np.ndarray
    used: np.ndarray
    confidence: Confidence

    @property
    def theta_deg(self) -> list[float]:
        return [math.degrees(a.theta) for a in self.arcs]

    @property
    def arc_length_mm(self) -> list[float]:
        return [a.length for a in self.arcs]

    def section_rms_mm(self, j: int) -> float:
        """RMS residual of the used points nearest to section j."""
        r = self.residuals_mm[self.used & (self.section_of == j)]
        return float(np.sqrt(np.mean(r ** 2))) if len(r) else float("nan")

    @property
    def inflection_points(self) -> np.ndarray:
        return np.array([a.end for a in self.arcs[:-1]]).reshape(-1, 2)


def _unpack(x, k, equal):
    th = np.full(k, x[0]) if equal else x[:k]
    u = x[1:] if equal else x[k:]
    return th, np.exp(np.concatenate([u, [0.0]]))


def _derived(x, k, equal, turn, pins):
    """θ_j (rad) and ℓ_j (mm) of the chain through pins (ax, ay, bx, by)."""
    th, ln = _unpack(x, k, equal)
    arcs = chain(th, ln, turn, pins[:2], pins[2:])
    return np.concatenate([[a.theta for a in arcs], [a.length for a in arcs]])


def _jacobian(f, x, rel=1e-6):
    f0 = f(x)
    jac = np.empty((len(f0), len(x)))
    for i in range(len(x)):
        h = rel * max(abs(x[i]), 1e-2)
        e = np.zeros(len(x))
        e[i] = h
        jac[:, i] = (f(x + e) - f(x - e)) / (2 * h)
    return jac


def correlation_inflation(r: np.ndarray) -> float:
    """Variance inflation 1 + 2 Σ ρ_m of a correlated residual sequence (Geyer's
    initial positive sequence), ≥ 1."""
    r = r - r.mean()
    n = len(r)
    var = float(r @ r) / n
    if var == 0 or n < 8:
        return 1.0
    tau = 1.0
    for m in range(1, n // 4):
        rho = float(r[:-m] @ r[m:]) / (n * var)
        if rho <= 0.02:
            break
        tau += 2 * rho
    return tau


def fit_chain(points: np.ndarray, span: float, sections: int, *, start=None,
              equal_sections: bool = False, px_per_mm: float = 1.0,
              pin_sigma_mm: float | None = None, scale_rel_sd: float = 0.0) -> JointFit:
    """Least-squares chain of ``sections`` arcs through the pins (0, 0) and (span, 0).

    Parameters
    ----------
    points : (n, 2) centerline (mm, levelled frame, ordered from the left pin).
    span : distance between the pins (mm).
    start : optional (θ_j rad, ℓ_j mm) per section to start from (e.g. the circle
        fits); several equal-section starts are tried as well.
    equal_sections : one θ shared by every section (ℓ still per section).
    px_per_mm : the image's scale, for the residual in px.
    pin_sigma_mm : 1-σ of each pin's position (default PIN_SIGMA_PX / px_per_mm).
    scale_rel_sd : relative 1-σ of the scale (px/mm), added to the lengths' errors.
    """
    p = np.asarray(points, float)
    k = int(sections)
    n_par = (1 if equal_sections else k) + k - 1
    if len(p) < 3 * n_par + 10:
        raise VisionError(f"the centerline has {len(p)} points: too few to fit {k} sections")
    if pin_sigma_mm is None:
        pin_sigma_mm = PIN_SIGMA_PX / px_per_mm
    pins = np.array([0.0, 0.0, span, 0.0])

    def resid(x, turn, pts):
        th, ln = _unpack(x, k, equal_sections)
        return signed_distance(pts, chain(th, ln, turn, pins[:2], pins[2:]))

    def pack(th, ln):
        th = np.clip(np.asarray(th, float), 1e-3, 2 * np.pi - 1e-3)
        u = np.log(np.asarray(ln, float)[:-1] / ln[-1])
        return np.concatenate([[th.mean()] if equal_sections else th, u])

    starts = [pack(np.full(k, math.radians(t)), np.ones(k)) for t in (15, 45, 90, 150)]
    if start is not None:
        starts.insert(0, pack(*start))
    lo = np.concatenate([np.full(n_par - k + 1, 1e-3), np.full(k - 1, -3.0)])
    hi = np.concatenate([np.full(n_par - k + 1, 2 * np.pi - 1e-3), np.full(k - 1, 3.0)])
    # the sense of the first section and the start: best cost over a few cheap tries
    tries = sorted(((float(np.sum(resid(x0, t, p) ** 2)), t, x0)
                    for t in (1, -1) for x0 in starts), key=lambda v: v[0])[:3]
    best = None
    for _, turn, x0 in tries:
        sol = least_squares(resid, np.clip(x0, lo, hi), bounds=(lo, hi), args=(turn, p),
                            x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12)
        if best is None or sol.cost < best[0].cost:
            best = (sol, turn)
    sol, turn = best
    # outliers: points more than 6 robust σ (and 0.5 px) off; refit without them
    r = sol.fun
    sigma = 1.4826 * np.median(np.abs(r - np.median(r)))
    used = np.abs(r) <= max(6 * sigma, 0.5 / px_per_mm)
    if not used.all():
        sol = least_squares(resid, sol.x, bounds=(lo, hi), args=(turn, p[used]),
                            x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    x = sol.x
    th, ln = _unpack(x, k, equal_sections)
    arcs = chain(th, ln, turn, pins[:2], pins[2:])
    r_all, section_of = signed_distance(p, arcs, which=True)
    r = r_all[used]
    m = len(r)

    # covariance: parameters from the residual variance (inflated for correlation),
    # then the pins' uncertainty carried through the fit
    jp = _jacobian(lambda v: resid(v, turn, p[used]), x)
    ja = _jacobian(lambda q: signed_distance(p[used], chain(th, ln, turn, q[:2], q[2:])), pins)
    tau = correlation_inflation(r)
    s2 = float(r @ r) / max(m - n_par, 1)
    counts = np.bincount(section_of[used], minlength=k)
    hess = jp.T @ jp
    blind = counts.min() < MIN_POINTS or np.linalg.cond(hess) > 1e12
    hinv = np.linalg.pinv(hess)
    g = -hinv @ jp.T @ ja                      # d x̂ / d pins
    sig_pins = pin_sigma_mm ** 2 * np.eye(4)
    cov = np.block([[tau * s2 * hinv + g @ sig_pins @ g.T, g @ sig_pins],
                    [sig_pins @ g.T, sig_pins]])
    dd = _jacobian(lambda z: _derived(z[:n_par], k, equal_sections, turn, z[n_par:]),
                   np.concatenate([x, pins]))
    var = np.diag(dd @ cov @ dd.T).copy()
    lengths = np.array([a.length for a in arcs])
    var[k:] += (lengths * scale_rel_sd) ** 2
    # a section the centerline does not see, or a singular fit: no standard error
    se = np.where((var >= 0) & ~blind, np.sqrt(np.abs(var)), np.inf)
    rms = float(np.sqrt(np.mean(r ** 2)))
    conf = Confidence(rms, rms * px_per_mm, np.degrees(se[:k]).tolist(), se[k:].tolist(),
                      float(np.ptp(lengths) / lengths.mean()), float(lengths.std()),
                      float(tau), int(m), int(len(p) - m), counts.tolist())
    return JointFit(arcs, turn, equal_sections, r_all, section_of, used, conf)


def check(fit: JointFit, middle: int, diameter_mm: float, px_per_mm: float,
          circle_fit: tuple[float, float] | None = None) -> list[str]:
    """The warnings of a joint fit against the documented thresholds (module top);
    ``circle_fit`` is the per-section (eqs. 38-39) θ (deg) and ℓ of the middle section."""
    c, out = fit.confidence, []
    mid_t, mid_l = fit.theta_deg[middle], fit.arc_length_mm[middle]
    limit = min(RMS_PX / px_per_mm, RMS_DIAMETER * diameter_mm)
    if c.rms_mm > limit:
        out.append(f"the arcs fit the centerline poorly: RMS residual {c.rms_px:.2f} px "
                   f"({c.rms_mm:.3f} mm) > {limit * px_per_mm:.2f} px; check the segmentation "
                   "and --sections, or the actuator is not a chain of arcs")
    for j, n in enumerate(c.section_points):
        if n < MIN_POINTS:
            out.append(f"section {j + 1} has {n} centerline points (< {MIN_POINTS}): the "
                       "photograph does not show it; check the segmentation")
    rel_t, rel_l = c.theta_se_deg[middle] / mid_t, c.arc_length_se_mm[middle] / mid_l
    if max(rel_t, rel_l) > REL_SE:
        out.append(f"the middle section is poorly determined: standard error of theta "
                   f"{100 * rel_t:.2f} %, of the arc length {100 * rel_l:.2f} % "
                   f"(> {100 * REL_SE:g} %)")
    if len(fit.arcs) > 1 and c.length_spread > LENGTH_SPREAD:
        lens = ", ".join(f"{v:.2f}" for v in fit.arc_length_mm)
        out.append(f"the section lengths differ by {100 * c.length_spread:.1f} % "
                   f"({lens} mm; > {100 * LENGTH_SPREAD:g} %): if the sections are equal, "
                   "the measurement is suspect")
    if circle_fit is not None:
        dt = abs(circle_fit[0] - mid_t) / mid_t
        dl = abs(circle_fit[1] - mid_l) / mid_l
        if max(dt, dl) > METHODS_DIFFER:
            out.append(f"the joint fit and the per-section circle fits (eqs. 38-39) differ "
                       f"on the middle section by {100 * dt:.1f} % in theta and "
                       f"{100 * dl:.1f} % in arc length (> {100 * METHODS_DIFFER:g} %)")
    if c.outliers > OUTLIERS * (c.points + c.outliers):
        out.append(f"{c.outliers} of {c.points + c.outliers} centerline points were left "
                   f"out as outliers (> {100 * OUTLIERS:g} %)")
    return out
