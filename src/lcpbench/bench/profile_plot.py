"""Figures of the performance and data profiles (:mod:`.profiles`).

One figure per kind and measure (``perf-profile-time.png``,
``data-profile-outer.png``, ...), one panel per settings profile. Drawn on a
bare :class:`matplotlib.figure.Figure` with the Agg canvas, as in
:mod:`.plot`; matplotlib is imported only here.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .profiles import MEASURES, Profile


def figure_name(kind: str, measure: str) -> str:
    return f"{'perf' if kind == 'performance' else 'data'}-profile-{measure}.png"


def plot_profiles(profiles: list[Profile], out: str | Path) -> list[str]:
    """Draw every (kind, measure) of ``profiles`` into ``out``; returns the file names."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    out = Path(out)
    names = []
    keys = list(dict.fromkeys((p.kind, p.measure) for p in profiles))
    for kind, measure in keys:
        panels = [p for p in profiles if (p.kind, p.measure) == (kind, measure)]
        rows = max(_legend_lines(p) for p in panels)  # legend rows under a panel
        fig = Figure(figsize=(6.4 * len(panels), 4.4 + 0.19 * rows), layout="constrained")
        FigureCanvasAgg(fig)
        axes = fig.subplots(1, len(panels), squeeze=False)[0]
        for ax, p in zip(axes, panels):
            _panel(ax, p)
        names.append(figure_name(kind, measure))
        fig.savefig(out / names[-1], dpi=110)
    return names


def legend_label(names: list[str], per_line: int = 3) -> str:
    """One legend entry for solvers whose curves are identical.

    One name is itself. Several are "same curve: a, b, c" over lines of
    ``per_line`` names, their common "/settings (driver)" said once at the end.
    """
    if len(names) == 1:
        return names[0]
    parts = [n.partition("/") for n in names]
    tails = {t for _, _, t in parts}
    if len(tails) == 1 and all(sep for _, sep, _ in parts):
        body, suffix = [h for h, _, _ in parts], " /" + tails.pop()
    else:
        body, suffix = list(names), ""
    lines = [", ".join(body[i:i + per_line]) for i in range(0, len(body), per_line)]
    return "same curve: " + ",\n".join(lines) + suffix


def _legend_columns(p: Profile) -> int:
    """3 columns of single names; 2 when an entry names several (they are wider)."""
    return 2 if any(len(g) > 1 for g in p.same_curves()) else 3


def _legend_lines(p: Profile) -> int:
    """Rows the legend under a panel takes (entries in columns, multi-line entries)."""
    heights = [legend_label([p.solvers[i] for i in g]).count("\n") + 1
               for g in p.same_curves()]
    return -(-sum(heights) // _legend_columns(p)) + max(heights, default=1)


def _panel(ax, p: Profile) -> None:
    hi = float(p.x[-1]) * 2.0 if p.x.size else 2.0
    lo = 1.0 if p.kind == "performance" else max(float(p.x[0]) / 2.0, 1e-12)
    from matplotlib import colormaps

    colours = colormaps["tab20"]
    # one line per group of identical curves (drawn once, named once)
    for k, group in enumerate(p.same_curves()):
        s = group[0]
        names = [p.solvers[i] for i in group]
        xs = np.concatenate([[lo], p.x, [hi]])
        ys = np.concatenate([[0.0 if p.kind == "data" else p.values[s, 0]], p.values[s],
                             [p.values[s, -1]]])
        base = all(n.startswith("baseline") for n in names)
        # 20 distinct colours, then the same colours dotted; the baselines dashed grey
        ax.step(xs, ys, where="post", lw=1.4, label=legend_label(names),
                color=("0.2" if names == ["baseline"] else "0.55") if base
                else colours(k % 20),
                ls="--" if base else ("-" if k < 20 else ":"))
    ax.set_xscale("log", base=2 if p.kind == "performance" else 10)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlim(lo, hi)
    unit = MEASURES[p.measure][3]
    if p.kind == "performance":
        ax.set_xlabel(f"τ (ratio to the best, {unit})")
        ax.set_ylabel("ρ(τ): share of problems within τ of the best")
    else:
        per = " / (N + 1)" if p.measure == "inner" else ""
        ax.set_xlabel(f"κ: budget, {unit}{per}")
        ax.set_ylabel("d(κ): share of problems solved")
    title = f"settings {p.group} ({p.problems} scenes; a failure never counts)"
    if p.left_out:  # said on the plot, not only in the report
        title += "\nleft out, no inner count reported: " + ", ".join(p.left_out)
    ax.set_title(title, fontsize=8.5)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6.5, loc="upper center", bbox_to_anchor=(0.5, -0.16),
              ncol=_legend_columns(p), frameon=False)
