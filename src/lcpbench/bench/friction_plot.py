"""Friction figures (issue 39): the forces along the chain, the pull-out force against
pressure, and a load–unload cycle. matplotlib is imported lazily and drawn on a bare
Figure with the Agg canvas (as :mod:`lcpbench.bench.plot`).
"""

from __future__ import annotations

import numpy as np

from .plot import new_figure


def plot_friction_forces(res, path):
    """The normal force N_i and the tangential force T_i of each node of a
    :class:`~lcpbench.model.friction_result.FrictionResult` against its x (mN, mm).

    Top: N_i of each wall. Bottom: T_i between the cone's bounds ±μ N_i (dashed);
    sticking nodes are filled circles, sliding ones crosses. Returns the Figure.
    """
    scene = res.scene
    free = np.arange(1, 1 + np.asarray(res.forces).size)  # nodes 2..N (2..N+1: free end)
    x = np.asarray(res.x, float)[free]
    up = 1e3 * np.asarray(res.forces, float)
    lo = 1e3 * (np.asarray(res.forces_lower, float) if res.forces_lower is not None
                else np.zeros_like(up))
    mu_up, mu_lo = scene.wall_friction
    limit = mu_up * up + mu_lo * lo
    T = 1e3 * np.asarray(res.tangential_forces, float)
    contact = up + lo > 0
    stick = np.asarray(res.stick, bool)
    slide = contact & ~stick

    fig = new_figure((7.0, 5.0))
    ax_n, ax_t = fig.subplots(2, 1, sharex=True)
    ax_n.plot(x, up, "-", color="C0", lw=1.2, label="upper wall")
    if res.forces_lower is not None:
        ax_n.plot(x, lo, "-", color="C2", lw=1.2, label="lower wall")
    ax_n.set_ylabel("normal force N (mN)")
    ax_n.legend(loc="upper right", fontsize=8)
    ax_t.fill_between(x, -limit, limit, color="0.9", label="cone |T| <= μN")
    ax_t.plot(x, limit, "--", color="0.5", lw=0.8)
    ax_t.plot(x, -limit, "--", color="0.5", lw=0.8)
    ax_t.plot(x, T, "-", color="C1", lw=1.0)
    ax_t.plot(x[stick], T[stick], "o", color="C1", ms=4, label="stick")
    ax_t.plot(x[slide], T[slide], "x", color="C3", ms=5, label="slip")
    ax_t.axhline(0.0, color="0.3", lw=0.6)
    ax_t.set_xlabel("x (mm)")
    ax_t.set_ylabel("tangential force T (mN)")
    ax_t.legend(loc="upper right", fontsize=8)
    mu = f"{mu_up:g}" if mu_up == mu_lo or res.forces_lower is None else f"{mu_up:g}/{mu_lo:g}"
    profile = getattr(scene, "wall_profile", None)
    wall = f"h = {scene.height:g} mm" if profile is None else f"wall {profile.name}"
    fig.suptitle(f"θ = {scene.theta:.4g}°, {wall}, μ = {mu}, pull "
                 f"{1e3 * res.pull:.4g} mN, ends {scene.left_end}/{scene.right_end}: "
                 f"ΣN = {1e3 * res.total_force:.4g} mN, ΣT = {float(T.sum()):.4g} mN",
                 fontsize=9)
    fig.savefig(path, dpi=130)
    return fig


def plot_pull_out_pressure(rows: list[dict], path):
    """Pull-out force against input pressure, one line per μ, one panel per height.

    ``rows``: dicts with ``friction``, ``pressure`` (kPa), ``height`` (mm) and
    ``pull_out_force`` (N), as :func:`lcpbench.bench.friction_grid.friction_rows`
    gives them. Returns the Figure.
    """
    heights = sorted({r["height"] for r in rows})
    mus = sorted({r["friction"] for r in rows})
    fig = new_figure((3.2 * max(1, len(heights)) + 1.0, 3.8))
    axes = np.atleast_1d(fig.subplots(1, len(heights), sharey=True))
    for ax, h in zip(axes, heights, strict=True):
        for k, mu in enumerate(mus):
            pts = sorted((r["pressure"], 1e3 * r["pull_out_force"]) for r in rows
                         if r["height"] == h and r["friction"] == mu and r["converged"])
            if pts:
                p, f = zip(*pts, strict=True)
                ax.plot(p, f, "-o", color=f"C{k}", ms=3, label=f"μ = {mu:g}")
        ax.set_title(f"h = {h:g} mm", fontsize=9)
        ax.set_xlabel("input pressure (kPa)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("pull-out force (mN)")
    axes[-1].legend(fontsize=8)
    fig.savefig(path, dpi=130)
    return fig


def plot_load_cycle(cycles: list, path):
    """Contact force (ΣN, mN) against input pressure (kPa) for each
    :class:`~lcpbench.studies.load_cycle.LoadCycle`: loading solid, unloading dashed,
    the frictionless model dotted. Returns the Figure."""
    fig = new_figure((6.0, 4.2))
    ax = fig.add_subplot()
    first = cycles[0]
    up = first.loading
    ax.plot(first.pressure[up], 1e3 * first.frictionless[up], ":", color="0.2", lw=1.5,
            label="μ = 0 (the paper's model)")
    for k, c in enumerate(cycles):
        mu = c.path[0].scene.wall_friction[0]
        p_up, f_up = c.branch(True)
        p_dn, f_dn = c.branch(False)
        ax.plot(p_up, 1e3 * f_up, "-", color=f"C{k}", marker="^", ms=3,
                label=f"μ = {mu:g}, loading")
        ax.plot(p_dn, 1e3 * f_dn, "--", color=f"C{k}", marker="v", ms=3,
                label=f"μ = {mu:g}, unloading")
    sc = first.path[0].scene
    ax.set_title(f"load–unload cycle, h = {sc.height:g} mm"
                 + (" channel" if sc.channel else "") + f", N = {sc.links}", fontsize=9)
    ax.set_xlabel("input pressure (kPa)")
    ax.set_ylabel("contact force ΣN (mN)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=130)
    return fig
