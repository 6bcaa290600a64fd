"""The ``lcpbench`` command line.

::

    lcpbench solve --theta 150 --height 3 [--links N|auto] [--channel] [--solver NAME]
                   [--settings default|low|mid|high] [--raw] [--json] [--plot F.png]
    lcpbench solvers [--json]
    lcpbench export --theta 150 --height 3 [scene options] --format dat|npz --out FILE
    lcpbench lcp FILE [--solver NAME] [--settings PROFILE] [--json]
    lcpbench validate cantilever [--links N] [--json]
    lcpbench --version

Exit status: 0 on success, 1 when the solve did not converge (the result is
still printed, with the reason), 2 on bad input (one line on stderr:
``lcpbench: error: <message>``, no traceback, no usage dump).
"""

from __future__ import annotations

import argparse
import inspect
import json
import math
import sys

import numpy as np

from . import __version__
from .api import solve
from .bench.harness import CONTINUATION, DEFAULT_TIME_LIMIT
from .bench.report import DEFAULT_OUT
from .bench.store import DEFAULT_STORE
from .errors import LcpbenchError, ProblemError
from .jsonsafe import sanitise
from .model.driver import METHODS
from .problems.scenes import (
    DEFAULT_EI,
    DEFAULT_LENGTH,
    DEFAULT_LINKS,
    DEFAULT_WEIGHT,
    MIN_LINKS,
    ActuatorScene,
)
from .solvers.base import PROFILES

PROG = "lcpbench"

# The defaults of ActuatorScene and lcpbench.solve, read from their owners
# rather than repeated here.
_FIELDS = ActuatorScene.__dataclass_fields__
DEFAULT_THETA = _FIELDS["theta"].default
DEFAULT_HEIGHT = _FIELDS["height"].default
_SOLVE = inspect.signature(solve).parameters
DEFAULT_TOL = _SOLVE["tol"].default
DEFAULT_SOLVER = _SOLVE["solver"].default
DEFAULT_METHOD = _SOLVE["method"].default


class _Exit(Exception):
    """Raised by the parser instead of exiting, so ``main`` can return a status."""

    def __init__(self, status: int):
        super().__init__(status)
        self.status = status


def _error_line(message: object) -> None:
    text = " ".join(str(message).split())  # exactly one line
    print(f"{PROG}: error: {text}", file=sys.stderr)


class ArgumentParser(argparse.ArgumentParser):
    """An argparse parser whose errors are one line on stderr and status 2."""

    def error(self, message: str):  # noqa: D102 - argparse API
        _error_line(message)
        raise _Exit(2)

    def exit(self, status: int = 0, message: str | None = None):  # noqa: D102
        if message:
            print(message, end="" if message.endswith("\n") else "\n", file=sys.stderr)
        raise _Exit(status)


def _links_arg(text: str) -> int | str:
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"links must be an integer >= {MIN_LINKS} or 'auto', got {text!r}"
        ) from None


