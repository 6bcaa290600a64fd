"""The ``lcpbench`` command line.

::

    lcpbench solve --theta 150 --height 3 [--links N|auto] [--channel] [--json] [--plot F.png]
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
from .errors import LcpbenchError
from .model.driver import METHODS
from .problems.scenes import (
    DEFAULT_EI,
    DEFAULT_LENGTH,
    DEFAULT_LINKS,
    DEFAULT_WEIGHT,
    MIN_LINKS,
    ActuatorScene,
)

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
    s.add_argument("--theta", type=float, default=DEFAULT_THETA, metavar="DEG",
                   help=f"unconstrained bend angle, degrees in (0, 360) (default {DEFAULT_THETA:g})")
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
    s.add_argument("--tol", type=float, default=DEFAULT_TOL, metavar="RAD",
                   help=f"convergence threshold on max|d alpha|, rad (default {DEFAULT_TOL:g})")
    s.add_argument("--solver", default=DEFAULT_SOLVER, metavar="NAME",
                   help=f"contact-step back-end: auto, active-set, lemke (default {DEFAULT_SOLVER})")
    s.add_argument("--method", choices=METHODS, default=DEFAULT_METHOD,
                   help=f"outer iteration (default {DEFAULT_METHOD})")
    s.add_argument("--json", action="store_true", help="print the result as one JSON object")
    s.add_argument("--plot", metavar="FILE.png",
                   help="draw the shape, walls and reactions (needs matplotlib)")
    s.set_defaults(handler=_cmd_solve)

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
    parser.set_defaults(handler=None, parser=parser)
    return parser


# -- output helpers -----------------------------------------------------------
def sanitise(obj):
    """A JSON-ready copy of ``obj``: NaN/±inf become None, numpy becomes Python."""
    if isinstance(obj, dict):
        return {str(k): sanitise(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [sanitise(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return sanitise(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


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
    scene = ActuatorScene(theta=args.theta, height=args.height, links=args.links,
                          length=args.length, EI=args.EI, weight=args.weight,
                          channel=args.channel)
    result = solve(scene, solver=args.solver, tol=args.tol, method=args.method)
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
            what = "CASE (cantilever)" if args.command == "validate" else "COMMAND (solve, validate)"
            args.parser.error(f"missing {what}; see '{args.parser.prog} --help'")
        return args.handler(args)
    except _Exit as exc:
        return exc.status
    except LcpbenchError as exc:
        _error_line(exc)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
