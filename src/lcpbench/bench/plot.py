"""Figures. matplotlib is optional (``pip install 'lcpbench[plot]'``) and imported lazily.

The figures are drawn on a bare :class:`matplotlib.figure.Figure` with the Agg
canvas, so nothing here touches pyplot or the global backend.
"""

from __future__ import annotations

import numpy as np

from .grid import scene_params


def plot_shape(result, path):
    """Draw a :class:`~lcpbench.model.result.ContactResult` to ``path`` (PNG, PDF, SVG, ...).

    The constrained shape over the unconstrained one, the wall(s) as horizontal
    lines (at +h, and −h for a channel) and the reactions as arrows from the
    wall at the contact nodes, the largest about h/2 long; the total force in
    mN is in the title. Axes in mm, equal aspect, in a figure of the data's
    aspect ratio (no white bands beside the axes). Returns the Figure.
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

    # Reactions: one arrow per group of neighbouring contact nodes (at N = 140 two
    # touching nodes are 0.2 mm apart and their arrows would merge), from the wall
    # into the body, length to scale (the scale bar), labelled with its force and
    # node count; a tick on the wall marks every contact node.
    free = chain.free_nodes
    sets = [(np.asarray(result.forces, float), h, -1.0)]
    if channel and result.forces_lower is not None:
        sets.append((np.asarray(result.forces_lower, float), -h, 1.0))
    groups = [(g, yw, sign) for f, yw, sign in sets
              for g in reaction_groups(f, x[free])]
    fmax = max((g["force"] for g, _, _ in groups), default=0.0)
    bar_top = -np.inf
    labels: list[tuple[float, float, int]] = []  # (arrow tip y, direction, text lines)
    if fmax > 0:
        unit = _nice(fmax)  # the scale bar's force (N)
        scale = 0.5 * max(h, 1.0) / unit  # mm of arrow per N
        gx = sorted(g["x"] for g, _, _ in groups)
        crowded = any(b - a < 0.15 * (hi - lo) for a, b in zip(gx, gx[1:]))
        for k, (g, yw, sign) in enumerate(groups):
            # neighbouring labels go left and right of their arrows, not over each other
            ha = ("right" if k % 2 == 0 else "left") if crowded else "center"
            ax.annotate("", xy=(g["x"], yw + sign * scale * g["force"]), xytext=(g["x"], yw),
                        arrowprops={"arrowstyle": "-|>", "color": "C3", "lw": 1.5}, zorder=4)
            ax.plot(g["nodes_x"], np.full(len(g["nodes_x"]), yw), "|", color="C3", ms=6,
                    zorder=5, label="contact node" if k == 0 else None)
            n = len(g["nodes_x"])
            labels.append((yw + sign * scale * g["force"], sign, 2 if n > 1 else 1))
            ax.annotate(f"{1e3 * g['force']:.4g} mN" + (f"\n({n} nodes)" if n > 1 else ""),
                        (g["x"], yw + sign * scale * g["force"]), fontsize=7, color="C3",
                        ha=ha, va="top" if sign < 0 else "bottom",
                        xytext=(0, -3 * sign if sign > 0 else -3), textcoords="offset points")
        # the scale bar, top left
        bx, by = lo + 0.02 * (hi - lo), max(float(np.max(y0)), h) + 0.05 * max(h, 1.0)
        ax.annotate("", xy=(bx, by), xytext=(bx, by + scale * unit),
                    arrowprops={"arrowstyle": "-|>", "color": "C3", "lw": 1.5})
        bar_top = by + scale * unit
        ax.text(bx + 0.01 * (hi - lo), by + 0.5 * scale * unit,
                f"scale: {1e3 * unit:g} mN", fontsize=7, color="C3", va="center")

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
    ymax = max(float(np.max(y)), float(np.max(y0)), h, bar_top)
    ypad = 0.1 * (ymax - ymin) if ymax > ymin else 1.0
    ymin, ymax = ymin - ypad, ymax + ypad
    # room for the force labels beyond the arrow tips (7-pt lines, ~0.13 in each)
    mm_per_in = ((hi - lo) + 2 * pad) / 6.0
    for tip, sign, lines in labels:
        if sign < 0:
            ymin = min(ymin, tip - (0.13 * lines + 0.08) * mm_per_in)
        else:
            ymax = max(ymax, tip + (0.13 * lines + 0.08) * mm_per_in)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.legend(loc="best", fontsize=8)
    # The figure takes the data's aspect ratio: with equal axes in a fixed 7 x 4 in
    # figure, a tall scene (a channel, large h) left white bands beside the axes.
    fig.set_size_inches(*_equal_aspect_size((hi - lo) + 2 * pad, ymax - ymin))
    fig.savefig(path, dpi=150)
    return fig


def _equal_aspect_size(width: float, height: float, *, axes_width: float = 6.0,
                       max_axes_height: float = 6.5) -> tuple[float, float]:
    """Figure size (in) whose axes box fits data ``width`` x ``height`` at equal aspect.

    The axes are ``axes_width`` wide (narrower when the height would exceed
    ``max_axes_height``), plus room for the labels (0.9 in) and the title (0.8 in).
    """
    ratio = height / width if width > 0 else 1.0
    aw = axes_width
    ah = aw * ratio
    if ah > max_axes_height:
        ah, aw = max_axes_height, max_axes_height / ratio
    return aw + 0.9, max(ah, 1.0) + 0.8


def reaction_groups(forces, node_x, rel: float = 1e-9) -> list[dict]:
    """Contact nodes grouped into runs of neighbours (consecutive free nodes).

    Each group: ``force`` (the sum, N), ``x`` (the force-weighted position,
    mm), ``nodes`` (free-node indices) and ``nodes_x``. A node is in contact
    when its reaction is above ``rel`` times the largest.
    """
    f = np.asarray(forces, float)
    fmax = float(f.max(initial=0.0))
    if fmax <= 0:
        return []
    idx = np.flatnonzero(f > rel * fmax)
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
    xs = np.asarray(node_x, float)
    return [{"force": float(f[r].sum()), "x": float(np.average(xs[r], weights=f[r])),
             "nodes": r.tolist(), "nodes_x": xs[r].tolist()} for r in runs if r.size]


def _nice(value: float) -> float:
    """A round number (1, 2 or 5 × 10^k) near half of ``value``: a scale bar's length."""
    import math

    target = 0.5 * value
    k = math.floor(math.log10(target))
    return min((m * 10.0 ** k for m in (1, 2, 5, 10)), key=lambda v: abs(v - target))


