"""``lcpbench design``: inverse queries (issue 38, item 2).

    lcpbench design --max-force F [--peak] [--by-pressure] [scene options] [--json]
    lcpbench design --min-force F [--by-pressure] [scene options] [--json]
    lcpbench design --touch [scene options] [--json]

The largest bend angle (or pressure) whose total force, or peak contact pressure with
``--peak``, stays at most F; the smallest that reaches F; the wall height of first
contact (:func:`lcpbench.studies.design.design`).
"""

from __future__ import annotations

from ..errors import ProblemError
from ._common import add_json_option, print_json
from ._scene_args import (
    add_profile_options,
    add_scene_options,
    add_wall_options,
    calibration_from,
    scene_from,
)


def register(subparsers) -> None:
    d = subparsers.add_parser(
        "design", help="inverse queries: the bend angle or pressure for a force limit, the "
                       "height of first touch",
        description="The largest bend angle (or pressure, --by-pressure) whose total force "
                    "(--peak: peak contact pressure per length) stays <= --max-force, the "
                    "smallest that reaches --min-force, or (--touch) the wall height at which "
                    "the actuator first touches the wall. Each answer is checked by a "
                    "forward solve; the output says how many solves it took.")
    add_scene_options(d)
    add_wall_options(d)
    add_profile_options(d)
    d.add_argument("--tol", type=float, default=1e-10, metavar="RAD",
                   help="convergence threshold of each forward solve, rad (default 1e-10: "
                        "the answer's force to 1e-6 needs forces to better than that)")
    q = d.add_mutually_exclusive_group(required=True)
    q.add_argument("--max-force", type=float, metavar="F",
                   help="N (N/mm with --peak): the largest theta or pressure that stays below")
    q.add_argument("--min-force", type=float, metavar="F",
                   help="N: the smallest theta or pressure that presses the walls with F")
    q.add_argument("--touch", action="store_true",
                   help="the wall height (mm) at which the actuator at --theta first touches")
    d.add_argument("--peak", action="store_true",
                   help="limit the peak contact pressure per length (N/mm), not the total "
                        "force (with --max-force)")
    d.add_argument("--by-pressure", action="store_true",
                   help="search the pressure over the calibration of --actuator (or --fit, "
                        "with --pressure as the start) and report it")
    add_json_option(d, "the answer as JSON")
    d.set_defaults(func=cmd_design)


def cmd_design(args) -> int:
    """0 answered, 2 bad input or a target out of reach (one line)."""
    from ..studies.design import design

    if args.peak and args.max_force is None:
        raise ProblemError("--peak limits the peak contact pressure: it goes with --max-force")
    if args.by_pressure and args.touch:
        raise ProblemError("--by-pressure searches the pressure for a force: not with --touch")
    scene = scene_from(args)
    got = design(scene, max_force=args.max_force, min_force=args.min_force, touch=args.touch,
                 peak=args.peak, calibration=calibration_from(args) if args.by_pressure else None,
                 tol=args.tol)
    if args.json:
        print_json(got.as_json())
        return 0
    if got.query == "touch":
        print(f"first touch    h = {got.height_mm:.6g} mm at theta = {got.theta_deg:g} deg "
              f"(1e-6 lower: {1e3 * got.beyond:.3g} mN; {got.solves} solves)")
        return 0
    unit, what = ("N/mm", "peak pressure") if got.peak else ("N", "total force")
    at = f"theta = {got.theta_deg:.6f} deg"
    if got.pressure is not None:
        at += f", P = {got.pressure:.6g} kPa"
    print(f"answer         {at}")
    print(f"{what:14s} {got.value:.9g} {unit} (limit {args.max_force or args.min_force:g})")
    if got.beyond == got.beyond:  # (NaN: the limit is not reached in the range)
        step = "+0.01 deg" if got.query == "max_force" else "-0.01 deg"
        print(f"{step:14s} {got.beyond:.9g} {unit} (a forward solve)")
    else:
        print("range          the limit is not reached in the range searched: its upper end")
    print(f"solves         {got.solves}")
    return 0
