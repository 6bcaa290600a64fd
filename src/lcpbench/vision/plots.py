"""Figures of the pipeline: the detections over the photograph (Figs. 15-18), θ
against pressure (Fig. 20), the model-photograph comparison (Fig. 23) and the fit
from shapes (`fit --shapes`)."""

from __future__ import annotations

import numpy as np

from .errors import VisionError


def _plt():
    try:
        import matplotlib
    except ImportError:
        raise VisionError("--plot needs matplotlib: pip install 'lcpbench[plot]'") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(fig, out) -> None:
    try:
        fig.savefig(out, dpi=130, bbox_inches="tight")
    except OSError as exc:
        raise VisionError(f"{out}: cannot write the plot ({exc.strerror})") from None
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)


def _crop(meas, pad: float = 0.06) -> tuple[float, float, float, float]:
    """Pixel box (x0, x1, y0, y1) around the actuator, the bearings and the marker."""
    r = meas.bearings.radius_px
    pts = np.vstack([meas.centerline_px, meas.marker.corners,
                     meas.bearings.left - r, meas.bearings.left + r,
                     meas.bearings.right - r, meas.bearings.right + r])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    m = pad * max(hi - lo)
    h, w = meas.image.shape[:2]
    return (max(lo[0] - m, -0.5), min(hi[0] + m, w - 0.5),
            max(lo[1] - m, -0.5), min(hi[1] + m, h - 0.5))


