"""``lcpbench compile``: the kernels compiled ahead of time (:mod:`lcpbench.aot`)."""

from __future__ import annotations


def register(subparsers) -> None:
    """Add ``compile`` to the command line.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The top-level parser's sub-commands.
    """
    c = subparsers.add_parser(
        "compile", help="compile the solve kernels ahead of time (a fast first solve)",
        description="Compile the kernels into numba's cache (the first time, about a "
                    "minute) and build their ahead-of-time module for this machine, so "
                    "that a new process's first solve does not import numba. Run it once "
                    "after installing or upgrading; solves work without it.")
    c.add_argument("--dir", default=None, help="output directory (default: beside numba's "
                   "cache of the kernels, <cache>/lcpbench-numba/<sha>/aot-<machine>)")
    c.set_defaults(func=cmd_compile)


def cmd_compile(args) -> int:
    """``lcpbench compile``: 0 built, 1 not built (one line says why)."""
    from ..aot import run

    return run(args.dir)
