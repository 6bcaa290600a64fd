"""The fit from photographs (issue 38, item 3): the θ(P) line and EI from measured shapes.

``lcpbench fit --shapes FILE.csv``: each row names the JSON that ``lcpbench vision
measure --json`` wrote for one photograph, its pressure and, for an actuator pressed
against a wall, the wall's centre-line height h (mm; empty for a free actuator):

    shape,pressure_kpa,height_mm
    p050.json,50,
    p100.json,100,
    c100.json,100,4.0

- **Free shapes** give the calibration line θ = slope · P + intercept (eqs. 40-42):
  least squares on the middle sections' measured θ
  (:func:`lcpbench.vision.calibrate.fit_theta_pressure`, 95 % Student-t intervals).
  Without free shapes the scene's calibration (``--fit`` or ``--actuator``) is used.
- **Pressed shapes** give EI. The pressed shape of a chain of weight w depends on EI
  only through wℓ³/EI (and on h and θ): with w = 0 it does not depend on EI at all, and
  with the paper's w (wℓ³/EI ≈ 0.2) a 10 % change of EI moves it by ~0.2 µm. The fit
  says how well the photographs determine EI: its 95 % interval.

The measured section (the middle one, between its inflection points as ``vision
compare`` takes it) is put in the frame of its chord (origin at its first end, x along
the chord); each point's residual is its signed distance, along the normal, to the
model's centre line (the polyline of its nodes). Points nearest the model's end links
are left out: the measured inflection points are uncertain along the curve, and a
point past the model's end has no partner (on rendered photographs they carried
17 µm RMS of residual, the rest 1.2 µm). Each shape's frame comes from its measured chord ends, uncertain too: a
shift and a turn per shape are fitted with EI (their uncertainty widens EI's).
Gauss–Newton in ln EI; the Jacobian from :func:`lcpbench.sensitivities` (∂y/∂EI per
node, and ∂x = −Σ_{j<k} tan α_j ∂Δy_j). The covariance is s² (JᵀJ)⁻¹,
s² inflated by the residuals' correlation along the curve (as the joint fit's), plus
the calibration line's covariance carried through (∂EI/∂(slope, intercept) from the
θ sensitivities); the interval is ± t(0.975, m − k) s.e., m the points used and k the
unknowns (ln EI and a shift and a turn per shape). With exactly two free shapes the
line has no scatter to estimate its uncertainty from: EI's interval then leaves the
line's out (its intervals are nan).
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError

MAX_ITER = 30
STEP_TOL = 1e-7  # on ln EI (EI to 1e-7 relative: far inside its interval)


@dataclass
class Shape:
    """One photographed shape: its pressure, wall height (None: free), the middle
    section's measured θ (deg) and its centre line in the frame of its chord (M × 2, mm)."""

    pressure: float
    height: float | None
    theta_deg: float
    points: np.ndarray


@dataclass
class ShapeFit:
    """The fit: the line (slope, intercept and their 95 % intervals; ``line_fitted``:
    from the free shapes, else the given calibration), EI with its s.e. and 95 %
    interval (None without pressed shapes), the shape residuals' RMS (mm) over
    ``points`` points, the Gauss–Newton iterations and forward solves."""

    slope: float
    intercept: float
    slope_ci95: tuple[float, float] | None
    intercept_ci95: tuple[float, float] | None
    line_fitted: bool
    EI: float | None
    EI_se: float | None
    EI_low: float | None
    EI_high: float | None
    rms_mm: float | None
    points: int
    free: int
    pressed: int
    iterations: int
    solves: int
    #: per pressed shape (x of its points in mm, their residuals in mm, ∂residual/∂ln EI),
    #: the points used: for the plot (not in the JSON)
    shape_residuals: list = dataclasses.field(default_factory=list, repr=False)

    def as_json(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v)
                for k, v in dataclasses.asdict(self).items() if k != "shape_residuals"}