def _int_arg(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def _add_scene_options(s) -> None:
    s.add_argument("--theta", type=float, default=None, metavar="DEG",
                   help=f"unconstrained bend angle, degrees in (0, 360) (default {DEFAULT_THETA:g})")
    s.add_argument("--pressure", type=float, default=None, metavar="KPA",
                   help="input pressure instead of --theta: theta from the actuator's "
                        "calibration (eqs. 40-42 of the paper, kPa)")
    s.add_argument("--actuator", default="1", metavar="1|2|3",
                   help="which of the paper's calibrations --pressure uses (default 1)")
    s.add_argument("--fit", default=None, metavar="SLOPE,INTERCEPT",
                   help="your own calibration theta = SLOPE * P + INTERCEPT (degrees, P in "
                        "the unit of --pressure) instead of --actuator")
    s.add_argument("--height", type=float, default=DEFAULT_HEIGHT, metavar="MM",
                   help=f"wall height above the pins, mm (default {DEFAULT_HEIGHT:g})")
    s.add_argument("--links", type=_links_arg, default=DEFAULT_LINKS, metavar="N|auto",
                   help=f"number of links, or 'auto' (default {DEFAULT_LINKS})")
    s.add_argument("--length", type=float, default=DEFAULT_LENGTH, metavar="MM",
                   help=f"section length, mm (default {DEFAULT_LENGTH:g})")
    s.add_argument("--EI", type=float, default=DEFAULT_EI, metavar="NMM2",
                   help=f"bending stiffness, N*mm^2 (default {DEFAULT_EI:g})")
    s.add_argument("--weight", type=float, default=DEFAULT_WEIGHT, metavar="NPMM",
                   help=f"weight per length, N/mm; 0 turns gravity off (default {DEFAULT_WEIGHT:g})")
    s.add_argument("--channel", action="store_true",
                   help="a second wall at -height (the paper's fixture)")


def _add_solver_options(s, default: str = DEFAULT_SOLVER) -> None:
    s.add_argument("--solver", default=default, metavar="NAME",
                   help=f"back-end (default {default}; `lcpbench solvers` lists them)")
    s.add_argument("--settings", choices=tuple(PROFILES), default="default",
                   help="accuracy profile: the solver's own defaults, or a generic "
                        "tolerance low 1e-3, mid 1e-6, high 1e-9 (default: default)")


def _add_store_options(s) -> None:
    s.add_argument("--store", default=str(DEFAULT_STORE), metavar="PATH",
                   help=f"SQLite results store (default {DEFAULT_STORE})")
    s.add_argument("--out", default=str(DEFAULT_OUT), metavar="DIR",
                   help=f"where the report goes (default {DEFAULT_OUT})")


def build_parser() -> ArgumentParser:
    parser = ArgumentParser(
        prog=PROG,
        description="Contact modelling of slender soft actuators (Hencky bar chain + LCP).",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    commands = parser.add_subparsers(
        dest="command", metavar="COMMAND", parser_class=ArgumentParser
    )

    s = commands.add_parser(
        "solve",
        help="constrained equilibrium of an actuator section against a wall",
        description="Solve one ActuatorScene and report the contact force and its certificate.",
    )
    _add_scene_options(s)
    s.add_argument("--tol", type=float, default=DEFAULT_TOL, metavar="RAD",
                   help=f"convergence threshold on max|d alpha|, rad (default {DEFAULT_TOL:g})")
    _add_solver_options(s)
    s.add_argument("--raw", action="store_true",
                   help="hand the back-end the raw step (mm, N) instead of the "
                        "nondimensionalised one")
    s.add_argument("--method", choices=METHODS, default=DEFAULT_METHOD,
                   help=f"outer iteration (default {DEFAULT_METHOD})")
    s.add_argument("--json", action="store_true", help="print the result as one JSON object")
    s.add_argument("--plot", metavar="FILE.png",
                   help="draw the shape, walls and reactions (needs matplotlib)")
    s.set_defaults(handler=_cmd_solve)

    ls = commands.add_parser(
        "solvers", help="list every back-end, installed or not, with its capabilities",
        description="List every back-end: availability, version, form, storage, warm "
                    "start, method and how to install it.")
    ls.add_argument("--json", action="store_true", help="print one JSON array")
    ls.set_defaults(handler=_cmd_solvers)

    e = commands.add_parser(
        "export", help="write the contact step at the converged configuration as an LCP file",
        description="Solve a scene, then write the contact step at its converged "
                    "configuration as an LCP (w = M z + q; z = gaps, w = reactions).")
    _add_scene_options(e)
    e.add_argument("--tol", type=float, default=DEFAULT_TOL, metavar="RAD",
                   help=f"convergence threshold of the solve, rad (default {DEFAULT_TOL:g})")
    e.add_argument("--format", choices=("dat", "npz"), default=None,
                   help="Siconos .dat (dense, column-major) or numpy .npz (M, q); "
                        "default: from the suffix of --out")
    e.add_argument("--out", required=True, metavar="FILE", help="where to write")
    e.add_argument("--raw", action="store_true",
                   help="physical units (mm, N) instead of the nondimensionalised step "
                        "(gaps / length, reactions / (EI/length^2))")
    e.set_defaults(handler=_cmd_export)

    lp = commands.add_parser(
        "lcp", help="solve an LCP file (.dat or .npz) with any back-end",
        description="Solve 0 <= z _|_ M z + q >= 0 from a Siconos .dat or a .npz file and "
                    "print z, w, status, iterations, time and residuals.")
    lp.add_argument("file", metavar="FILE", help="a .dat (Siconos) or .npz (M, q) file")
    _add_solver_options(lp, default="lemke")
    lp.add_argument("--json", action="store_true", help="print the result as one JSON object")
    lp.set_defaults(handler=_cmd_lcp)

    sw = commands.add_parser(
        "sweep", help="run a grid of scenes over back-ends and settings into the results store",
        description="Run every scene of a theta x height grid (and optionally N, EI, w, "
                    "length) with every back-end and settings profile, plus the root-finding "
                    "baseline, into an SQLite store; then write the report. A killed sweep "
                    "resumes where it stopped when run again. With no arguments: the paper's "
                    "grid (theta 10-180 by 10, h 2-7 mm by 1, N = 140) over every installed "
                    "back-end. With --continuation each back-end solves every line of the "
                    "grid (all parameters but theta equal) in order of theta, each scene "
                    "started from its neighbours' answers; those runs are stored as driver "
                    "globalised+secant (or +previous), apart from the cold ones.")
    sw.add_argument("--grid", choices=("paper", "hard"), default="paper",
                    help="paper: the theta x height grid below (default); hard: the "
                         "hard-case suite (theta 170-180, h down to 0.02 l, N up to 2000, "
                         "grazing, no contact, heavy, EI 1-1000, channel)")
    sw.add_argument("--theta", default=None, metavar="A:B:STEP",
                    help="bend angles, degrees: start:stop:step (stop included), a comma list "
                         "or one value (default 10:180:10)")
    sw.add_argument("--height", default=None, metavar="A:B:STEP",
                    help="wall heights, mm (default 2:7:1)")
    sw.add_argument("--links", default=str(DEFAULT_LINKS), metavar="LIST",
                    help=f"numbers of links (default {DEFAULT_LINKS})")
    sw.add_argument("--EI", default=None, metavar="LIST", help="bending stiffnesses, N*mm^2 "
                    f"(default {DEFAULT_EI:g})")
    sw.add_argument("--weight", default=None, metavar="LIST",
                    help=f"weights per length, N/mm (default {DEFAULT_WEIGHT:g})")
    sw.add_argument("--length", default=None, metavar="LIST",
                    help=f"section lengths, mm (default {DEFAULT_LENGTH:g})")
    sw.add_argument("--channel", action="store_true", help="two walls, at +h and -h")
    sw.add_argument("--solvers", default="all", metavar="A,B,..",
                    help="back-ends to run (default: every installed one)")
    sw.add_argument("--settings", default="default,high", metavar="P,Q,..",
                    help="settings profiles among default, low, mid, high (default "
                         "default,high)")
    sw.add_argument("--tol", type=float, default=None, metavar="RAD",
                    help="driver tolerance of every run (default: per profile, 1e-3 for "
                         "default and low, 1e-6 mid, 1e-9 high)")
    sw.add_argument("--method", default=DEFAULT_METHOD, metavar="M[,M]",
                    help=f"outer iteration(s): globalised, undamped or both, comma-separated "
                         f"(default {DEFAULT_METHOD})")
    sw.add_argument("--continuation", nargs="?", const="quadratic", default=None,
                    choices=CONTINUATION, metavar="PREDICTOR",
                    help="warm-start along theta: run each back-end over each line of "
                         "scenes (every parameter but theta equal), theta ascending, each "
                         "scene started from the extrapolation of the previous answers: "
                         "quadratic (the parabola through the last three; the default when "
                         "given without a value), secant (the line through the last two) or "
                         "previous (the last answer); stored as driver "
                         "globalised+PREDICTOR, so a cold sweep into the same store "
                         "compares with it in the report. Globalised driver only; the time "
                         "limit of a line is --time-limit per scene")
    sw.add_argument("--baseline", choices=("analytic", "fd", "both", "none"),
                    default="both",
                    help="the root-finding baseline: analytic Jacobian, finite differences "
                         "as fsolve would (about 1 s per scene), both (default), or none")
    _add_store_options(sw)
    sw.add_argument("--no-report", action="store_true", help="do not write the report")
    sw.add_argument("--jobs", type=_int_arg, default=None, metavar="K",
                    help="worker processes (default: the number of cores, at most 4)")
    sw.add_argument("--time-limit", type=float, default=DEFAULT_TIME_LIMIT, metavar="S",
                    help=f"seconds per solve before it is killed and recorded as a timeout "
                         f"(default {DEFAULT_TIME_LIMIT:g})")
    sw.add_argument("--rerun", action="store_true",
                    help="recompute runs that are already in the store")
    sw.add_argument("--quiet", action="store_true", help="no progress bar")
    sw.set_defaults(handler=_cmd_sweep)

    rp = commands.add_parser(
        "report", help="tables, CSV and figures from a results store",
        description="Build the comparison tables, the paper's Table II, the CSV of every "
                    "run and the figures from the store alone (nothing is solved).")
    _add_store_options(rp)
    rp.add_argument("--table2-height", type=float, default=None, metavar="MM",
                    help="wall height of the Table II-style table (default: the smallest)")
    rp.add_argument("--no-plots", action="store_true", help="tables and CSV only")
    rp.set_defaults(handler=_cmd_report)

    se = commands.add_parser(
        "select", help="the fastest back-end that meets an accuracy on this kind of scene",
        description="Probe every installed back-end and settings profile on four scenes of "
                    "this kind (N, length, EI, w, channel), cache the runs in the store, and "
                    "print the fastest one whose total-force error is within --tol on all of "
                    "them.")
    se.add_argument("--tol", type=float, default=1e-6, metavar="REL",
                    help="largest relative error of the total force (default 1e-6)")
    se.add_argument("--time-budget", type=float, default=None, metavar="S",
                    help="largest mean time of one solve, seconds (default: none)")
    _add_scene_options(se)
    se.add_argument("--solvers", default="all", metavar="A,B,..",
                    help="candidate back-ends (default: every installed one)")
    se.add_argument("--store", default=None, metavar="PATH",
                    help=f"where the probes are cached (default $LCPBENCH_STORE or "
                         f"{DEFAULT_STORE})")
    se.add_argument("--jobs", type=_int_arg, default=None, metavar="K",
                    help="worker processes (default: the number of cores, at most 4)")
    se.add_argument("--json", action="store_true", help="print the selection as JSON")
    se.add_argument("--quiet", action="store_true", help="no progress bar")
    se.set_defaults(handler=_cmd_select)

    rr = commands.add_parser(
        "reproduce", help="regenerate the paper's figures and tables into results/paper",
        description="Figs. 5-8, 10, 24, 26-27 and Tables I-II of the paper from the model, "
                    "each as a PNG with the numbers behind it, and a README that puts our "
                    "numbers beside the paper's.")
    rr.add_argument("--out", default="results/paper", metavar="DIR",
                    help="output folder (default results/paper)")
    rr.add_argument("--quick", action="store_true",
                    help="coarser grids and smaller N: a smoke run in seconds")
    rr.set_defaults(handler=_cmd_reproduce)

    v = commands.add_parser(
        "validate",
        help="validation against beam theory",
        description="Compare the model against a closed-form reference.",
    )
    cases = v.add_subparsers(dest="case", metavar="CASE", parser_class=ArgumentParser)
    c = cases.add_parser(
        "cantilever",
        help="clamped-free beam under a uniform load against a wall (Sec. III-G)",
    )
    c.add_argument("--links", type=_int_arg, default=DEFAULT_LINKS, metavar="N",
                   help=f"number of links (default {DEFAULT_LINKS})")
    c.add_argument("--json", action="store_true", help="print the result as one JSON object")
    c.set_defaults(handler=_cmd_validate_cantilever)
    v.set_defaults(handler=None, parser=v)
    from .vision.commands import register as register_vision  # no OpenCV import until run

    register_vision(commands)
    parser.set_defaults(handler=None, parser=parser)
    return parser


# -- output helpers -----------------------------------------------------------
def _print_json(obj) -> None:
    print(json.dumps(sanitise(obj), allow_nan=False))


def _node_ranges(nodes) -> str:
    """'20-22 (3 nodes)' from sorted 1-based node numbers; 'none' if empty."""
    nodes = [int(n) for n in nodes]
    if not nodes:
        return "none"
    runs, start, prev = [], nodes[0], nodes[0]
    for n in nodes[1:]:
        if n != prev + 1:
            runs.append((start, prev))
            start = n
        prev = n
    runs.append((start, prev))
    text = ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs)
    return f"{text} ({len(nodes)} node{'s' if len(nodes) != 1 else ''})"


def _contacts(forces, free_nodes) -> list[int]:
    forces = np.asarray(forces, float)
    total = float(forces.sum())
    idx = np.flatnonzero(forces > 1e-9 * max(total, 1e-300))
    return (np.asarray(free_nodes)[idx] + 1).tolist()  # 1-based node numbers


def _summary(result, extra=()) -> str:
    sc = result.scene
    cert = result.certificate
    free = sc.chain().free_nodes  # solve() resolved links="auto" in result.scene
    scene = (f"theta={sc.theta:g} deg, h={sc.height:g} mm, N={result.links}, "
             f"length={sc.length:g} mm, EI={sc.EI:g} N*mm^2, w={sc.weight:g} N/mm"
             + (", channel" if sc.channel else ""))
    rows = [
        ("scene", scene),
        ("converged", ("yes" if result.converged else "no") + f" ({result.reason})"),
        ("total force", f"{1e3 * result.total_force:.6g} mN ({result.total_force:.6g} N)"),
        ("contact nodes", _node_ranges(_contacts(result.forces, free))),
    ]
    if result.forces_lower is not None:
        lower = float(np.sum(result.forces_lower))
        rows += [
            ("lower wall", f"{1e3 * lower:.6g} mN ({lower:.6g} N)"),
            ("lower contacts", _node_ranges(_contacts(result.forces_lower, free))),
        ]
    rows += [
        ("iterations", f"{result.outer_iterations} outer, {result.inner_iterations} inner "
                       f"({result.solver}, {result.method}, tol {result.tol:g} rad)"),
        ("time", f"{result.time_s:.3g} s"),
        ("certificate", f"min gap {cert.min_gap:.3g} mm, min force {cert.min_force:.3g} N, "
                        f"complementarity {cert.complementarity:.3g} N*mm, "
                        f"closure {cert.closure:.3g} mm"),
        ("", f"max torque residual {cert.max_torque_residual:.3g} N*mm "
             f"({cert.relative_torque_residual:.3g} relative)"),
        *extra,
    ]
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


# -- commands -----------------------------------------------------------------
def _cmd_solve(args) -> int:
    if args.plot is not None:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            _error_line("--plot needs matplotlib: pip install 'lcpbench[plot]'")
            return 2
    scene = _scene_from(args)
    result = solve(scene, solver=args.solver, tol=args.tol, method=args.method,
                   settings=args.settings, scaled=not args.raw)
    plot_error = None
    if args.plot is not None:
        from .bench.plot import plot_shape

        try:
            plot_shape(result, args.plot)
        except (OSError, ValueError) as exc:
            plot_error = f"--plot {args.plot}: {exc}"
    if args.json:
        _print_json(result.to_dict())
    else:
        extra = [("plot", args.plot)] if args.plot is not None and plot_error is None else []
        print(_summary(result, extra))
    if plot_error is not None:  # the result is printed all the same
        _error_line(plot_error)
        return 2
    return 0 if result.converged else 1


def _scene_from(args) -> ActuatorScene:
    kw = {"height": args.height, "links": args.links, "length": args.length, "EI": args.EI,
          "weight": args.weight, "channel": args.channel}
    if args.pressure is None:
        if args.fit is not None:
            raise ProblemError("--fit needs --pressure")
        theta = DEFAULT_THETA if args.theta is None else args.theta
        return ActuatorScene(theta=theta, **kw)
    from .problems.calibrations import linear_calibration, scene_from_pressure

    if args.theta is not None:
        raise ProblemError("give --theta or --pressure, not both (the calibration sets theta)")
    actuator = args.actuator
    if args.fit is not None:
        try:
            slope, intercept = (float(v) for v in args.fit.split(","))
        except ValueError:
            raise ProblemError(f"fit must be SLOPE,INTERCEPT (two numbers), got "
                               f"{args.fit!r}") from None
        actuator = linear_calibration(slope, intercept)
    return scene_from_pressure(args.pressure, actuator, **kw)


def _cmd_solvers(args) -> int:
    from .solvers.registry import backends, plugin_errors

    rows = [b.capabilities() for b in backends().values()]
    if args.json:
        _print_json(rows)
        return 0
    head = ("name", "installed", "version", "form", "storage", "warm", "method", "install")
    table = [[r["name"], "yes" if r["available"] else "no", r["version"] or "-", r["form"],
              r["storage"], "yes" if r["warm_start"] else "no", r["method"], r["install"]]
             for r in rows]
    widths = [max(len(str(x)) for x in col) for col in zip(head, *table)]
    for line in [head, *table]:
        print("  ".join(f"{str(x):<{w}}" for x, w in zip(line, widths)).rstrip())
    for err in plugin_errors():
        print(f"plug-in not loaded: {err}", file=sys.stderr)
    return 0


def _cmd_export(args) -> int:
    from .model.step import assemble_step
    from .problems.lcpfile import write_lcp
    from .solvers.runner import step_lcp

    fmt = args.format
    if fmt is None:
        suffix = args.out.rsplit(".", 1)[-1].lower() if "." in args.out else ""
        if suffix not in ("dat", "npz"):
            _error_line(f"--out {args.out}: give a .dat or .npz suffix, or --format dat|npz")
            return 2
        fmt = suffix
    scene = _scene_from(args)
    result = solve(scene, tol=args.tol)
    if not result.converged:
        _error_line(f"the scene did not converge ({result.reason}); nothing written")
        return 1
    chain = result.scene.chain()
    step = assemble_step(chain, result.alpha)
    form, M, q, _, _ = step_lcp(step, scaled=not args.raw)
    write_lcp(args.out, M, q, fmt=fmt)
    units = "mm and N" if args.raw else "gaps / length, reactions / (EI/length^2)"
    print(f"wrote {args.out}: LCP of size {q.size} (contact rows of nodes "
          f"{_node_ranges(chain.free_nodes[form.rows] + 1)}; {units})")
    return 0


def _cmd_lcp(args) -> int:
    from .problems.lcpfile import read_lcp
    from .solvers.runner import solve_lcp

    prob = read_lcp(args.file)
    sol = solve_lcp(prob.M, prob.q, args.solver, args.settings)
    res = sol.extra.get("residuals", {})
    out = {
        "file": args.file, "size": int(prob.q.size), "solver": sol.extra.get("backend"),
        "settings": args.settings, "status": sol.status.value, "message": sol.message,
        "iterations": sol.iterations, "solve_time_s": sol.solve_time,
        "setup_time_s": sol.setup_time, "time_source": sol.extra.get("time_source", "solver"),
        "residuals": res, "z": sol.z, "w": sol.w,
    }
    if args.json:
        _print_json(out)
    else:
        with np.printoptions(precision=6, threshold=20, edgeitems=5, linewidth=100):
            rows = [
                ("problem", f"{args.file} (n = {prob.q.size})"),
                ("solver", f"{out['solver']} (settings {args.settings})"),
                ("status", sol.status.value + (f" ({sol.message})" if sol.message else "")),
                ("iterations", str(sol.iterations)),
                ("time", f"solve {1e6 * sol.solve_time:.1f} us, setup "
                         f"{1e6 * sol.setup_time:.1f} us ({out['time_source']})"),
                ("residuals", ", ".join(f"{k} {v:.3g}" for k, v in res.items()) or "n/a"),
                ("z", str(np.asarray(sol.z))),
                ("w", str(np.asarray(sol.w))),
            ]
        width = max(len(k) for k, _ in rows)
        print("\n".join(f"{k:<{width}}  {v}" for k, v in rows))
    return 0 if sol.solved else 1


def _float_list(text, name) -> tuple | None:
    from .bench.grid import parse_range

    return None if text is None else parse_range(text, name)


def _positive_number(value, name) -> float:
    if not (math.isfinite(value) and value > 0):
        raise ProblemError(f"{name} must be a number > 0, got {value:g}")
    return value


def _cmd_sweep(args) -> int:
    from .bench.grid import Grid, parse_range
    from .bench.harness import default_workers, plan_sweep, sweep
    from .bench.store import Store
    from .solvers.registry import available_backends, get_backend, get_settings

    if args.grid == "hard":
        from .bench.grid import hard_scenes

        given = [f"--{n}" for n in ("theta", "height", "EI", "weight", "length")
                 if getattr(args, n) is not None] + (["--channel"] if args.channel else [])
        if given or args.links != str(DEFAULT_LINKS):
            raise ProblemError("--grid hard is a fixed list of scenes; it takes no "
                               f"{', '.join(given) or '--links'}")
        scenes = hard_scenes()
    else:
        grid_kw = {"theta": parse_range(args.theta or "10:180:10", "theta"),
                   "height": parse_range(args.height or "2:7:1", "height"),
                   "links": parse_range(args.links, "links", integer=True),
                   "channel": args.channel}
        for name in ("EI", "weight", "length"):
            values = _float_list(getattr(args, name), name)
            if values is not None:
                grid_kw[name] = values
        scenes = Grid(**grid_kw).scenes()  # validates every scene before anything runs
    methods = [m.strip() for m in args.method.split(",") if m.strip()]
    if args.continuation is not None and "undamped" in methods:
        raise ProblemError("--continuation needs the globalised driver; it cannot be used "
                           "with --method undamped")
    if args.solvers.strip() == "all":
        solvers = available_backends()
    else:
        solvers = list(dict.fromkeys(x.strip() for x in args.solvers.split(",") if x.strip()))
        if not solvers:
            raise ProblemError("solvers must list at least one back-end, or be 'all'")
        for name in solvers:
            get_backend(name)  # unknown or not installed: SolverNotFound, exit 2
    settings = list(dict.fromkeys(x.strip() for x in args.settings.split(",") if x.strip()))
    if not settings:
        raise ProblemError("settings must list at least one of default, low, mid, high")
    for p in settings:
        get_settings(p)
    if args.tol is not None:
        from .api import _check_tol

        _check_tol(args.tol)
    jobs_n = default_workers() if args.jobs is None else args.jobs
    if jobs_n < 1:
        raise ProblemError(f"jobs must be an integer >= 1, got {jobs_n}")
    limit = _positive_number(args.time_limit, "time-limit")
    baselines = {"analytic": ["baseline"], "fd": ["baseline-fd"],
                 "both": ["baseline", "baseline-fd"], "none": []}[args.baseline]
    jobs = plan_sweep(scenes, solvers, settings, tol=args.tol, method=methods,
                      baselines=baselines, continuation=args.continuation)
    with Store(args.store) as store:
        bar = _progress(args.quiet)
        try:
            plan = sweep(store, jobs, workers=jobs_n, time_limit=limit, rerun=args.rerun,
                         progress=bar.update if bar else None)
        except KeyboardInterrupt:
            if bar:
                bar.close()
            _error_line(f"interrupted: {store.count()} runs are safe in {args.store}; run the "
                        "same command again to resume")
            return 130
        if bar:
            bar.close()
        lines = sum(j.kind == "line" for j in jobs) // max(1, len(solvers) * len(settings))
        along = (f" by {args.continuation} continuation along {lines} line(s) in theta"
                 if args.continuation else "")
        print(f"{plan.rows_todo} runs computed, {plan.rows_done} already in {args.store} "
              f"({len(scenes)} scenes x {len(solvers)} back-ends x {len(settings)} settings"
              f"{f' x {len(methods)} drivers' if len(methods) > 1 else ''}{along}"
              f" + {len(baselines)} baseline(s) + references; {jobs_n} worker(s))")
        if not args.no_report:
            return _write_report(store, args.out, limit, None, plots=True)
    return 0


class _Bar:
    """A tqdm progress bar with an ETA, fed by the sweep's progress callback."""

    def __init__(self):
        from tqdm import tqdm

        self.bar = None
        self.tqdm = tqdm
        self.failed = 0

    def update(self, done, total, job, row) -> None:
        if self.bar is None:
            self.bar = self.tqdm(total=total, initial=done - 1, unit="run", file=sys.stderr,
                                 dynamic_ncols=True, desc="sweep")
        if row.get("status") != "solved":
            self.failed += 1
        self.bar.set_postfix_str(f"{job.backend} {job.settings}; not solved {self.failed}",
                                 refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _progress(quiet: bool):
    return None if quiet else _Bar()


def _write_report(store, out, time_limit, table2_height, plots: bool) -> int:
    from .bench.report import build_report

    if plots:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            plots = False
            print("matplotlib is not installed: tables only (pip install 'lcpbench[plot]')",
                  file=sys.stderr)
    try:
        info = build_report(store, out, time_limit=time_limit, plots=plots,
                            table2_height=table2_height)
    except OSError as exc:
        raise ProblemError(f"out {out}: cannot write the report there ({exc})") from exc
    print(f"report of {info['runs']} runs in {info['out']}/report.md")
    return 0


def _cmd_report(args) -> int:
    from .bench.store import Store

    with Store(args.store, create=False) as store:
        return _write_report(store, args.out, DEFAULT_TIME_LIMIT, args.table2_height,
                             plots=not args.no_plots)


def _cmd_select(args) -> int:
    from .bench.harness import default_workers
    from .bench.select import select_backend

    scene = _scene_from(args)
    if scene.links == "auto":
        raise ProblemError("links must be a number for select (the kind of scene is N, "
                           "length, EI, w and channel)")
    candidates = None if args.solvers.strip() == "all" else [
        x.strip() for x in args.solvers.split(",") if x.strip()]
    workers = default_workers() if args.jobs is None else args.jobs
    if workers < 1:
        raise ProblemError(f"jobs must be an integer >= 1, got {workers}")
    bar = _progress(args.quiet)
    try:
        sel = select_backend(scene, tol=args.tol, time_budget=args.time_budget,
                             store=args.store, candidates=candidates, workers=workers,
                             progress=bar.update if bar else None)
    finally:
        if bar:
            bar.close()
    if args.json:
        _print_json(sel.to_dict())
    elif sel.backend is None:
        print(f"no back-end: {sel.reason}")
    else:
        print(f"{sel.backend} --settings {sel.settings}: {sel.reason}")
    return 0 if sel.backend is not None else 1


def _cmd_reproduce(args) -> int:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        _error_line("reproduce draws figures: pip install 'lcpbench[plot]'")
        return 2
    from tqdm import tqdm

    from .bench.reproduce import reproduce

    bar = tqdm(unit="stage", file=sys.stderr, desc="reproduce", dynamic_ncols=True)

    def progress(done, total, stage):
        bar.total = total
        bar.set_postfix_str(stage, refresh=False)
        bar.update(done - bar.n)

    try:
        info = reproduce(args.out, quick=args.quick, progress=progress)
    except OSError as exc:
        raise ProblemError(f"out {args.out}: cannot write there ({exc})") from exc
    finally:
        bar.close()
    print(f"wrote the paper's figures and tables to {args.out}/ "
          f"({len(info.get('files', []))} files); see {args.out}/README.md")
    return 0


def _cmd_validate_cantilever(args) -> int:
    from .model.validation import cantilever_validation

    out = cantilever_validation(args.links)
    if args.json:
        _print_json(out)
    else:
        err = out["relative_error"]
        rows = [
            ("case", f"cantilever, uniform load against a wall (Sec. III-G), N={out['links']}"),
            ("model force", f"{1e3 * out['model_force']:.6g} mN"),
            ("theory force", f"{1e3 * out['theory_force']:.6g} mN (linear beam theory)"),
            ("relative error", "n/a (no contact in theory)" if not math.isfinite(err)
             else f"{100 * err:+.4g} %"),
            ("converged", ("yes" if out["converged"] else "no")
             + f" ({out['outer_iterations']} outer iterations)"),
            ("contact nodes", _node_ranges(out["contact_nodes"])),
        ]
        width = max(len(k) for k, _ in rows)
        print("\n".join(f"{k:<{width}}  {v}" for k, v in rows))
    return 0 if out["converged"] else 1


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 1 not converged, 2 bad input)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if args.handler is None:
            what = ("CASE (cantilever)" if args.command == "validate" else
                    "COMMAND (solve, solvers, export, lcp, sweep, report, select, reproduce, validate)")
            args.parser.error(f"missing {what}; see '{args.parser.prog} --help'")
        return args.handler(args)
    except _Exit as exc:
        return exc.status
    except LcpbenchError as exc:
        _error_line(exc)
        return 2
    except BrokenPipeError:  # output piped into `head` and the like
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    raise SystemExit(main())
