"""The report's tissue figures: force and contact pressure against input pressure,
one line per wall stiffness (issue 17, elastic walls).

Built from the store's reference solves only (like every report figure). The
input pressure is recovered from θ by the paper's calibration of actuator 1
(eq. 40, :mod:`lcpbench.problems.calibrations`), the one ``--grid tissue``
used; the contact pressure per length of a node is its reaction over its
share of wall length, R / a (:func:`lcpbench.model.elastic.wall_pressure`).
At a rigid wall that is the point force smeared over one link, which grows
with N at the edges of a contact: the figure says so.
"""

from __future__ import annotations

import json
import math

import numpy as np

from ..problems.calibrations import get_calibration


def tissue_lines(refs: dict) -> dict[float, dict[float, list[tuple[float, float, float]]]]:
    """{height: {k: [(input pressure kPa, total force mN, max pressure N/mm), ...]}}.

    Only scenes of a grid with elastic walls (some scene of the same height has a
    finite ``wall_stiffness``) and converged references; rigid scenes of those
    heights join as k = inf.
    """
    cal = get_calibration(1)
    out: dict[float, dict[float, list]] = {}
    for r in refs.values():
        if not r["converged"]:
            continue
        p = json.loads(r["scene"])
        k = float(p.get("wall_stiffness", math.inf))
        a = p["length"] / p["links"]
        forces = r.get("forces")
        peak = float(np.max(forces, initial=0.0)) / a if forces is not None else math.nan
        P = (p["theta"] - cal.intercept) / cal.slope
        out.setdefault(p["height"], {}).setdefault(k, []).append(
            (P, 1e3 * float(r["total_force"]), peak))
    elastic = {h for h, by_k in out.items() if any(math.isfinite(k) for k in by_k)}
    return {h: {k: sorted(v) for k, v in sorted(out[h].items())} for h in sorted(elastic)}


def tissue_table(refs: dict) -> str:
    """A markdown table: per height and k, the largest force and contact pressure."""
    lines = tissue_lines(refs)
    if not lines:
        return ""
    rows = ["| h (mm) | wall k (N/mm per mm) | max force (mN) | max contact pressure "
            "(N/mm) | at input pressure (kPa) |", "|---|---|---|---|---|"]
    for h, by_k in lines.items():
        for k, pts in by_k.items():
            P, F, peak = max(pts, key=lambda t: t[2])
            rows.append(f"| {h:g} | {'rigid' if math.isinf(k) else f'{k:g}'} | "
                        f"{max(t[1] for t in pts):.4g} | {peak:.4g} | {P:.4g} |")
    return "\n".join(rows) + "\n"


def plot_tissue(refs: dict, path) -> bool:
    """Draw the figure into ``path``; False (nothing written) without elastic scenes."""
    lines = tissue_lines(refs)
    if not lines:
        return False
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(lines), 2, figsize=(10.0, 3.0 * len(lines)), squeeze=False,
                             constrained_layout=True)
    ks = sorted({k for by_k in lines.values() for k in by_k})
    cmap = plt.get_cmap("viridis", max(len(ks), 2))
    for row, (h, by_k) in zip(axes, lines.items()):
        for k, pts in by_k.items():
            c = "k" if math.isinf(k) else cmap(ks.index(k))
            label = "rigid wall (pressure R/a)" if math.isinf(k) else f"k = {k:g} N/mm²"
            P = [t[0] for t in pts]
            row[0].plot(P, [t[1] for t in pts], "-o", ms=3, color=c, label=label)
            row[1].plot(P, [t[2] for t in pts], "-o", ms=3, color=c, label=label)
        row[0].set_ylabel(f"h = {h:g} mm\ntotal force (mN)")
        row[1].set_ylabel("max contact pressure (N/mm)")
        for ax in row:
            ax.grid(True, alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("input pressure (kPa, θ by actuator 1's calibration, eq. 40)")
    axes[0][1].legend(fontsize=7)
    axes[0][0].set_title("force on the walls", fontsize=9)
    axes[0][1].set_title("contact pressure per length (a rigid wall's grows with N)",
                         fontsize=9)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True