def section_points(meas: dict, where: str = "shape") -> tuple[np.ndarray, float]:
    """The middle section's centre line in the frame of its chord (mm) and its θ (deg)
    from a ``vision measure --json`` dict: between its inflection points (the paper's,
    the circle fits', where present: they hold for a pressed section), as ``vision
    compare`` takes it."""
    try:
        c = np.asarray(meas["centerline_mm"], dtype=float).reshape(-1, 2)
        secs = meas["sections"]
        mid = int(meas["middle"]["index"])
        theta = float(meas["middle"]["theta_deg"])
        circles = (meas.get("circle_fits") or {}).get("sections")
        sec = (circles or secs)[mid]
        p1, p2 = np.asarray(sec["start_mm"], float), np.asarray(sec["end_mm"], float)
        span = float(meas.get("pin_span_mm", c[-1, 0]))
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise ProblemError(f"--shapes: {where} is not the JSON of `lcpbench vision measure "
                           f"--json` ({type(exc).__name__}: {exc})") from None
    if not (np.all(np.isfinite(c)) and math.isfinite(theta)) or c.shape[0] < 8:
        raise ProblemError(f"--shapes: {where}: its centre line needs 8 or more finite "
                           "points and a finite theta")
    if len(secs) > 1:
        full = np.vstack([[0.0, 0.0], c, [span, 0.0]])
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(full, axis=0).T))])
        s1 = s[np.argmin(np.hypot(*(full - p1).T))]
        s2 = s[np.argmin(np.hypot(*(full - p2).T))]
        c = full[(s >= s1) & (s <= s2)]
    chord = p2 - p1
    L = float(np.hypot(*chord))
    if not L > 0:
        raise ProblemError(f"--shapes: {where}: the section's ends coincide")
    e = chord / L
    rel = c - p1
    return np.column_stack([rel @ e, rel @ np.array([-e[1], e[0]])]), theta


def read_shapes(path) -> list[Shape]:
    """The rows of a shapes CSV (header ``shape,pressure_kpa[,height_mm]``; ``shape``
    relative to the CSV; an empty height: a free actuator)."""
    rows = []
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            head = [c.strip() for c in next(reader, [])]
            if head[:2] != ["shape", "pressure_kpa"] or head[2:] not in ([], ["height_mm"]):
                raise ProblemError(f"--shapes: {path}: the header must be shape,pressure_kpa"
                                   f"[,height_mm], got {','.join(head)!r}")
            for k, row in enumerate(reader, start=2):
                if not row or not "".join(row).strip() or row[0].strip().startswith("#"):
                    continue
                rows.append(_row(path, k, row))
    except OSError as exc:
        raise ProblemError(f"--shapes: cannot read {str(path)!r} ({exc.strerror})") from exc
    if not rows:
        raise ProblemError(f"--shapes: {path}: no rows")
    return rows


def _row(path, k: int, row: list[str]) -> Shape:
    try:
        P = float(row[1])
        h = float(row[2]) if len(row) > 2 and row[2].strip() else None
    except (IndexError, ValueError):
        raise ProblemError(f"--shapes: {path}: row {k} is not shape,pressure_kpa"
                           f"[,height_mm]") from None
    if not math.isfinite(P) or (h is not None and not (math.isfinite(h) and h > 0)):
        raise ProblemError(f"--shapes: {path}: row {k}: the pressure must be finite and a "
                           "height > 0 mm (or empty: a free actuator)")
    name = os.path.join(os.path.dirname(str(path)), row[0].strip())
    try:
        with open(name, encoding="utf-8") as fh:
            meas = json.load(fh)
    except (OSError, ValueError) as exc:
        raise ProblemError(f"--shapes: row {k}: cannot read {name!r} as JSON ({exc})") from None
    points, theta = section_points(meas, name)
    return Shape(P, h, theta, points)


def fit_shapes(scene, shapes: list[Shape], calibration, *, tol: float = 1e-10) -> ShapeFit:
    """The line from the free shapes (else ``calibration``), then EI from the pressed
    ones (module docstring); ``scene`` gives N, ℓ, w, the walls and the starting EI."""
    from .calibrate import fit_theta_pressure
    from .errors import VisionError

    free = [s for s in shapes if s.height is None]
    pressed = [s for s in shapes if s.height is not None]
    cov_line = np.zeros((2, 2))
    slope, intercept = float(calibration.slope), float(calibration.intercept)
    ci_s = ci_i = None
    if free:
        try:
            line = fit_theta_pressure([s.pressure for s in free], [s.theta_deg for s in free])
        except VisionError as exc:
            raise ProblemError(f"--shapes: the free shapes: {exc}") from None
        slope, intercept = line.slope, line.intercept
        ci_s = tuple(float(v) for v in line.slope_ci95)
        ci_i = tuple(float(v) for v in line.intercept_ci95)
        if line.n > 2:
            P = np.array([s.pressure for s in free])
            A = np.column_stack([P, np.ones(P.size)])
            cov_line = line.rmse_deg**2 * line.n / (line.n - 2) * np.linalg.inv(A.T @ A)
    out = ShapeFit(slope, intercept, ci_s, ci_i, bool(free), None, None, None, None, None,
                   0, len(free), len(pressed), 0, 0)
    if pressed:
        _fit_EI(scene, pressed, slope, intercept, cov_line, tol, out)
    return out


