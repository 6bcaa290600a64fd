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
