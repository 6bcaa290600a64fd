"""The back-end listing: ``lcpbench solvers [--json]``."""

from __future__ import annotations

import sys

from ._common import add_json_option, print_json


def register(subparsers) -> None:
    """Add ``solvers`` to the command line.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The top-level parser's sub-commands.
    """
    ls = subparsers.add_parser(
        "solvers", help="list every back-end, installed or not, with its capabilities",
        description="List every back-end: availability, version, form, the form of the "
                    "frictional step it takes, storage, warm start, method and how to "
                    "install it.")
    add_json_option(ls, "one JSON array")
    ls.set_defaults(func=cmd_solvers)


def cmd_solvers(args) -> int:
    """``lcpbench solvers``: one row a back-end; plug-ins that failed to load on stderr."""
    from ..solvers.registry import backends, plugin_errors

    rows = [b.capabilities() for b in backends().values()]
    if args.json:
        print_json(rows)
        return 0
    head = ("name", "installed", "version", "form", "friction", "storage", "warm", "method",
            "install")
    table = [[r["name"], "yes" if r["available"] else "no", r["version"] or "-", r["form"],
              r["friction"] or "-", r["storage"], "yes" if r["warm_start"] else "no",
              r["method"], r["install"]]
             for r in rows]
    widths = [max(len(str(x)) for x in col) for col in zip(head, *table)]
    for line in [head, *table]:
        print("  ".join(f"{str(x):<{w}}" for x, w in zip(line, widths)).rstrip())
    for err in plugin_errors():
        print(f"plug-in not loaded: {err}", file=sys.stderr)
    return 0