def _fit_EI(scene, pressed, slope, intercept, cov_line, tol, out: ShapeFit) -> None:
    """Gauss–Newton in (ln EI, and per shape its frame: a shift and a turn of the
    measured points, whose chord ends are measured too); ``out`` filled in."""
    from scipy.stats import t as student

    from ..api import check_tol, solve
    from ..model.sensitivity import sensitivities
    from .jointfit import correlation_inflation

    tol = check_tol(tol)
    last: list = [None] * len(pressed)
    cache: dict = {}

    def model(EI):  # per shape: the model at each point's arc length, ∂/∂ln EI, ∂/∂θ
        if EI in cache:
            return cache[EI]
        got = []
        for i, sh in enumerate(pressed):
            sc = dataclasses.replace(scene, EI=float(EI), height=float(sh.height),
                                     theta=float(slope * sh.pressure + intercept))
            res = solve(sc, tol=tol, start=last[i])
            out.solves += 1
            if not res.converged:
                raise ProblemError(f"fit --shapes: the forward solve at P = {sh.pressure:g} "
                                   f"(theta {sc.theta:.4g} deg, h {sh.height:g} mm, EI "
                                   f"{EI:.4g}) did not converge ({res.reason})")
            last[i] = res
            sens = sensitivities(res, wrt=("EI", "theta_deg"))
            got.append((np.column_stack([res.x, res.y]),
                        EI * _node_derivative(res, sens.heights["EI"]),
                        _node_derivative(res, sens.heights["theta_deg"])))
        cache.clear()
        cache[EI] = got
        return got

    S = len(pressed)
    frames = np.zeros((S, 3))  # (shift x, shift y, turn) of each shape's points

    xs: list = []

    def residual(EI, frames):  # signed normal distances to the model's centre line
        got = model(EI)
        xs.clear()
        r, J, T = [], [], []
        cols = 1 + 3 * S
        for i, (sh, (nodes, d_ei, d_th)) in enumerate(zip(pressed, got, strict=True)):
            c, s_ = math.cos(frames[i, 2]), math.sin(frames[i, 2])
            p = sh.points @ np.array([[c, s_], [-s_, c]]) + frames[i, :2]
            k, w, n = _foot(nodes, p)
            # a point whose nearest place is on an end link lies past the model's ends
            # (the measured inflection points are uncertain along the curve): left out
            n = n * ((k > 0) & (k < nodes.shape[0] - 2))[:, None]
            r.append(np.einsum("ij,ij->i", n, _interp(nodes, k, w) - p))
            xs.append(p[:, 0])
            block = np.zeros((p.shape[0], cols))
            block[:, 0] = np.einsum("ij,ij->i", n, _interp(d_ei, k, w))
            block[:, 1 + 3 * i] = -n[:, 0]
            block[:, 2 + 3 * i] = -n[:, 1]
            q = p - frames[i, :2]  # −∂p/∂turn = (q_y, −q_x)
            block[:, 3 + 3 * i] = n[:, 0] * q[:, 1] - n[:, 1] * q[:, 0]
            J.append(block)
            T.append(np.einsum("ij,ij->i", n, _interp(d_th, k, w)) * np.array(
                [[sh.pressure], [1.0]]))
        return np.concatenate(r), np.vstack(J), np.hstack(T).T

    z = math.log(scene.EI)
    r, J, Jt = residual(scene.EI, frames)
    xs_at = list(xs)  # (the points' x of the state accepted last)
    for it in range(1, MAX_ITER + 1):
        out.iterations = it
        step, *_ = np.linalg.lstsq(J, -r, rcond=None)
        t, moved = 1.0, False
        while t >= 1e-6:
            try:
                r2, J2, Jt2 = residual(math.exp(z + t * step[0]),
                                       frames + t * step[1:].reshape(S, 3))
            except ProblemError:
                r2 = None
            if r2 is not None and r2 @ r2 <= (r @ r) * (1 + 1e-12):
                z, frames, r, J, Jt, moved = (z + t * step[0],
                                              frames + t * step[1:].reshape(S, 3), r2, J2,
                                              Jt2, True)
                xs_at = list(xs)
                break
            t *= 0.5
        if not moved or abs(t * step[0]) <= STEP_TOL:
            break
    used = np.any(J != 0.0, axis=1)  # (the points left out have zero rows)
    ends = np.cumsum([0] + [x.size for x in xs_at])
    out.shape_residuals = [(xs_at[i][used[a:b]], r[a:b][used[a:b]], J[a:b, 0][used[a:b]])
                           for i, (a, b) in enumerate(zip(ends[:-1], ends[1:], strict=True))]
    r, J, Jt = r[used], J[used], Jt[used]
    m, k = r.size, J.shape[1]
    dof = max(m - k, 1)
    s2 = float(r @ r) / dof * correlation_inflation(r)
    # ln EI's column with the frames projected out: where it vanishes (no weight: the
    # shape does not depend on EI; a relative change of EI moves the points by less than
    # 1e-9 ℓ RMS) EI is not determined and its interval is unbounded
    F = J[:, 1:]
    e0 = J[:, 0] - F @ np.linalg.lstsq(F, J[:, 0], rcond=None)[0]
    info = float(e0 @ e0)
    if not math.sqrt(info / m) > 1e-9 * scene.length:  # (moves no point by 1e-9 ℓ)
        var_z = math.inf
    else:
        C = np.linalg.inv(J.T @ J)
        # the calibration line's covariance carried through: ∂ln EI/∂(slope, intercept)
        g = -(C @ (J.T @ Jt))[0]
        var_z = s2 * C[0, 0] + float(g @ cov_line @ g)
    EI, se_z = math.exp(z), math.sqrt(max(var_z, 0.0))
    half = float(student.ppf(0.975, dof)) * se_z
    out.EI, out.EI_se = EI, EI * se_z
    bounded = half <= 50.0  # (beyond a factor e^50 either way: not determined at all)
    out.EI_low = EI * math.exp(-half) if bounded else 0.0
    out.EI_high = EI * math.exp(half) if bounded else math.inf
    out.rms_mm = float(np.sqrt(np.mean(r**2)))
    out.points = m


