"""The paper command: ``lcpbench reproduce [--out DIR] [--quick]``.

Regenerates the paper's figures and tables (Figs. 5-8, 10, 24, 26-27 and
Tables I-II) with the numbers behind them; needs matplotlib.
"""

from __future__ import annotations

import sys

from ..errors import ProblemError
from ._common import error_line, has_matplotlib


def register(subparsers) -> None:
    """Add ``reproduce`` to the command line.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The top-level parser's sub-commands.
    """
    rr = subparsers.add_parser(
        "reproduce", help="regenerate the paper's figures and tables (results/reproduced)",
        description="Figs. 5-8, 10, 24, 26-27 and Tables I-II of the paper from the model, "
                    "each as a PNG with the numbers behind it, and a README that puts our "
                    "numbers beside the paper's.")
    rr.add_argument("--out", default="results/reproduced", metavar="DIR",
                    help="output folder (default results/reproduced, not tracked; the "
                         "committed figures are regenerated only when asked: --out "
                         "results/paper). A file is rewritten only if its numbers changed "
                         "beyond round-off (relative 1e-6)")
    rr.add_argument("--quick", action="store_true",
                    help="coarser grids and smaller N: a smoke run in seconds")
    rr.set_defaults(func=cmd_reproduce)


def cmd_reproduce(args) -> int:
    """``lcpbench reproduce``: 0 when every stage was written, 2 without matplotlib."""
    if not has_matplotlib():
        error_line("reproduce draws figures: pip install 'lcpbench[plot]'")
        return 2
    from tqdm import tqdm

    from ..paper.reproduce import reproduce

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
    print(f"the paper's figures and tables in {args.out}/: {len(info['written'])} files "
          f"written, {len(info['unchanged'])} unchanged (the same numbers to round-off, "
          f"left as they were); see {args.out}/README.md")
    return 0
