"""Figures of the pipeline: the detections over the photograph (Figs. 15-18), θ
against pressure (Fig. 20) and the model-photograph comparison (Fig. 23)."""

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


def plot_measurement(meas, out, truth: dict | None = None) -> None:
    """(a) The undistorted photograph with the marker, the bearings, the pin line,
    the centerline, inflection points and the fitted circles (Figs. 15-18); (b) the
    levelled centerline in mm with the circle fits and θ, ℓ per section."""
    from .stages import to_px

    plt = _plt()
    fig, (a, b) = plt.subplots(1, 2, figsize=(15, 5.6), gridspec_kw={"width_ratios": [1.1, 1]})
    img = meas.image[..., ::-1]
    a.imshow(img)
    q = np.vstack([meas.marker.corners, meas.marker.corners[:1]])
    a.plot(q[:, 0], q[:, 1], "-", color="deepskyblue", lw=1.5,
           label=f"ArUco marker ({meas.px_per_mm:.3f} px/mm)")
    bl, br = meas.bearings.left, meas.bearings.right
    t = np.linspace(0, 2 * np.pi, 100)
    for k, c in enumerate((bl, br)):
        a.plot(c[0] + meas.bearings.radius_px * np.cos(t), c[1] + meas.bearings.radius_px *
               np.sin(t), "-", color="lime", lw=1.2, label="pin bearings" if k == 0 else None)
    a.plot([bl[0], br[0]], [bl[1], br[1]], "--", color="yellow", lw=1,
           label=f"pin line (level {meas.level_deg:+.2f}°)")
    cpx = meas.centerline_px
    a.plot(cpx[:, 0], cpx[:, 1], "-", color="magenta", lw=1, label="centerline (sub-pixel)")
    colours = ["tab:blue", "tab:purple", "tab:green", "tab:brown", "tab:olive"]
    for j, s in enumerate(meas.sections):
        arc = _arc_points(s)
        apx = to_px(arc, meas.bearings, meas.px_per_mm)
        a.plot(apx[:, 0], apx[:, 1], ":", color=colours[j % 5], lw=2)
    if len(meas.inflection_points_mm):
        ipx = to_px(meas.inflection_points_mm, meas.bearings, meas.px_per_mm)
        a.plot(ipx[:, 0], ipx[:, 1], "s", color="red", ms=6, label="inflection points")
    h, w = meas.image.shape[:2]
    bar = 10 * meas.px_per_mm
    x0, y0 = w - bar - 0.04 * w, h - 0.05 * h
    a.plot([x0, x0 + bar], [y0, y0], "-", color="k", lw=3)
    a.text(x0 + bar / 2, y0 - 0.015 * h, "10 mm", ha="center", va="bottom", fontsize=8)
    a.set_title("(a) undistorted photograph: detected features")
    a.set_xlabel("x (px)")
    a.set_ylabel("y (px)")
    a.legend(loc="lower left", fontsize=7, framealpha=0.85)

    c = meas.centerline_mm
    b.plot(c[:, 0], c[:, 1], ".", color="0.3", ms=1.5, label="centerline (measured)")
    for j, s in enumerate(meas.sections):
        arc = _arc_points(s)
        mid = " (middle)" if j == meas.middle else ""
        b.plot(arc[:, 0], arc[:, 1], "-", color=colours[j % 5], lw=1.5,
               label=f"section {j + 1}{mid}: θ = {s.theta_deg:.2f}°, ℓ = {s.arc_length_mm:.2f} mm")
    if len(meas.inflection_points_mm):
        ip = meas.inflection_points_mm
        b.plot(ip[:, 0], ip[:, 1], "s", color="red", ms=6, label="inflection points")
    b.plot([0, meas.pin_span_mm], [0, 0], "o", color="k", ms=6, label="pins")
    if truth is not None and "theta_deg" in truth:
        b.set_title(f"(b) levelled frame, circle fits (truth: θ = {truth['theta_deg']:g}°, "
                    f"ℓ = {truth['arc_length_mm']:g} mm)")
    else:
        b.set_title("(b) levelled frame, least-squares circle per section (eqs. 38-39)")
    b.set_xlabel("x along the pin line (mm)")
    b.set_ylabel("y (mm)")
    b.set_aspect("equal")
    b.grid(alpha=0.3)
    # below the flat panel (b), in figure coordinates, clear of its axis label
    fig.legend(*b.get_legend_handles_labels(), fontsize=7, loc="lower right",
               bbox_to_anchor=(0.99, 0.03), ncol=2)
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
    for k, h in enumerate((cmp.height_mm, -cmp.height_mm)):
        a.plot(xs, [h, h], "k-", lw=2, label="wall faces (±h)" if k == 0 else None)
    a.set_aspect("equal")
    a.set_xlabel("x (mm)")
    a.set_ylabel("y (mm)")
    a.set_title(f"(a) θ = {cmp.theta_deg:.1f}°, h = {cmp.height_mm:g} mm, "
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