def _foot(nodes: np.ndarray, p: np.ndarray):
    """Each point's nearest place on the polyline ``nodes``: its link k, its share w
    along it, and the link's unit normal (M × 2)."""
    a, d = nodes[:-1], np.diff(nodes, axis=0)  # links
    dd = np.einsum("ij,ij->i", d, d)
    rel = p[:, None, :] - a[None, :, :]
    w = np.clip(np.einsum("mkj,kj->mk", rel, d) / dd, 0.0, 1.0)
    gap = rel - w[..., None] * d[None]
    k = np.argmin(np.einsum("mkj,mkj->mk", gap, gap), axis=1)
    t = d[k] / np.sqrt(dd[k])[:, None]
    return k, w[np.arange(p.shape[0]), k], np.column_stack([-t[:, 1], t[:, 0]])


def _interp(nodes: np.ndarray, k: np.ndarray, w: np.ndarray) -> np.ndarray:
    return nodes[k] * (1 - w)[:, None] + nodes[k + 1] * w[:, None]


def _node_derivative(res, d_heights: np.ndarray) -> np.ndarray:
    """(∂x, ∂y) of every node (N + 1 × 2) from ∂y of the free nodes (the pins fixed in
    y): ∂x_k = −Σ_{j<k} tan α_j (∂y_{j+1} − ∂y_j)."""
    chain = res.scene.chain()
    dy = np.zeros(chain.links + 1)
    dy[chain.free_nodes] = d_heights
    dx = np.concatenate([[0.0], np.cumsum(-np.tan(res.alpha) * np.diff(dy))])
    return np.column_stack([dx, dy])


__all__ = ["Shape", "ShapeFit", "fit_shapes", "read_shapes", "section_points"]
