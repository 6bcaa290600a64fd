"""The paper commands: ``lcpbench reproduce [--out DIR] [--quick]`` and
``lcpbench anchoring [--out DIR] [--quick]``.

``reproduce`` regenerates the paper's figures and tables (Figs. 5-8, 10, 24,
26-27 and Tables I-II) with the numbers behind them; ``anchoring`` reruns
Fig. 24's scenes with the whole 3-section actuator beside the single-section
model (issue 17). Both need matplotlib.
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
                    help="coarser grids and smaller N: a smoke run in seconds (once the kernels are "
                         "compiled)")
    rr.set_defaults(func=cmd_reproduce)

    an = subparsers.add_parser(
        "anchoring", help="Fig. 24's scenes with the whole 3-section actuator "
                          "(results/anchoring-run)",
        description="Solve the scenes of Fig. 24 (actuators 1-3, h = 4.5, 5.5, 6.5 mm, "
                    "0-172.37 kPa, the paper's channel) with the paper's single-section "
                    "model and with the whole 3-section anchoring actuator (weight away from "
                    "and toward the load cell); write the middle section's force and shape "
                    "beside the single section's, when all three sections touch, tables "
                    "and two figures.")
    an.add_argument("--out", default="results/anchoring-run", metavar="DIR",
                    help="output folder (default results/anchoring-run, not tracked; the "
                         "committed study is regenerated only when asked: --out "
                         "results/anchoring). A file is rewritten only if its numbers "
                         "changed beyond round-off (relative 1e-6)")
    an.add_argument("--quick", action="store_true",
                    help="6 pressures and N = 40 per section: a smoke run")
    an.set_defaults(func=cmd_anchoring)


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


def cmd_anchoring(args) -> int:
    """``lcpbench anchoring``: 0 when the study was written, 2 without matplotlib."""
    if not has_matplotlib():
        error_line("anchoring draws figures: pip install 'lcpbench[plot]'")
        return 2
    from ..paper.anchoring import anchoring_study

    try:
        info = anchoring_study(args.out, quick=args.quick)
    except OSError as exc:
        raise ProblemError(f"out {args.out}: cannot write there ({exc})") from exc
    s = info["summary"]
    print(f"the whole actuator beside the single section in {args.out}/: "
          f"{len(info['written'])} files written, {len(info['unchanged'])} unchanged; "
          f"{s['scenes']} rows, all converged: {s['all_converged']}; see "
          f"{args.out}/README.md")
    return 0