def plot_measurement(meas, out, truth: dict | None = None) -> None:
    """Two panels stacked, each sized to its content, each legend in a strip below
    it: (a) the undistorted photograph cropped to the fixture, with the marker, the
    bearings, the pin line, the sub-pixel centerline and the joint fit's arcs and
    inflection points drawn over it (Figs. 15-18); (b) the levelled centerline in mm
    with the joint fit (θ ± s.e., ℓ ± s.e. per section) and, dashed, the paper's
    per-section circle fits (eqs. 38-39); the warnings, if any, under it."""
    from .stages import to_px

    plt = _plt()
    colours = ["tab:blue", "tab:purple", "tab:green", "tab:brown", "tab:olive"]
    x0, x1, y0, y1 = _crop(meas)
    asp_a = (y1 - y0) / (x1 - x0)
    c = meas.centerline_mm
    span = meas.pin_span_mm
    arcs = [_arc_points(s) for s in meas.sections]
    allb = np.vstack([c, *arcs, [[0, 0], [span, 0]]])
    blo, bhi = allb.min(axis=0), allb.max(axis=0)
    pad = 0.04 * (bhi[0] - blo[0])
    bx = (blo[0] - pad, bhi[0] + pad)
    by = (blo[1] - pad, bhi[1] + pad)
    asp_b = (by[1] - by[0]) / (bx[1] - bx[0])
    if asp_b < 0.2:                       # a flat actuator: give (b) some height
        mid, half = 0.5 * (by[0] + by[1]), 0.1 * (bx[1] - bx[0])
        by, asp_b = (mid - half, mid + half), 0.2
    # layout in inches: [title, (a), x label, legend (a)], then the same for (b)
    fig_w, side = 9.0, 0.75
    wa = min(fig_w - 2 * side, 5.6 / asp_a)
    ha, wb = wa * asp_a, fig_w - 2 * side
    hb = wb * asp_b
    n_warn = len(meas.warnings)
    leg_a, leg_b = 0.55, 0.75 + 0.17 * n_warn
    gap = 0.45                             # title above a panel
    lab = 0.5                              # x label and tick labels below it
    fig_h = gap + ha + lab + leg_a + 1.4 * gap + hb + lab + leg_b
    fig = plt.figure(figsize=(fig_w, fig_h))
    ya = (fig_h - gap - ha) / fig_h
    a = fig.add_axes([(fig_w - wa) / 2 / fig_w, ya, wa / fig_w, ha / fig_h])
    yb = (leg_b + lab) / fig_h
    b = fig.add_axes([side / fig_w, yb, wb / fig_w, hb / fig_h])

    a.imshow(meas.image[..., ::-1])
    q = np.vstack([meas.marker.corners, meas.marker.corners[:1]])
    a.plot(q[:, 0], q[:, 1], "-", color="deepskyblue", lw=1.5,
           label=f"ArUco marker ({meas.px_per_mm:.3f} px/mm)")
    bl, br = meas.bearings.left, meas.bearings.right
    t = np.linspace(0, 2 * np.pi, 100)
    for k, cc in enumerate((bl, br)):
        a.plot(cc[0] + meas.bearings.radius_px * np.cos(t), cc[1] + meas.bearings.radius_px *
               np.sin(t), "-", color="lime", lw=1.2, label="pin bearings" if k == 0 else None)
    a.plot([bl[0], br[0]], [bl[1], br[1]], "--", color="yellow", lw=1,
           label=f"pin line (level {meas.level_deg:+.2f}°)")
    cpx = meas.centerline_px
    a.plot(cpx[:, 0], cpx[:, 1], "-", color="magenta", lw=0.8, label="centerline (sub-pixel)")
    for j, arc in enumerate(arcs):
        apx = to_px(arc, meas.bearings, meas.px_per_mm)
        a.plot(apx[:, 0], apx[:, 1], "-", color=colours[j % 5], lw=2, alpha=0.9,
               label="joint fit: one arc per section" if j == 0 else None)
    if len(meas.inflection_points_mm):
        ipx = to_px(meas.inflection_points_mm, meas.bearings, meas.px_per_mm)
        a.plot(ipx[:, 0], ipx[:, 1], "s", color="red", ms=6, mec="k", mew=0.5,
               label="inflection points (joint fit)")
    bar = 10 * meas.px_per_mm
    bx0, by0 = x1 - bar - 0.04 * (x1 - x0), y1 - 0.05 * (y1 - y0)
    a.plot([bx0, bx0 + bar], [by0, by0], "-", color="k", lw=3)
    a.text(bx0 + bar / 2, by0 - 0.015 * (y1 - y0), "10 mm", ha="center", va="bottom",
           fontsize=8)
    a.set_xlim(x0, x1)
    a.set_ylim(y1, y0)
    a.set_title("(a) undistorted photograph: detected features and the fitted arcs",
                fontsize=10)
    a.set_xlabel("x (px)", fontsize=8)
    a.set_ylabel("y (px)", fontsize=8)
    a.tick_params(labelsize=7)
    a.legend(loc="upper center", bbox_to_anchor=(0.5, -lab / ha), ncol=3, fontsize=7,
             frameon=False)

    b.plot(c[:, 0], c[:, 1], ".", color="0.35", ms=1.5, label="centerline (measured)")
    for j, (s, arc) in enumerate(zip(meas.sections, arcs)):
        tag = " (middle)" if j == meas.middle else ""
        se = (f" ± {s.theta_se_deg:.2g}°" if s.theta_se_deg is not None else "°",
              f" ± {s.arc_length_se_mm:.2g} mm" if s.arc_length_se_mm is not None else " mm")
        b.plot(arc[:, 0], arc[:, 1], "-", color=colours[j % 5], lw=1.6,
               label=f"section {j + 1}{tag}: θ = {s.theta_deg:.2f}{se[0]}, "
                     f"ℓ = {s.arc_length_mm:.2f}{se[1]}")
    if meas.circle_fits is not None:
        for j, s in enumerate(meas.circle_fits):
            arc = _arc_points(s)
            cm = meas.circle_fits[meas.middle]
            b.plot(arc[:, 0], arc[:, 1], "--", color="0.15", lw=0.8, label=None if j else
                   f"circle per section (eqs. 38-39): middle θ = {cm.theta_deg:.2f}°, "
                   f"ℓ = {cm.arc_length_mm:.2f} mm")
        kn = meas.circle_knots_mm
        b.plot(kn[:, 0], kn[:, 1], "s", mfc="none", mec="k", ms=7,
               label="their inflection points")
    if len(meas.inflection_points_mm):
        ip = meas.inflection_points_mm
        b.plot(ip[:, 0], ip[:, 1], "s", color="red", ms=5, label="inflection points (joint fit)")
    b.plot([0, span], [0, 0], "o", color="k", ms=6, label="pins (bearing centres)")
    conf = meas.confidence
    what = (f"RMS residual {conf.rms_px:.2f} px, section lengths spread "
            f"{100 * conf.length_spread:.2f} %") if conf is not None else ""
    if truth is not None and "theta_deg" in truth:
        what += f"; truth θ = {truth['theta_deg']:g}°, ℓ = {truth['arc_length_mm']:g} mm"
    b.set_title(f"(b) levelled frame (mm), joint fit of {len(meas.sections)} arcs\n{what}",
                fontsize=10)
    b.set_xlim(*bx)
    b.set_ylim(*by)
    b.set_aspect("equal")
    b.set_xlabel("x along the pin line (mm)", fontsize=8)
    b.set_ylabel("y (mm)", fontsize=8)
    b.tick_params(labelsize=7)
    b.grid(alpha=0.3)
    b.legend(loc="upper center", bbox_to_anchor=(0.5, -lab / hb), ncol=2, fontsize=7,
             frameon=False)
    for k, w in enumerate(meas.warnings):
        fig.text(0.5, (0.12 + 0.17 * (n_warn - 1 - k)) / fig_h, "warning: " + w, ha="center",
                 va="bottom", color="tab:red", fontsize=7, wrap=True)
    _save(fig, out)


