"""``lcpbench export-testset``: the contact steps as a qpbenchmark test set.

::

    lcpbench export-testset [--grid paper|hard] [--theta ..] [--height ..] [--links ..]
                            [--out DIR] [--solvers A,B|all] [--settings P,Q] [--no-results]
                            [--overwrite]
"""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import ProblemError
from ..problems.scenes import DEFAULT_LINKS

DEFAULT_OUT = Path("results") / "testset"


def register(subparsers) -> None:
    """Add ``export-testset`` to the command line."""
    ex = subparsers.add_parser(
        "export-testset", help="write the contact steps as a qpbenchmark test set",
        description="Write two contact steps per scene (at the driver's first configuration "
                    "and at the converged one) as bound-constrained QPs in qpsolvers' .npz "
                    "layout, with a qpbenchmark TestSet module, a README and problems.csv; "
                    "and (unless --no-results) lcpbench's back-ends on them in qpbenchmark's "
                    "results CSV schema.")
    ex.add_argument("--grid", choices=("paper", "hard"), default="paper",
                    help="paper: the theta x height grid (default); hard: the hard cases")
    ex.add_argument("--theta", default=None, metavar="A:B:STEP",
                    help="bend angles, degrees (default 10:180:10)")
    ex.add_argument("--height", default=None, metavar="A:B:STEP",
                    help="wall heights, mm (default 2:7:1)")
    ex.add_argument("--links", default=None, metavar="LIST",
                    help=f"numbers of links (default {DEFAULT_LINKS})")
    for name in ("EI", "weight", "length"):
        ex.add_argument(f"--{name}", default=None, metavar="LIST", help=f"{name} values")
    ex.add_argument("--channel", action="store_true", help="two walls, at +h and -h")
    ex.add_argument("--out", default=str(DEFAULT_OUT), metavar="DIR",
                    help=f"where the test set goes (default {DEFAULT_OUT})")
    ex.add_argument("--solvers", default="all", metavar="A,B,..",
                    help="back-ends whose results are written (default: every installed)")
    ex.add_argument("--settings", default="default,high", metavar="P,Q,..",
                    help="settings profiles of the results (default default,high)")
    ex.add_argument("--no-results", action="store_true",
                    help="write the problems only, not lcpbench's results on them")
    ex.add_argument("--overwrite", action="store_true",
                    help="replace a test set already in DIR (default: refuse)")
    ex.add_argument("--quiet", action="store_true", help="no progress line")
    ex.set_defaults(func=cmd_export_testset)


def cmd_export_testset(args) -> int:
    """Write the test set; 0 on success, 2 on bad input."""
    from ..bench.testset_files import export_testset
    from ._sweep_scenes import sweep_scenes
    from .sweep import sweep_backends

    scenes = sweep_scenes(args)
    solvers, settings = sweep_backends(args)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ProblemError(f"out {out}: is a file, not a folder")
    if (out / "problems.csv").exists() and not args.overwrite:
        raise ProblemError(f"out {out}: holds a test set already; pass --overwrite to "
                           "replace it, or another --out")

    def progress(done, problem, backend, s):
        if not args.quiet and done % 50 == 0:
            print(f"\r{done} results ({problem.name})", end="", file=sys.stderr, flush=True)

    try:
        info = export_testset(scenes, out, solvers=[] if args.no_results else solvers,
                              settings=settings, results=not args.no_results,
                              grid=args.grid, progress=progress)
    except OSError as exc:
        raise ProblemError(f"out {out}: cannot write the test set there ({exc})") from exc
    if not args.quiet:
        print(file=sys.stderr)
    print(f"{info['problems']} problems from {len(scenes)} scenes in {info['out']}"
          + (f"; {info['results']} result rows in {info['out']}/results/lcpbench_contact.csv"
             if info["results"] else ""))
    return 0
