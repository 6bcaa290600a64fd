"""The figures of ``lcpbench reproduce``, one function per figure of the paper.

Each function takes the rows that :mod:`lcpbench.paper.reproduce` also writes
as CSV, so a figure can be redrawn from its numbers. They draw on a bare
:class:`matplotlib.figure.Figure` with the Agg canvas (no pyplot, no global
backend), like :mod:`lcpbench.bench.plot`.
"""

from __future__ import annotations

import math

import numpy as np


def new_figure(size: tuple[float, float] = (7.0, 4.5)):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _colors(n: int) -> list:
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    return [cmap(v) for v in np.linspace(0.0, 0.9, max(n, 1))]


def plot_fig5(rows: list[dict], data: dict, path) -> None:
    """Fig. 5: percent change of the total force against N, and the N the rule picks.

    Left: the change between successive N (step 10) at the plot height, one
    curve per θ (log scale), the 0.01 % threshold and the N the grid needs.
    Right: the N the Sec. III-D rule picks for every scene of the grid.
    """
    fig = new_figure((11.0, 4.5))
    ax = fig.add_subplot(1, 2, 1)
    h = data["plot_height"]
    thetas = sorted({r["theta"] for r in rows if r["height"] == h})
    colors = _colors(len(thetas))
    for c, th in zip(colors, thetas):
        pts = [(r["links"], r["percent_change"]) for r in rows
               if r["height"] == h and r["theta"] == th and math.isfinite(r["percent_change"])
               and r["percent_change"] > 0]
        if pts:
            ax.plot(*zip(*pts), "-o", ms=2.5, lw=1.0, color=c, label=f"{th:g}°")
    ax.axhline(data["threshold_percent"], color="C3", lw=1.0, ls="--",
               label=f"threshold {data['threshold_percent']:g} %")
    if data.get("grid_links"):
        ax.axvline(data["grid_links"], color="0.3", lw=1.0, ls=":",
                   label=f"rule's N (grid) = {data['grid_links']}")
    ax.axvline(140, color="C1", lw=1.0, ls="-.", label="paper's N = 140")
    ax.set_yscale("log")
    ax.set_xlabel("number of links N")
    ax.set_ylabel("change in total force from N − 10 (%)")
    ax.set_title(f"h = {h:g} mm, ℓ = 30 mm, EI = 32.01 N·mm²", fontsize=9)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=6, ncol=2)

    ax = fig.add_subplot(1, 2, 2)
    heights = sorted({s["height"] for s in data["scenes"]})
    for c, hh in zip(_colors(len(heights)), heights):
        pts = [(s["theta"], s["chosen"]) for s in data["scenes"]
               if s["height"] == hh and s["contact"] and s["chosen"] is not None]
        if pts:
            ax.plot(*zip(*pts), "-o", ms=3, color=c, label=f"h = {hh:g} mm")
    ax.axhline(140, color="C1", lw=1.0, ls="-.", label="paper: 140")
    ax.set_xlabel("bend angle θ (degrees)")
    ax.set_ylabel("N picked by the 0.01 % rule")
    ax.set_title("Sec. III-D rule per scene (scenes in contact)", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.savefig(path, dpi=130)


def plot_shapes(shapes: list[dict], key: str, path, title: str) -> None:
    """Figs. 6 and 7: constrained shapes (solid) over the unconstrained arcs (dashed)."""
    fig = new_figure((8.0, 4.5))
    ax = fig.add_subplot()
    colors = _colors(len(shapes))
    for c, s in zip(colors, shapes):
        label = f"θ = {s['theta']:g}°" if key == "theta" else f"h = {s['height']:g} mm"
        ax.plot(s["x0"], s["y0"], "--", lw=0.8, color=c, alpha=0.6)
        ax.plot(s["x"], s["y"], "-", lw=1.6, color=c,
                label=f"{label}: {1e3 * s['total_force']:.3g} mN")
        if key == "height":
            ax.axhline(s["height"], color=c, lw=0.7, ls=":")
    if key == "theta":
        ax.axhline(shapes[0]["height"], color="0.2", lw=1.5, label="wall")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(title + "; dashed: unconstrained", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.savefig(path, dpi=130)


def plot_fig8(a: list[dict], b: list[dict], c: list[dict], path) -> None:
    """Fig. 8: total force against θ per h (a), against EI per h (b) and per θ (c)."""
    fig = new_figure((15.0, 4.5))
    panels = [
        (a, "height", "theta", "bend angle θ (degrees)", "h = {:g} mm",
         "(a) against θ, EI = 32.01 N·mm²"),
        (b, "height", "EI", "bending stiffness EI (N·mm²)", "h = {:g} mm",
         "(b) against EI, θ = 150°"),
        (c, "theta", "EI", "bending stiffness EI (N·mm²)", "θ = {:g}°",
         "(c) against EI, h = 3 mm"),
    ]
    for k, (rows, group, xkey, xlabel, fmt, title) in enumerate(panels):
        ax = fig.add_subplot(1, 3, k + 1)
        groups = sorted({r[group] for r in rows})
        for col, g in zip(_colors(len(groups)), groups):
            pts = sorted((r[xkey], 1e3 * r["total_force"]) for r in rows if r[group] == g)
            ax.plot(*zip(*pts), "-o", ms=2.5, color=col, label=fmt.format(g))
        if k == 0:
            bad = [(r["theta"], 1e3 * r["total_force"]) for r in rows
                   if not r.get("undamped_converged", True)]
            if bad:
                ax.plot(*zip(*bad), "x", color="C3", ms=7,
                        label="undamped Fig. 3 iteration fails")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("total reaction force (mN)")
        ax.set_title(title, fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=6, ncol=2)
    fig.savefig(path, dpi=130)


def plot_cantilever(rows: list[dict], data: dict, path) -> None:
    """Fig. 10: the cantilever against beam theory, free (a) and against the wall (b)."""
    fig = new_figure((11.0, 4.5))
    ax = fig.add_subplot(1, 2, 1)
    s = np.array([r["s"] for r in rows])
    ax.plot([r["x_free"] for r in rows], [r["y_free"] for r in rows], "-", color="C0",
            lw=2.0, label="model (clamp 2EI/a, loads at link centres)")
    ax.plot([r["x_free_paper_like"] for r in rows], [r["y_free_paper_like"] for r in rows],
            "-", color="C2", lw=1.0, label="model, paper-like (clamp EI/a, loads at nodes)")
    ax.plot(s, [r["y_free_theory"] for r in rows], "--", color="k", lw=1.0,
            label="eq. (33), linear theory")
    ax.set_title(f"(a) free, F = {data['load']:g} N/mm: max node distance / ℓ = "
                 f"{data['free_max_distance']:.2e} (paper-like "
                 f"{data['free_max_distance_paper_like']:.2e})", fontsize=8)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("deflection toward the wall (mm)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)

    ax = fig.add_subplot(1, 2, 2)
    ax.plot([r["x_held"] for r in rows], [r["y_held"] for r in rows], "-", color="C0",
            lw=2.0, label="model")
    ax.plot(s, [r["y_held_theory"] for r in rows], "--", color="k", lw=1.0,
            label="theory: eq. (33) minus the tip load R_t")
    ax.axhline(data["height"], color="0.2", lw=1.5, label="wall")
    ax.set_title(f"(b) wall at h = {data['height']:g} mm: R = "
                 f"{1e3 * data['model_force']:.4g} mN, theory {1e3 * data['theory_force']:.4g}"
                 f" mN ({100 * data['relative_error']:+.3f} %)", fontsize=8)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("deflection toward the wall (mm)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.savefig(path, dpi=130)


def plot_fig24(rows: list[dict], data: dict, path) -> None:
    """Fig. 24 (top): model force against pressure per actuator, band from EI and w extremes.

    The band's range of EI and w is in each panel's legend.
    """
    from matplotlib.patches import Patch

    heights = sorted({r["height"] for r in rows})
    (ei_lo, w_hi), (ei_hi, w_lo) = data["corners"]["lo"], data["corners"]["hi"]
    band = Patch(color="0.5", alpha=0.3,
                 label=f"shaded: EI {ei_lo:g}–{ei_hi:g} N·mm², w {w_lo:g}–{w_hi:g} N/mm "
                       "(Sec. V-E)")
    fig = new_figure((15.0, 4.5))
    for k, h in enumerate(heights):
        ax = fig.add_subplot(1, len(heights), k + 1)
        for j, act in enumerate(sorted({r["actuator"] for r in rows})):
            sel = sorted((r for r in rows if r["height"] == h and r["actuator"] == act),
                         key=lambda r: r["pressure_kpa"])
            p = [r["pressure_kpa"] for r in sel]
            ax.fill_between(p, [1e3 * r["force_lo"] for r in sel],
                            [1e3 * r["force_hi"] for r in sel], color=f"C{j}", alpha=0.2)
            ax.plot(p, [1e3 * r["total_force"] for r in sel], "-", color=f"C{j}",
                    label=f"actuator {act}")
        knee = next(o["knee_kpa"] for o in data["onset"] if o["height"] == h)
        ax.axvline(knee, color="0.4", ls=":", lw=1.0, label=f"paper's knee {knee:g} kPa")
        ax.set_title(f"({'abc'[k]}) h = {h:g} mm (channel 2h)", fontsize=9)
        ax.set_xlabel("pressure P (kPa)")
        ax.set_ylabel("model total force (mN)")
        ax.grid(True, alpha=0.3)
        handles, _ = ax.get_legend_handles_labels()
        ax.legend(handles=[*handles, band], fontsize=7, loc="upper left")
    fig.savefig(path, dpi=130)


def plot_fig26(rows: list[dict], path) -> None:
    """Fig. 26: |R_LCP − R_NL| / (R_LCP + R_NL) × 100 against θ, one curve per h.

    Filled markers: the baseline's answer is a valid contact answer; open: it
    solves its equations but penetrates the wall (or needs a pulling wall).
    """
    fig = new_figure((8.0, 4.8))
    ax = fig.add_subplot()
    heights = sorted({r["height"] for r in rows})
    floor = 1e-12
    for col, h in zip(_colors(len(heights)), heights):
        sel = sorted((r for r in rows if r["height"] == h
                      and math.isfinite(r["analytic_disagreement_percent"])),
                     key=lambda r: r["theta"])
        if not sel:
            continue
        th = [r["theta"] for r in sel]
        d = [max(r["analytic_disagreement_percent"], floor) for r in sel]
        ax.plot(th, d, "-", color=col, lw=1.0, label=f"h = {h:g} mm")
        for t, v, r in zip(th, d, sel):
            ax.plot([t], [v], "o", ms=4, color=col,
                    mfc=col if r["analytic_valid"] else "white")
    ax.axhline(0.1, color="C3", ls="--", lw=1.0, label="0.1 % (paper, h ≥ 4 mm)")
    ax.plot([], [], "o", color="0.3", mfc="white", label="baseline penetrates the wall")
    ax.set_yscale("log")
    ax.set_xlabel("bend angle θ (degrees)")
    ax.set_ylabel("|R_LCP − R_NL| / (R_LCP + R_NL) (%)")
    n = rows[0]["links"] if rows else 0
    ax.set_title(f"Fig. 26: LCP against the root-finding baseline (analytic Jacobian), "
                 f"N = {n}", fontsize=9)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.savefig(path, dpi=130)


def plot_fig27(panels: list[dict], path) -> None:
    """Fig. 27: LCP and baseline shapes at θ = 150°, h = 3 mm (a) and 1 mm (b)."""
    fig = new_figure((11.0, 4.0))
    for k, p in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), k + 1)
        ax.plot(p["lcp_x"], p["lcp_y"], "-", color="C0", lw=2.0,
                label=f"LCP: {1e3 * p['lcp_force']:.4g} mN")
        ax.plot(p["nl_x"], p["nl_y"], "--", color="C3", lw=1.3,
                label=f"root finding: {1e3 * p['nl_force']:.4g} mN"
                      + ("" if p["nl_valid"] else
                         f" (beyond the wall by {p['nl_max_penetration']:.3g} mm)"))
        ax.axhline(p["height"], color="0.2", lw=1.5, label="wall")
        ax.set_title(f"({'ab'[k]}) θ = 150°, h = {p['height']:g} mm", fontsize=9)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_ylim(-0.5, p["height"] + 0.5 + max(p["nl_max_penetration"], 0.0))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="lower center")
    fig.savefig(path, dpi=130)


def plot_table2(rows: list[dict], paper: dict, path) -> None:
    """Table II as a plot: time over the fastest LCP solve against θ, ours and the paper's."""
    fig = new_figure((8.0, 4.8))
    ax = fig.add_subplot()
    th = [r["theta"] for r in rows]
    ax.plot(th, [r["lcp_norm"] for r in rows], "-o", color="C0", label="LCP (ours)")
    und = [(r["theta"], r["undamped_norm"]) for r in rows if math.isfinite(r["undamped_norm"])]
    if und:
        ax.plot(*zip(*und), ":s", color="C0", ms=4, mfc="white",
                label="LCP, undamped Fig. 3 iteration (ours; missing: diverged)")
    for key, col, name in (("analytic", "C3", "root finding, analytic Jacobian"),
                           ("fd", "C1", "root finding, finite differences (hybr)"),
                           ("fdlm", "C4", "root finding, finite differences (LM)")):
        ax.plot(th, [r[f"{key}_norm"] for r in rows], "-", color=col, lw=1.0,
                label=f"{name} (ours; open: not a valid answer)")
        for r in rows:
            ax.plot([r["theta"]], [r[f"{key}_norm"]], "o", color=col, ms=5,
                    mfc=col if r[f"{key}_valid"] else "white")
    ax.plot(paper["thetas"], paper["lcp"], "--^", color="C0", alpha=0.5, label="LCP (paper)")
    ax.plot(paper["thetas"], paper["nonlinear"], "--^", color="C3", alpha=0.5,
            label="nonlinear gradient descent (paper)")
    ax.set_yscale("log")
    ax.set_xlabel("bend angle θ (degrees)")
    ax.set_ylabel("time / fastest LCP solve")
    n = rows[0]["links"] if rows else 0
    ax.set_title(f"Table II: h = 1 mm, N = {n}; normalised to each study's fastest LCP solve",
                 fontsize=9)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=6)
    fig.savefig(path, dpi=130)
