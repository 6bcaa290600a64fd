"""The picture of a solve against walls of any profile y = h(x) (``lcpbench solve
--wall-profile F.csv --plot F.png``): the shape, the profile wall(s), and the
reactions as arrows normal to the wall (their vertical parts are the forces R)."""

from __future__ import annotations

import numpy as np


def plot_profile_shape(result, path):
    """Draw a profile-wall :class:`~lcpbench.model.result.ContactResult` to ``path``.

    The constrained shape over the unconstrained one, each wall profile over
    the chain's x range, and one arrow per contact node along the wall's
    normal, of length proportional to the normal force R·sqrt(1 + h'²) (the
    largest about a third of the wall height). Axes in mm. Returns the Figure.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..model.chain import node_positions

    scene = result.scene
    chain = scene.chain()
    x0, y0 = node_positions(chain, chain.rest_alpha)
    x, y = np.asarray(result.x, float), np.asarray(result.y, float)
    fig = Figure(figsize=(7.0, 3.6), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot(x0, y0, "--", color="0.6", lw=1.2, label="unconstrained")
    ax.plot(x, y, "-", color="C0", lw=2.0, marker="o", ms=2.0, zorder=3, label="constrained")
    lo, hi = scene.x_reach
    grid = np.linspace(lo, hi, 400)
    free = chain.free_nodes
    walls = [(chain.upper_profile, np.asarray(result.forces, float), -1.0)]
    if chain.lower_profile is not None and result.forces_lower is not None:
        walls.append((chain.lower_profile, np.asarray(result.forces_lower, float), 1.0))
    top = max(float(np.max(np.abs(p(grid)))) for p, _, _ in walls)
    fmax = max(float(np.max(f, initial=0.0) * np.sqrt(1 + np.max(p.slope(x[free]) ** 2)))
               for p, f, _ in walls)
    scale = top / 3.0 / fmax if fmax > 0 else 0.0
    for i, (prof, force, sign) in enumerate(walls):
        ax.plot(grid, prof(grid), color="0.25", lw=1.5, zorder=1,
                label="wall" if i == 0 else None)
        on = np.flatnonzero(force > 1e-9 * max(fmax, 1e-300))
        for k in on:
            xk = x[free[k]]
            slope = float(prof.slope(xk))
            nx, ny = -sign * slope, sign  # μ (h', −1) upper, ν (−l', 1) lower
            length = force[k] * scale
            ax.annotate("", xy=(xk + nx * length, float(prof(xk)) + ny * length),
                        xytext=(xk, float(prof(xk))),
                        arrowprops={"arrowstyle": "->", "color": "C3", "lw": 1.2})
    ax.set_title(f"F = {1e3 * result.total_force:.4g} mN (vertical parts of the wall's "
                 f"normal reactions), {'converged' if result.converged else 'NOT converged'}",
                 fontsize=9)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_aspect("equal")
    ax.legend(fontsize=7, loc="upper right")
    fig.savefig(path, dpi=130)
    return fig
