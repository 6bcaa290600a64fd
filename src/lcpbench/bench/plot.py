"""Figures. matplotlib is optional (``pip install 'lcpbench[plot]'``) and imported lazily.

The figures are drawn on a bare :class:`matplotlib.figure.Figure` with the Agg
canvas, so nothing here touches pyplot or the global backend.
"""

from __future__ import annotations

import numpy as np


def plot_shape(result, path) -> None:
    """Draw a :class:`~lcpbench.model.result.ContactResult` to ``path`` (PNG, PDF, SVG, ...).

    The constrained shape over the unconstrained one, the wall(s) as horizontal
    lines (at +h, and −h for a channel) and the reactions as arrows from the
    wall at the contact nodes, the largest about h/2 long; the total force in
    mN is in the title. Axes in mm, equal aspect.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..model.chain import node_positions

    scene = result.scene
    chain = scene.chain()
    x0, y0 = node_positions(chain, chain.rest_alpha)
    x, y = np.asarray(result.x, float), np.asarray(result.y, float)
    h = float(chain.wall)
    channel = bool(chain.channel)

    fig = Figure(figsize=(7.0, 4.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot(x0, y0, "--", color="0.6", lw=1.2, label="unconstrained")
    ax.plot(x, y, "-", color="C0", lw=2.0, marker="o", ms=2.0, zorder=3, label="constrained")

    xs = np.concatenate([x, x0])
    lo, hi = float(xs.min()), float(xs.max())
    pad = 0.05 * (hi - lo) if hi > lo else 1.0
    walls = [h] + ([-h] if channel else [])
    for i, yw in enumerate(walls):
        ax.axhline(yw, color="0.25", lw=1.5, zorder=1, label="wall" if i == 0 else None)

    # Reactions: arrows from the wall into the body (−y from the upper wall,
    # +y from the lower), the largest about h/2 long.
    free = chain.free_nodes
    sets = [(np.asarray(result.forces, float), h, -1.0)]
    if channel and result.forces_lower is not None:
        sets.append((np.asarray(result.forces_lower, float), -h, 1.0))
    fmax = max((float(f.max(initial=0.0)) for f, _, _ in sets), default=0.0)
    if fmax > 0:
        scale = 0.5 * h / fmax
        for k, (f, yw, sign) in enumerate(sets):
            idx = np.flatnonzero(f > 1e-9 * fmax)
            if idx.size == 0:
                continue
            ax.quiver(x[free[idx]], np.full(idx.size, yw), np.zeros(idx.size),
                      sign * scale * f[idx], angles="xy", scale_units="xy", scale=1.0,
                      color="C3", width=0.004, zorder=4, label="reaction" if k == 0 else None)

    total = 1e3 * float(result.total_force)
    title = f"total force {total:.4g} mN"
    if hasattr(scene, "theta"):
        title = f"θ = {scene.theta:g}°, h = {h:g} mm, N = {result.links}: " + title
    if channel and result.forces_lower is not None:
        title += f" (lower wall {1e3 * float(np.sum(result.forces_lower)):.4g} mN)"
    if not result.converged:
        title += " [not converged]"
    ax.set_title(title, fontsize=10)
    ax.set_xlim(lo - pad, hi + pad)
    ymin = min(float(np.min(y)), float(np.min(y0)), -h if channel else 0.0)
    ymax = max(float(np.max(y)), float(np.max(y0)), h)
    ypad = 0.1 * (ymax - ymin) if ymax > ymin else 1.0
    ax.set_ylim(ymin - ypad, ymax + ypad)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(loc="best", fontsize=8)
    fig.savefig(path, dpi=150)


def _figure(size=(7.0, 4.5)):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def plot_work_precision(summary: list[dict], evaluated, path) -> None:
    """Time against achieved error, one curve per back-end across its settings.

    A point is one (back-end, settings): the median force error over the
    scenes (x) against the median wall time of one solve (y), both over the
    runs that converged; its marker is filled when every run was a success.
    """
    import math

    fig = _figure((8.0, 5.5))
    ax = fig.add_subplot()
    order = {"default": 0, "low": 1, "mid": 2, "high": 3}
    by_backend: dict[str, list] = {}
    for e in evaluated:
        if (not e.row["converged"] or not math.isfinite(e.error)
                or e.row["method"] not in ("globalised", "hybr", "lm")):
            continue  # the undamped driver's runs are in the tables, not in this figure
        by_backend.setdefault(e.backend, {}).setdefault(e.settings, []).append(e)
    success = {(r["backend"], r["settings"]): r["success"] for r in summary
               if r["method"] in ("globalised", "hybr", "lm")}
    markers = "osD^v<>ph*X"
    for k, (backend, per) in enumerate(sorted(by_backend.items())):
        pts = []
        for settings in sorted(per, key=lambda s: order.get(s, 9)):
            es = per[settings]
            err = float(np.median([max(e.error, 1e-16) for e in es]))
            t = float(np.median([1e3 * e.row["wall_time"] for e in es]))
            pts.append((err, t, settings))
        color = f"C{k % 10}"
        marker = markers[k // 10 % len(markers)]
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "-", color=color, lw=1.0,
                alpha=0.7)
        for err, t, settings in pts:
            full = success.get((backend, settings), 0.0) == 1.0
            ax.plot([err], [t], marker, color=color, ms=6,
                    mfc=color if full else "white")
        ax.annotate(backend, (pts[-1][0], pts[-1][1]), fontsize=7, color=color,
                    xytext=(3, 2), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median force error |F − F_ref| / max(F_ref, EI/ℓ²)  (converged runs)")
    ax.set_ylabel("median time per solve (ms)")
    ax.set_title("Work-precision: each curve is one back-end across settings "
                 "(filled: every run a success)", fontsize=9)
    ax.grid(True, which="major", alpha=0.3)
    fig.savefig(path, dpi=130)


def plot_forces(refs: dict, evaluated, path) -> None:
    """Total force against θ for each h (the reference), with the baseline's valid answers."""
    import json

    fig = _figure()
    ax = fig.add_subplot()
    by_h: dict[float, list] = {}
    for r in refs.values():
        if r["converged"]:
            by_h.setdefault(r["height"], []).append((r["theta"], 1e3 * r["total_force"]))
    base: dict[float, list] = {}
    for e in evaluated:
        if e.backend == "baseline" and e.row["converged"]:
            base.setdefault(e.row["height"], []).append(
                (e.row["theta"], 1e3 * e.row["total_force"]))
    for k, h in enumerate(sorted(by_h)):
        pts = sorted(by_h[h])
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "-o", ms=3, color=f"C{k}",
                label=f"h = {h:g} mm")
        if h in base:
            b = sorted(base[h])
            ax.plot([p[0] for p in b], [p[1] for p in b], "x", ms=6, color=f"C{k}")
    ax.plot([], [], "x", color="0.3", label="root-finding baseline (valid answers)")
    ax.set_xlabel("bend angle θ (degrees)")
    ax.set_ylabel("total contact force (mN)")
    first = next(iter(refs.values()), None)
    if first is not None:
        scene = json.loads(first["scene"])
        ax.set_title(f"N = {scene['links']}, ℓ = {scene['length']:g} mm, "
                     f"EI = {scene['EI']:g} N·mm², w = {scene['weight']:g} N/mm "
                     "(reference solves)", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=130)


