"""The ``lcpbench`` command line.

::

    lcpbench solve --theta 150 --height 3 [--links N|auto] [--channel] [--solver NAME]
                   [--settings default|low|mid|high] [--raw] [--json] [--plot F.png]
    lcpbench anchor --pressure KPA | --theta DEG --height MM --friction MU [--channel] [--json]
    lcpbench cycle --friction 0.1,0.3 [--height MM] [--channel] [--pressure A:B:STEP] [--plot F.png]
    lcpbench solvers [--json]
    lcpbench export --theta 150 --height 3 [scene options] --format dat|npz --out FILE
    lcpbench lcp FILE [--solver NAME] [--settings PROFILE] [--formulation NAME|best] [--json]
    lcpbench validate cantilever [--links N] [--json]
    lcpbench sweep | report | select | reproduce ...
    lcpbench compile [--dir DIR]
    lcpbench --version

Exit status: 0 on success, 1 when the solve did not converge (the result is
still printed, with the reason), 2 on bad input (one line on stderr:
``lcpbench: error: <message>``, no traceback, no usage dump), 130 when
interrupted.

One module per command group, each with ``register(subparsers)`` whose
parsers set ``func(args) -> int``: :mod:`.solve` (solve, export, lcp,
validate), :mod:`.solvers` (solvers), :mod:`.sweep` (sweep, report, select),
:mod:`.anchor` (anchor), :mod:`.cycle` (cycle), :mod:`.paper` (reproduce, anchoring), :mod:`.compile` (compile), and ``lcpbench.vision.commands`` when it is
installed. The shared scene options are in :mod:`._scene_args`. The command
modules are imported when the parser is built, not by ``import lcpbench.cli``.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from ._common import PROG, ArgumentParser, ParserExit, error_line

__all__ = ["PROG", "build_parser", "main"]

# The command groups, in the order of `lcpbench --help`.
GROUPS = ("solve", "solvers", "sweep", "anchor", "cycle", "export", "paper", "compile", "design",
          "fit")


def _optional_groups() -> list:
    """Command groups of optional sub-packages that are present (today: vision)."""
    try:
        from ..vision import commands
    except ModuleNotFoundError as exc:
        if exc.name not in ("lcpbench.vision", "lcpbench.vision.commands"):
            raise  # vision is there but one of its own imports is broken: say so
        return []
    return [commands]


def _default_to_usage_error(parser: argparse.ArgumentParser) -> None:
    """Make every parser that has sub-commands report a missing one as bad input.

    A parser with sub-commands and no ``func`` of its own gets ``func=None``
    and ``parser=itself``, so :func:`main` can name what is missing.
    """
    for action in parser._actions:
        if not isinstance(action, argparse._SubParsersAction):
            continue
        if parser.get_default("func") is None:
            parser.set_defaults(func=None, parser=parser, subcommands=action)
        for sub in dict.fromkeys(action.choices.values()):
            _default_to_usage_error(sub)


def build_parser() -> ArgumentParser:
    """The top-level parser with every command group registered.

    Returns
    -------
    ArgumentParser
        Its errors are one line on stderr and :class:`ParserExit` (status 2).
    """
    from .. import __version__

    parser = ArgumentParser(
        prog=PROG,
        description="Contact modelling of slender soft actuators (Hencky bar chain + LCP).",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    commands = parser.add_subparsers(
        dest="command", metavar="COMMAND", parser_class=ArgumentParser
    )
    for name in GROUPS:
        importlib.import_module(f"{__name__}.{name}").register(commands)
    for group in _optional_groups():
        group.register(commands)
    _default_to_usage_error(parser)
    return parser


def _missing(args) -> str:
    action = args.subcommands
    return (f"missing {action.metavar} ({', '.join(action.choices)}); "
            f"see '{args.parser.prog} --help'")


#: the commands that solve nothing (the rest may compile the kernels at their first use)
NO_KERNELS = ("solvers", "report", "export", "compile", "vision")


def _first_use_notice() -> None:
    """One line on stderr when this process first compiles a kernel (one not yet in
    numba's cache for this install: the first solve of a kind, seconds to a minute on
    two cores), which would look like a hang (:func:`lcpbench.numba_cache.on_compile`)."""
    from ..numba_cache import on_compile

    on_compile(lambda: print(
        "lcpbench: compiling kernels for this install (once per kind of solve, up to about "
        "a minute on two cores; `lcpbench compile` builds the solve kernels ahead of "
        "time)", file=sys.stderr, flush=True))


def main(argv: list[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : list of str, optional
        The arguments after the program name (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        The exit status: 0 ok, 1 not converged or not solved, 2 bad input
        (one line on stderr), 130 interrupted.
    """
    from ..errors import LcpbenchError

    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        if args.func is None:
            args.parser.error(_missing(args))
        if args.command not in NO_KERNELS:
            _first_use_notice()
        return args.func(args)
    except ParserExit as exc:
        return exc.status
    except LcpbenchError as exc:  # ProblemError, SolverNotFound, StoreError...
        error_line(exc)
        return 2
    except KeyboardInterrupt:
        error_line("interrupted")
        return 130
    except BrokenPipeError:  # output piped into `head` and the like
        sys.stderr.close()
        return 0
    finally:  # the notice is this command's: a process that goes on compiles silently
        from ..numba_cache import on_compile

        on_compile(None)