def new_figure(size=(7.0, 4.5)):
    """A matplotlib Figure on the Agg canvas (no pyplot state), ``size`` in inches."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


#: the marker of each settings profile in the work-precision figure
SETTINGS_MARKERS = {"default": "o", "low": "v", "mid": "D", "high": "s", "-": "P"}
#: where an exact (zero) median error is drawn; the axis labels it "0"
ERROR_FLOOR = 1e-16
_DRIVERS = ("globalised", "hybr", "lm")


def work_precision_points(summary: list[dict], evaluated, *,
                          time_limit: float | None = None) -> dict[str, list[dict]]:
    """The points of the work-precision figure, per back-end, settings in order.

    A point is one (back-end, settings) over every scene of the report, the
    globalised driver (and the baselines' own), scored by the report's rule:
    ``error`` is the median force error with every unsuccessful run counted
    as an infinite error, so it is ``inf`` (drawn apart, as failed) when half
    the runs or more failed; ``time`` is the shifted geometric mean of the
    wall time over every scene (ms; shift 1 ms, an unsuccessful run charged
    at ``time_limit``, the sweep's 60 s by default:
    :func:`~.metrics.charged_sgm`); ``success`` the fraction of successful runs.
    """
    import math

    from .jobs import DEFAULT_TIME_LIMIT
    from .metrics import TIME_SHIFT_MS, charged_sgm

    limit = DEFAULT_TIME_LIMIT if time_limit is None else time_limit
    order = {"default": 0, "low": 1, "mid": 2, "high": 3}
    groups: dict[tuple, list] = {}
    for e in evaluated:
        if e.row["method"] in _DRIVERS:
            groups.setdefault((e.backend, e.settings), []).append(e)
    success = {(r["backend"], r["settings"]): r["success"] for r in summary
               if r["method"] in _DRIVERS}
    out: dict[str, list[dict]] = {}
    for (backend, settings), es in groups.items():
        errors = sorted(e.error if e.success and math.isfinite(e.error) else math.inf
                        for e in es)
        n = len(errors)
        median = errors[n // 2] if n % 2 else 0.5 * (errors[n // 2 - 1] + errors[n // 2])
        ok = [e.success for e in es]
        out.setdefault(backend, []).append({
            "settings": settings, "error": median, "runs": n,
            "time": charged_sgm([1e3 * e.row["wall_time"] for e in es], ok, 1e3 * limit,
                                TIME_SHIFT_MS),
            "success": success.get((backend, settings), sum(ok) / n)})
    for pts in out.values():
        pts.sort(key=lambda p: order.get(p["settings"], 9))
    return out


#: points closer than this on both log axes (a factor 10^0.01, 2.3 %) cannot be told apart
SAME_POINT_DECADES = 0.01


def indistinguishable(pts_by: dict[str, list[dict]]) -> list[list[str]]:
    """Back-ends whose work-precision lines cannot be told apart, grouped.

    Two lines are the same when they have the same settings in the same
    order and each pair of points is within :data:`SAME_POINT_DECADES` on
    both log axes, failed (infinite error) at the same points, and equal in
    success. Groups in name order; a back-end alone is a group of one.
    """
    import math

    def close(a: float, b: float) -> bool:
        if not (math.isfinite(a) and math.isfinite(b)):
            return a == b
        if a <= 0 or b <= 0:
            return a == b
        return abs(math.log10(a) - math.log10(b)) <= SAME_POINT_DECADES

    def same(p: list[dict], q: list[dict]) -> bool:
        return len(p) == len(q) and all(
            a["settings"] == b["settings"] and a["success"] == b["success"]
            and close(a["error"], b["error"]) and close(a["time"], b["time"])
            for a, b in zip(p, q))

    groups: list[list[str]] = []
    for name in sorted(pts_by):
        for g in groups:
            if same(pts_by[g[0]], pts_by[name]):
                g.append(name)
                break
        else:
            groups.append([name])
    return groups


def plot_work_precision(summary: list[dict], evaluated, path, *,
                        time_limit: float | None = None) -> None:
    """Time against achieved error, one line per back-end across its settings.

    x: the median force error over every scene, failures counted as infinite
    (:func:`work_precision_points`); a back-end that failed on half the scenes
    or more has no median error and is drawn in the "failed" column at the
    right, never at a made-up error. y: the time score of the report, over
    every scene with failures charged at the time limit. Marker shape: the
    settings profile; filled: every run a success. Back-ends whose lines
    cannot be told apart (:func:`indistinguishable`) are drawn once and named
    together. Names are in the legend (a table), not on the plot.
    """
    import math

    from matplotlib.lines import Line2D

    from .metrics import TIME_SHIFT_MS

    pts_by = work_precision_points(summary, evaluated, time_limit=time_limit)
    groups = indistinguishable(pts_by)
    fig = new_figure((10.0, 6.0))
    ax = fig.add_subplot()
    finite = [p["error"] for ps in pts_by.values() for p in ps
              if math.isfinite(p["error"]) and p["error"] > 0]
    x_fail = 10 ** (math.ceil(math.log10(max(finite))) + 1.5) if finite else 1.0
    x_floor = ERROR_FLOOR
    cmap = _cmap(len(groups))
    handles = []
    for k, names in enumerate(groups):
        pts = pts_by[names[0]]
        color = cmap(k)
        style = "-" if k < 20 else "--"
        xs = [x_fail if not math.isfinite(p["error"]) else max(p["error"], x_floor)
              for p in pts]
        ys = [p["time"] for p in pts]
        ax.plot(xs, ys, style, color=color, lw=1.0, alpha=0.7)
        for x, y, p in zip(xs, ys, pts):
            full = p["success"] == 1.0
            ax.plot([x], [y], SETTINGS_MARKERS.get(p["settings"], "*"), color=color, ms=7,
                    mfc=color if full else "white", mew=1.3)
        rate = ", ".join(f"{p['settings']} {100 * p['success']:.0f} %" for p in pts)
        label = names[0] if len(names) == 1 else "same points: " + ",\n".join(
            ", ".join(names[i:i + 3]) for i in range(0, len(names), 3))
        handles.append(Line2D([], [], color=color, ls=style, label=f"{label} ({rate})"))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axvspan(x_fail / 10 ** 0.75, x_fail * 10 ** 0.75, color="0.9", zorder=0)
    ax.set_xlim(x_floor / 10, x_fail * 10 ** 0.75)
    ticks = [t for t in ax.get_xticks() if x_floor <= t < x_fail / 10 ** 0.75]
    ax.set_xticks([*ticks, x_fail])
    ax.set_xticklabels([("0 (exact)" if t == x_floor else f"1e{round(math.log10(t))}")
                        for t in ticks] + ["failed\n(≥ half\nthe runs)"], fontsize=8)
    ax.set_xlabel("median total-force error |F − F_ref| / max(F_ref, EI/ℓ²) over every "
                  "scene (an unsuccessful run counts as infinite)")
    ax.set_ylabel(f"time sgm over every scene (ms; shift {TIME_SHIFT_MS:g} ms,\n"
                  "an unsuccessful run charged at the time limit)")
    ax.set_title("Work-precision: one line per back-end, from its default to its high "
                 "settings", fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    keys = [Line2D([], [], ls="", marker=m, color="0.3", mfc="0.3",
                   label=f"settings {s}" if s != "-" else "baseline (no settings)")
            for s, m in SETTINGS_MARKERS.items()
            if any(p["settings"] == s for ps in pts_by.values() for p in ps)]
    keys += [Line2D([], [], ls="", marker="o", color="0.3", mfc="0.3",
                    label="filled: every run a success"),
             Line2D([], [], ls="", marker="o", color="0.3", mfc="white",
                    label="open: some runs unsuccessful")]
    first = ax.legend(handles=keys, fontsize=7, loc="upper left", title="markers",
                      title_fontsize=7)
    ax.add_artist(first)
    fig.legend(handles=handles, fontsize=7, loc="outside right upper",
               title="back-end (success per settings)", title_fontsize=7)
    fig.savefig(path, dpi=130)


def _cmap(n: int):
    """Distinct colours for ``n`` lines (tab10 up to 10, tab20 beyond)."""
    from matplotlib import colormaps

    cmap = colormaps["tab10" if n <= 10 else "tab20"]
    return lambda k: cmap(k % cmap.N)


#: the scene parameters of a line of the force figure, with their units
_PARAMS = (("height", "h", "mm"), ("links", "N", ""), ("length", "ℓ", "mm"),
           ("EI", "EI", "N·mm²"), ("weight", "w", "N/mm"), ("channel", "channel", ""),
           ("wall_stiffness", "k", "N/mm²"))


def _param_text(name: str, value, digits: int = 6) -> str:
    for key, sym, unit in _PARAMS:
        if key == name:
            if key == "channel":
                return "channel" if value else "one wall"
            return f"{sym} = {value:.{digits}g}" + (f" {unit}" if unit else "")
    return f"{name} = {value}"


def _digits(values) -> int:
    """Significant digits that print distinct ``values`` distinctly (6 at least)."""
    values = {v for v in values if isinstance(v, float)}
    for d in range(6, 18):
        if len({f"{v:.{d}g}" for v in values}) == len(values):
            return d
    return 17


def force_lines(refs: dict) -> tuple[list[dict], dict]:
    """The lines of the force-against-θ figure: scenes equal in everything but θ.

    Returns the lines (each ``params``, ``thetas``, ``forces`` in mN, θ
    ascending, and a ``label`` naming the parameters that differ between
    lines, with units) and the parameters common to every line (for the
    title). Scenes that differ in anything but θ are never joined.
    """
    import json

    groups: dict[str, dict] = {}
    for r in refs.values():
        if not r["converged"]:
            continue
        params = scene_params(r["scene"])
        theta = params.pop("theta")
        key = json.dumps(params, sort_keys=True)
        g = groups.setdefault(key, {"params": params, "pts": []})
        g["pts"].append((theta, 1e3 * r["total_force"]))
    names = [k for k, _, _ in _PARAMS]
    varying = [n for n in names if len({json.dumps(g["params"].get(n)) for g in
                                        groups.values()}) > 1]
    common = {n: v for n, v in (next(iter(groups.values()))["params"].items()
                                if groups else []) if n not in varying}
    digits = {n: _digits(g["params"].get(n) for g in groups.values()) for n in varying}
    lines = []
    for g in sorted(groups.values(),
                    key=lambda g: [g["params"].get(n, float("inf")) for n in names]):
        pts = sorted(g["pts"])
        lines.append({"params": g["params"], "thetas": [p[0] for p in pts],
                      "forces": [p[1] for p in pts],
                      # a rigid wall's key has no wall_stiffness (bench/grid.scene_key)
                      "label": ", ".join(_param_text(n, g["params"].get(n, float("inf")),
                                                     digits[n])
                                         for n in varying)
                      or "reference"})
    return lines, common


def plot_forces(refs: dict, evaluated, path) -> None:
    """Total force against θ, one line per set of scenes equal in all but θ.

    The line's label names what differs between lines (with units), the title
    what they share; a scene alone on its line is a marker without a line.
    The root-finding baseline's valid answers are crosses on their scene.
    """
    import json

    lines, common = force_lines(refs)
    fig = new_figure((12.0, 5.0) if len(lines) > 6 else (9.0, 5.0))
    ax = fig.add_subplot()
    base: dict[str, list] = {}
    for e in evaluated:
        if e.backend == "baseline" and e.row["converged"]:
            params = scene_params(e.row["scene"])
            params.pop("theta")
            base.setdefault(json.dumps(params, sort_keys=True), []).append(
                (e.row["theta"], 1e3 * e.row["total_force"]))
    cmap = _cmap(len(lines))
    for k, line in enumerate(lines):
        style = "-o" if len(line["thetas"]) > 1 else "o"
        ax.plot(line["thetas"], line["forces"], style, ms=4, color=cmap(k),
                label=line["label"])
        b = base.get(json.dumps(line["params"], sort_keys=True))
        if b:
            b = sorted(b)
            ax.plot([p[0] for p in b], [p[1] for p in b], "x", ms=7, color=cmap(k))
    if base:
        ax.plot([], [], "x", color="0.3", label="root-finding baseline (valid answers)")
    ax.set_xlabel("bend angle θ (degrees)")
    ax.set_ylabel("total contact force (mN)")
    shared = ", ".join(_param_text(n, v) for n, v in common.items())
    ax.set_title(f"Reference solves{': ' + shared if shared else ''}", fontsize=9)
    ax.grid(True, alpha=0.3)
    fig.legend(fontsize=7, loc="outside right upper")
    fig.savefig(path, dpi=130)


def shape_panels(refs: dict, theta: float | None = None, height: float | None = None
                 ) -> tuple[dict, list[tuple[str, list[dict], list[str]]]]:
    """The two panels of the shapes figure: against h at one θ, against θ at one h.

    Only scenes equal in every other parameter are used (those of the most
    common N, ℓ, EI, w and walls, returned as the first item, for the
    title); each panel is (title, reference rows, legend labels with units).
    """
    import json
    from collections import Counter

    rows = [r for r in refs.values() if r["converged"] and r["y"] is not None]
    if not rows:
        return {}, []

    def rest(r):
        p = scene_params(r["scene"])
        return json.dumps({k: v for k, v in p.items() if k not in ("theta", "height")},
                          sort_keys=True)
    common = Counter(rest(r) for r in rows).most_common(1)[0][0]
    rows = [r for r in rows if rest(r) == common]
    thetas = sorted({r["theta"] for r in rows})
    heights = sorted({r["height"] for r in rows})
    theta = theta if theta is not None else min(thetas, key=lambda t: abs(t - 150.0))
    height = height if height is not None else heights[0]
    left = sorted((r for r in rows if r["theta"] == theta), key=lambda r: r["height"])
    right = sorted((r for r in rows if r["height"] == height), key=lambda r: r["theta"])
    if len(right) > 9:  # keep the figure readable
        right = right[:: max(1, len(right) // 9)]
    return json.loads(common), [
        (f"θ = {theta:g}°, against the wall height h", left,
         [f"h = {r['height']:g} mm" for r in left]),
        (f"h = {height:g} mm, against the bend angle θ", right,
         [f"θ = {r['theta']:g}°" for r in right]),
    ]


def plot_shapes(refs: dict, path, theta: float | None = None, height: float | None = None
                ) -> None:
    """Constrained shapes: against h at one θ (left), against θ at one h (right).

    Panels from :func:`shape_panels`; the y-axis spans the curves and walls
    drawn, stretched (the shapes are flat: a few mm over 30 mm), legends carry units.
    """
    shared, panels = shape_panels(refs, theta, height)
    if not panels:
        return
    fig = new_figure((12.0, 4.2))
    fig.suptitle(", ".join(_param_text(k, shared[k]) for k, _, _ in _PARAMS if k in shared
                           and k != "height"), fontsize=9)
    for k, (title, sel, labels) in enumerate(panels):
        ax = fig.add_subplot(1, 2, k + 1)
        for j, (r, label) in enumerate(zip(sel, labels)):
            ax.plot(r["x"], r["y"], "-", lw=1.2, color=f"C{j % 10}", label=label)
            if k == 0:
                ax.axhline(r["height"], color=f"C{j % 10}", lw=0.6, ls=":")
        if k == 1 and sel:
            ax.axhline(sel[0]["height"], color="0.25", lw=1.2, label="wall")
        if sel:
            ys = np.concatenate([np.asarray(r["y"], float) for r in sel] + [[0.0]])
            top = max(float(ys.max()), max(r["height"] for r in sel))
            bottom = min(float(ys.min()), 0.0)
            pad = 0.08 * (top - bottom) if top > bottom else 1.0
            ax.set_ylim(bottom - pad, top + pad)
        ax.set_title(title + (" (dotted: each wall)" if k == 0 else ""), fontsize=9)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm, stretched: not to the scale of x)")
        ax.legend(fontsize=6, ncol=2, loc="lower center")
    fig.savefig(path, dpi=130)