def plot_shapes(refs: dict, path, theta: float | None = None, height: float | None = None
                ) -> None:
    """Constrained shapes: against h at one θ (left), against θ at one h (right)."""
    rows = [r for r in refs.values() if r["converged"] and r["y"] is not None]
    if not rows:
        return
    thetas = sorted({r["theta"] for r in rows})
    heights = sorted({r["height"] for r in rows})
    theta = theta if theta is not None else min(thetas, key=lambda t: abs(t - 150.0))
    height = height if height is not None else heights[0]
    fig = _figure((11.0, 4.0))
    for k, (title, sel, label) in enumerate([
        (f"θ = {theta:g}°, against h", [r for r in rows if r["theta"] == theta],
         lambda r: f"h = {r['height']:g}"),
        (f"h = {height:g} mm, against θ", [r for r in rows if r["height"] == height],
         lambda r: f"{r['theta']:g}°"),
    ]):
        ax = fig.add_subplot(1, 2, k + 1)
        sel = sorted(sel, key=lambda r: (r["height"], r["theta"]))
        if k == 1 and len(sel) > 9:  # keep the figure readable
            sel = sel[:: max(1, len(sel) // 9)]
        for j, r in enumerate(sel):
            ax.plot(r["x"], r["y"], "-", lw=1.2, color=f"C{j % 10}", label=label(r))
            if k == 0:
                ax.axhline(r["height"], color=f"C{j % 10}", lw=0.6, ls=":")
        if k == 1:
            ax.axhline(height, color="0.25", lw=1.2)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize=6, ncol=2)
    fig.savefig(path, dpi=130)
