"""``lcpbench sweep --grid friction``: the pull-out force over μ × pressure × h (issue 39).

The grid is :class:`lcpbench.bench.friction_grid.FrictionGrid` (default
:data:`~lcpbench.bench.friction_grid.FRICTION_GRID`); ``--friction``, ``--pressure``,
``--height`` and ``--links`` change its lists. The points go into the
store's ``pull_outs`` table as they are done, under the store's sweep lock: a killed
sweep resumes where it stopped. The report (beside the store, or ``--out``) is the
table as CSV and the figure of the pull-out force against pressure, one line per μ.
"""

from __future__ import annotations

import sys

from ..bench.sweep import DEFAULT_TIME_LIMIT
from ..errors import ProblemError
from ._common import error_line, has_matplotlib
from ._scene_args import DEFAULT_METHOD

#: options of ``sweep`` that are for the back-end grids, with their defaults
_NOT_FOR_FRICTION = {"theta": None, "EI": None, "weight": None, "length": None,
                     "wall_stiffness": None, "sections_count": None, "solvers": None,
                     "settings": None, "continuation": None, "baseline": None,
                     "formulation": None, "standard": False, "dask": None, "repeat": None,
                     "channel": False, "jobs": None, "oversubscribe": False, "all": False,
                     "time_limit": DEFAULT_TIME_LIMIT, "method": DEFAULT_METHOD}


def _advance(bar):
    """The progress callback: one step per point, the last point computed shown."""
    def update(row):
        if row is not None:
            bar.set_postfix_str(f"mu {row['friction']:g}, {row['pressure']:g} kPa, h "
                                f"{row['height']:g} mm: {1e3 * (row['pull_out_force'] or 0):.4g}"
                                f" mN", refresh=False)
        bar.update(1)
    return update


def friction_grid_from(args):
    """The :class:`FrictionGrid` of the command line, every scene checked."""
    from ..bench.friction_grid import FrictionGrid
    from ..bench.grid import parse_range
    from ._sweep_scenes import in_model_units

    given = [f"--{k.replace('_', '-')}" for k, default in _NOT_FOR_FRICTION.items()
             if getattr(args, k, default) != default]
    if given:
        raise ProblemError(f"--grid friction runs lcpbench.pull_out over --friction x "
                           f"--pressure x --height (actuator 1's calibration, the paper's "
                           f"channel); it takes no {', '.join(given)}")
    kw = {}
    if args.friction is not None:
        kw["friction"] = parse_range(args.friction, "friction")
    if args.pressure is not None:
        kw["pressure"] = parse_range(args.pressure, "pressure")
    if args.height is not None:
        kw["height"] = parse_range(in_model_units(args.height, "height"), "height")
    if args.links is not None:
        links = parse_range(args.links, "links", integer=True)
        if len(links) != 1:
            raise ProblemError(f"--grid friction takes one --links, got {args.links!r}")
        kw["links"] = int(links[0])
    grid = FrictionGrid(**kw)
    grid.points()  # every scene built and checked before anything runs
    return grid


def sweep_friction(args) -> int:
    """Run the friction grid into the store; write its CSV and figure. 0 when every
    point converged, 1 when some did not (they are in the CSV with their reason)."""
    from ..bench.friction_grid import friction_rows, run_friction_grid
    from ..bench.report import default_out
    from ..bench.store import Store

    grid = friction_grid_from(args)
    tol = 1e-10 if args.tol is None else args.tol
    with Store(args.store) as store, store.lock("lcpbench sweep --grid friction",
                                                wait=args.wait):
        print(f"the friction grid: {len(grid.friction)} mu x {len(grid.pressure)} pressures "
              f"x {len(grid.height)} heights = {len(grid)} pull-outs (actuator "
              f"{grid.actuator}, channel, N = {grid.links}) into {args.store}",
              file=sys.stderr)
        bar = None
        if not args.quiet:
            from tqdm import tqdm

            bar = tqdm(total=len(grid), unit="pull-out", file=sys.stderr, smoothing=0,
                       dynamic_ncols=True, desc="pull-outs")
        try:
            done, there = run_friction_grid(store, grid, rerun=args.rerun, tol=tol,
                                            progress=_advance(bar) if bar else None)
        except KeyboardInterrupt:
            if bar:
                bar.close()
            error_line(f"interrupted: the pull-outs done are safe in {args.store}; run the "
                       "same command again to resume")
            return 130
        if bar:
            bar.close()
        rows = friction_rows(store, grid, tol)
    print(f"{done} pull-outs computed, {there} already in {args.store}")
    bad = [r for r in rows if not r["converged"]]
    if not args.no_report:
        out = default_out(args.store) if args.out is None else args.out
        write_friction_report(rows, out)
    return 1 if bad else 0


#: the CSV's header, units in the names
HEADER = ("friction", "pressure_kpa", "height_mm", "theta_deg", "links", "pull_out_force_n",
          "normal_force_total_n", "capacity_n", "held_pull_n", "solves", "converged", "reason")


def write_friction_report(rows: list[dict], out) -> None:
    """``pull-out.csv`` and (with matplotlib) ``pull-out-pressure.png`` in ``out``."""
    import csv
    from pathlib import Path

    folder = Path(out)
    cols = ("friction", "pressure", "height", "theta", "links", "pull_out_force",
            "normal_force_total", "capacity", "held_pull", "solves", "converged", "reason")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with open(folder / "pull-out.csv", "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(HEADER)
            for r in rows:
                w.writerow([r[c] for c in cols])
        if has_matplotlib():
            from ..bench.friction_plot import plot_pull_out_pressure

            plot_pull_out_pressure(rows, folder / "pull-out-pressure.png")
    except OSError as exc:
        raise ProblemError(f"out {folder}: cannot write the report there ({exc})") from exc
    print(f"report of {len(rows)} pull-outs in {folder}/pull-out.csv"
          + (" and pull-out-pressure.png" if has_matplotlib() else ""))