def _arc_points(s) -> np.ndarray:
    c = np.asarray(s.center_mm)
    a1 = np.arctan2(s.start_mm[1] - c[1], s.start_mm[0] - c[0])
    a2 = np.arctan2(s.end_mm[1] - c[1], s.end_mm[0] - c[0])
    th = np.radians(s.theta_deg)
    # go from a1 by ±θ, whichever lands on a2
    sign = 1 if abs(np.angle(np.exp(1j * (a1 + th - a2)))) < abs(np.angle(np.exp(
        1j * (a1 - th - a2)))) else -1
    t = a1 + sign * np.linspace(0, th, 200)
    return c + s.radius_mm * np.column_stack([np.cos(t), np.sin(t)])


def plot_calibration(pressure, theta, fit, out, unit: str = "kPa") -> None:
    """Bend angle against pressure like Fig. 20: the mean at each pressure with the
    range of the repeats as error bars, the fitted line and its 95 % band."""
    from scipy import stats

    plt = _plt()
    p = np.asarray(pressure, float)
    t = np.asarray(theta, float)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    ps = np.unique(p)
    mean = np.array([t[p == v].mean() for v in ps])
    lo = mean - np.array([t[p == v].min() for v in ps])
    hi = np.array([t[p == v].max() for v in ps]) - mean
    ax.errorbar(ps, mean, yerr=[lo, hi], fmt="o", color="tab:blue", capsize=3,
                label=f"measured (mean, range of repeats; {len(t)} images)")
    x = np.linspace(p.min(), p.max(), 100)
    ax.plot(x, fit.slope * x + fit.intercept, "-", color="tab:red",
            label=f"θ = {fit.slope:.4g}·P + {fit.intercept:.4g}  (R² = {fit.r2:.4f})")
    if fit.n > 2:
        n, pm = len(p), p.mean()
        s = fit.rmse_deg * np.sqrt(n / (n - 2))
        se = s * np.sqrt(1 / n + (x - pm) ** 2 / ((p - pm) ** 2).sum())
        q = stats.t.ppf(0.975, n - 2)
        yy = fit.slope * x + fit.intercept
        ax.fill_between(x, yy - q * se, yy + q * se, color="tab:red", alpha=0.15,
                        label="95 % confidence band of the line")
    ax.set_xlabel(f"pressure P ({unit})")
    ax.set_ylabel("middle-section bend angle θ (deg)")
    ax.set_title("Unconstrained bend angle against pressure (cf. Fig. 20, eqs. 40-42)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    _save(fig, out)


def plot_comparison(cmp, out) -> None:
    """(a) Model and photographed centerlines after ICP, with the walls; (b) the
    point-pair distances in mm and in % of the span (Fig. 23)."""
    plt = _plt()
    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 4.6))
    a.plot(cmp.photo_mm[:, 0], cmp.photo_mm[:, 1], "-", color="tab:orange", lw=3, alpha=0.7,
           label="photographed centerline (after ICP)")
    a.plot(cmp.model_mm[:, 0], cmp.model_mm[:, 1], ".", color="tab:blue", ms=3,
           label=f"model, N = {len(cmp.model_mm) - 1} (lcpbench.solve)")
    from .geometry import offset_curve

    for k, sgn in enumerate((1, -1)):
        e = offset_curve(cmp.model_mm, sgn * cmp.radius_mm)
        a.plot(e[:, 0], e[:, 1], "-", color="0.5", lw=0.8,
               label=f"model tube surface (±{cmp.radius_mm:g} mm)" if k == 0 else None)
    xs = [cmp.model_mm[:, 0].min() - 2, cmp.model_mm[:, 0].max() + 2]
    for k, h in enumerate((cmp.wall_face_mm, -cmp.wall_face_mm)):
        a.plot(xs, [h, h], "k-", lw=2, label="wall faces (±h)" if k == 0 else None)
    a.set_aspect("equal")
    a.set_xlabel("x (mm)")
    a.set_ylabel("y (mm)")
    a.set_title(f"(a) θ = {cmp.theta_deg:.1f}°, wall face {cmp.wall_face_mm:g} mm, "
                f"force {1e3 * cmp.force_n:.2f} mN")
    a.grid(alpha=0.3)
    a.legend(fontsize=7, loc="lower center", bbox_to_anchor=(0.5, 0.06), ncol=2)
    idx = np.arange(len(cmp.distances_mm))
    b.plot(idx, cmp.distances_mm, "-", color="tab:blue")
    b.set_xlabel("point pair index (0 = left pin)")
    b.set_ylabel("point pair distance (mm)", color="tab:blue")
    b2 = b.twinx()
    b2.plot(idx, cmp.percent, alpha=0)
    b2.set_ylabel("% of the span in x (eq. 43)")
    lo, hi = b.get_ylim()
    b2.set_ylim(100 * lo / cmp.span_mm, 100 * hi / cmp.span_mm)
    b.set_title(f"(b) mean {cmp.distances_mm.mean():.4f} mm ({cmp.percent.mean():.3f} %), "
                f"max {cmp.distances_mm.max():.4f} mm")
    b.grid(alpha=0.3)
    _save(fig, out)


