"""``lcpbench anchor``: how hard can you pull before the actuator slips (issue 39)?

::

    lcpbench anchor --pressure KPA | --theta DEG --height MM --friction MU [--channel]
                    [--wall-stiffness K] [--sections anchoring] [--json] [--plot F.png]
                    [--wall-profile F.csv [--lower-profile F.csv] [--profile-kind K]]

Both ends are sliders (held in y, free along x) and the pull acts on the right end;
:func:`lcpbench.pull_out` follows the pull up to gross slip. The output gives the
pull-out force P* (N), ΣN over every wall at pull-out (N; at the last state held, whose
pull ``held_pull`` is just below P*), the capacity Σ μ N there (against a wall of any
profile, Σ N (μ t_x − n_x): the pull that gross slip balances), the
nodes that pass from stick to slip and the number of frictional solves. Exit status 0
when the pull-out force was found, 1 when not (with the reason), 2 on bad input.
"""

from __future__ import annotations

import numpy as np

from ..model.friction_result import scene_fields
from ._common import add_json_option, error_line, format_rows, has_matplotlib, print_json
from ._friction_args import mu_arg, refuse_auto_links
from ._scene_args import (
    add_profile_options,
    add_scene_options,
    add_section_options,
    add_wall_stiffness_option,
    scene_from,
)


def register(subparsers) -> None:
    """Add ``anchor`` to the command line."""
    a = subparsers.add_parser(
        "anchor", help="the pull-out force: the largest axial pull wall friction holds",
        description="The largest axial pull (N) the actuator holds by wall friction: both "
                    "ends sliders (free along x), the pull on the right end, followed up to "
                    "gross slip (lcpbench.pull_out, docs/friction.md). Prints the pull-out "
                    "force, the total normal force over every wall at pull-out and the "
                    "number of frictional solves.")
    add_scene_options(a)
    add_section_options(a)
    add_profile_options(a)
    add_wall_stiffness_option(a)
    a.add_argument("--friction", type=mu_arg, required=True, metavar="MU",
                   help="Coulomb coefficient of the walls, > 0: one number, or "
                        "MU_UPPER,MU_LOWER with --channel")
    a.add_argument("--tol", type=float, default=1e-10, metavar="RAD",
                   help="convergence threshold of each frictional state, rad (default 1e-10)")
    add_json_option(a)
    a.add_argument("--plot", metavar="FILE.png",
                   help="draw the normal and tangential forces along the chain at pull-out, "
                        "stick and slip marked (needs matplotlib)")
    a.set_defaults(func=cmd_anchor)


def cmd_anchor(args) -> int:
    """``lcpbench anchor``: 0 pull-out found, 1 not, 2 bad input or plot error."""
    from ..studies.pull_out import pull_out

    if args.plot is not None and not has_matplotlib():
        error_line("--plot needs matplotlib: pip install 'lcpbench[plot]'")
        return 2
    refuse_auto_links(args, always=True)
    args.left_end, args.right_end, args.pull = "slider", "slider", None
    scene = scene_from(args)
    po = pull_out(scene, tol=args.tol)  # (refuses what it cannot take, in one line)
    plot_error = None
    if args.plot is not None:
        if not po.path:
            plot_error = f"--plot {args.plot}: no state held to draw ({po.reason})"
        else:
            from ..bench.friction_plot import plot_friction_forces

            try:
                plot_friction_forces(po.path[-1], args.plot)
            except (OSError, ValueError) as exc:
                plot_error = f"--plot {args.plot}: {exc}"
    if args.json:
        print_json(anchor_json(po, scene, args.pressure))
    else:
        print(summary(po, scene, args.pressure, None if plot_error else args.plot))
    if plot_error is not None:
        error_line(plot_error)
        return 2
    return 0 if po.converged else 1


def _events(po) -> list[dict]:
    """Stick-to-slip events with 1-based node numbers (the free nodes are 2..N)."""
    return [{"node": int(j) + 2, "pull": float(P)} for j, P in po.events]


def anchor_json(po, scene, pressure) -> dict:
    """The JSON answer (N, mm, kPa)."""
    return {
        "pull_out_force": po.force, "normal_force_total": po.normal_force_total,
        "capacity": po.capacity, "held_pull": po.path[-1].pull if po.path else None,
        "solves": po.solves, "converged": po.converged,
        "reason": po.reason, "pressure": pressure,
        "normal_forces": po.normal_forces, "tangential_forces": po.tangential_forces,
        "stick_to_slip": _events(po),
        "units": {"pull_out_force": "N", "normal_force_total": "N", "capacity": "N",
                  "held_pull": "N", "normal_forces": "N", "tangential_forces": "N", "pressure": "kPa",
                  "stick_to_slip.pull": "N"},
        "scene": scene_fields(scene),
    }


def summary(po, scene, pressure, plot) -> str:
    """Aligned lines: the scene, P*, ΣN, Σ μN, events, solves, verdict."""
    mu = scene.friction if np.ndim(scene.friction) == 0 else ",".join(
        f"{m:g}" for m in scene.friction)
    made = f" (from {pressure:g} kPa)" if pressure is not None else ""
    events = ", ".join(f"{e['node']} at {1e3 * e['pull']:.4g} mN" for e in _events(po))
    held = f"{1e3 * po.path[-1].pull:.6g} mN" if po.path else "none"
    rows = [
        ("scene", f"theta={scene.theta:.6g} deg{made}, " + (
                  f"h={scene.height:g} mm, " if getattr(scene, "wall_profile", None) is None
                  else f"wall profile {scene.wall_profile.name}, ") +
                  f"N={scene.links}, mu={mu}" + (", channel" if scene.channel else "")
         + (f", wall k={scene.wall_stiffness:g} N/mm per mm"
            if getattr(scene, "wall_stiffness", np.inf) < np.inf else "")
         + ", sliders at both ends, the pull on the right end"),
        ("pull-out force", f"{1e3 * po.force:.6g} mN ({po.force:.6g} N)"),
        ("normal force", f"{1e3 * po.normal_force_total:.6g} mN over every wall, at pull-out "
                         f"(the last state held, pull {held})"),
        ("capacity", f"{1e3 * po.capacity:.6g} mN (" + (
            "sum of mu N there" if getattr(scene, "wall_profile", None) is None else
            "the pull gross slip balances there: sum of N (mu t_x - n_x)") + ")"),
        ("stick to slip", events or "none between the states held"),
        ("solves", f"{po.solves} frictional"),
        ("converged", ("yes" if po.converged else "no") + f" ({po.reason})"),
    ]
    if plot is not None:
        rows.append(("plot", plot))
    return format_rows(rows)
