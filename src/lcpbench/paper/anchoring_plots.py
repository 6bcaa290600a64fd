"""The figures of the whole-actuator study (:mod:`lcpbench.paper.anchoring`)."""

from __future__ import annotations

import numpy as np

from .data import GF, PAPER
from .plots import new_figure


def plot_force_pressure(rows: list[dict], contact: list[dict], path) -> None:
    """Force on the load cell against pressure, one panel per h.

    Colour: the actuator. Solid: the single-section model; dashed: the whole
    actuator's middle section, weight away from the load cell; dotted: the
    same, weight toward it. Grey: the paper's knee and its ~1 gf forces.
    """
    heights = sorted({r["height"] for r in rows})
    fig = new_figure((15.0, 4.8))
    for k, h in enumerate(heights):
        ax = fig.add_subplot(1, len(heights), k + 1)
        for j, act in enumerate(sorted({r["actuator"] for r in rows})):
            for g, style, what in (("-y", "--", "whole, w away"),
                                   ("+y", ":", "whole, w toward")):
                sel = sorted((r for r in rows if r["height"] == h and r["actuator"] == act
                              and r["gravity"] == g), key=lambda r: r["pressure_kpa"])
                p = [r["pressure_kpa"] for r in sel]
                if g == "-y":
                    ax.plot(p, [1e3 * r["single_force"] for r in sel], "-", color=f"C{j}",
                            lw=1.2, label=f"actuator {act}: single section")
                ax.plot(p, [1e3 * r["middle_force"] for r in sel], style, color=f"C{j}",
                        lw=1.2, label=f"actuator {act}: {what}")
            knees = [c[f"all_touch_kpa_{g}"] for c in contact
                     if c["height"] == h and c["actuator"] == act for g in ("-y",)]
            for x in knees:
                if np.isfinite(x):
                    ax.axvline(x, color=f"C{j}", lw=0.6, alpha=0.5)
        knee = PAPER["fig24"]["knee_kpa"][h]
        ax.axvline(knee, color="0.3", ls="-.", lw=1.0, label=f"paper's knee {knee:g} kPa")
        ax.axhline(1e3 * GF * PAPER["fig24"]["low_force_gf"], color="0.5", lw=0.8, ls="-",
                   alpha=0.6, label="1 gf (paper's low-pressure forces)")
        ax.set_yscale("symlog", linthresh=10.0)
        ax.set_ylim(bottom=0.0)
        ax.set_title(f"({'abc'[k]}) h = {h:g} mm: thin verticals, all 3 sections touch "
                     "(w away)", fontsize=8)
        ax.set_xlabel("pressure P (kPa)")
        ax.set_ylabel("force on the load cell (mN)")
        ax.grid(True, alpha=0.3)
        if k == 0:
            ax.legend(fontsize=6, loc="upper left", ncol=1)
    fig.savefig(path, dpi=120)


def plot_shapes(cases: list[dict], path) -> None:
    """The whole actuator in its channel at a few pressures; the single section dashed
    over the middle section (centred on it), the section boundaries marked."""
    fig = new_figure((10.0, 1.6 * len(cases) + 0.6))
    for k, c in enumerate(cases):
        ax = fig.add_subplot(len(cases), 1, k + 1)
        x, y, h = np.asarray(c["whole_x"]), np.asarray(c["whole_y"]), c["height"]
        ax.axhspan(h, h + 1.5, color="0.8")
        ax.axhspan(-h - 1.5, -h, color="0.8")
        ax.plot(x, y, "-", color="C0", lw=2.0, label="whole actuator (3 sections)")
        (_, b0), (_, b1), _ = c["nodes"]
        ax.plot(x[[0, b0, b1, -1]], y[[0, b0, b1, -1]], "o", color="C0", ms=3)
        xs, ys = np.asarray(c["single_x"]), np.asarray(c["single_y"])
        shift = 0.5 * (x[b0] + x[b1]) - 0.5 * (xs[0] + xs[-1])
        ax.plot(xs + shift, ys, "--", color="C3", lw=1.2, label="paper's single section")
        ax.set_ylim(-h - 1.5, h + 1.5)
        ax.set_aspect("equal")
        ax.text(0.005, 0.9, f"P = {c['pressure']:g} kPa, θ = {c['theta']:.0f}°: middle "
                f"{1e3 * c['whole_force']:.1f} mN, single {1e3 * c['single_force']:.1f} mN",
                transform=ax.transAxes, fontsize=7, va="top")
        ax.set_yticks([-h, 0, h])
        if k == 0:
            ax.set_title(f"actuator {c['actuator']}, h = {h:g} mm (walls at ±h), weight away "
                         "from the upper wall", fontsize=9)
            ax.legend(fontsize=7, loc="lower right")
        if k == len(cases) - 1:
            ax.set_xlabel("x (mm)")
    fig.savefig(path, dpi=120)