def plot_shape_fit(out, shapes, got) -> None:
    """``fit --shapes``: (a) the free shapes' θ against pressure and the fitted line;
    (b) each pressed shape's residuals (normal distance to the model at the fitted EI,
    µm) along x, with the change that EI at either end of its 95 % interval would make
    (what the photographs have to resolve)."""
    plt = _plt()
    fig, (ax, bx) = plt.subplots(2, 1, figsize=(6.4, 7.2))
    free = [s for s in shapes if s.height is None]
    ps = np.array([s.pressure for s in shapes])
    x = np.linspace(ps.min(), ps.max(), 50)
    if free:
        ax.plot([s.pressure for s in free], [s.theta_deg for s in free], "o", color="tab:blue",
                label=f"free shapes ({len(free)})")
    ax.plot(x, got.slope * x + got.intercept, "-", color="tab:red",
            label=f"θ = {got.slope:.4g}·P + {got.intercept:.4g}"
            + ("" if got.line_fitted else " (given)"))
    ax.set_xlabel("pressure P (kPa)")
    ax.set_ylabel("middle-section θ (deg)")
    ax.set_title("(a) the calibration line (eqs. 40-42)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    pressed = [s for s in shapes if s.height is not None]
    for i, (sh, (xs, r, d)) in enumerate(zip(pressed, got.shape_residuals, strict=False)):
        order = np.argsort(xs)
        c = f"C{i % 10}"
        bx.plot(xs[order], 1e3 * r[order], ".", ms=2, color=c,
                label=f"P = {sh.pressure:g} kPa, h = {sh.height:g} mm")
        if got.EI_high is not None and np.isfinite(got.EI_high) and got.EI_low > 0:
            for end in (got.EI_low, got.EI_high):
                bx.plot(xs[order], 1e3 * d[order] * np.log(end / got.EI), "-", lw=0.8,
                        color=c, alpha=0.6)
    title = "(b) pressed shapes: residuals at the fitted EI"
    if got.EI is not None:
        title += (f", EI = {got.EI:.4g} N mm²; lines: the model at the interval's ends "
                  f"({got.EI_low:.3g} .. {got.EI_high:.3g})")
    bx.set_title(title, fontsize=8)
    bx.set_xlabel("x along the section's chord (mm)")
    bx.set_ylabel("normal distance to the model (µm)")
    bx.grid(alpha=0.3)
    if pressed:
        bx.legend(fontsize=8)
    fig.tight_layout()
    _save(fig, out)
