"""What every command module of the ``lcpbench`` command line shares.

The parser class whose errors are one line on stderr, the small argument
types, and the output helpers (JSON, aligned key/value tables, node ranges,
the progress bar). Nothing here imports numpy, the bench or matplotlib at
module level, so ``import lcpbench.cli`` stays cheap.
"""

from __future__ import annotations

import argparse
import json
import sys

PROG = "lcpbench"


class ParserExit(Exception):
    """Raised by the parser instead of exiting, so ``main`` can return a status.

    Parameters
    ----------
    status : int
        The exit status the parser asked for.
    """

    def __init__(self, status: int):
        super().__init__(status)
        self.status = status


def error_line(message: object) -> None:
    """Print ``lcpbench: error: <message>`` on stderr, folded to exactly one line.

    Parameters
    ----------
    message : object
        What went wrong; its ``str`` is printed with white space folded.
    """
    text = " ".join(str(message).split())  # exactly one line
    print(f"{PROG}: error: {text}", file=sys.stderr)


class ArgumentParser(argparse.ArgumentParser):
    """An argparse parser whose errors are one line on stderr and status 2."""

    def error(self, message: str):  # noqa: D102 - argparse API
        error_line(message)
        raise ParserExit(2)

    def exit(self, status: int = 0, message: str | None = None):  # noqa: D102
        if message:
            print(message, end="" if message.endswith("\n") else "\n", file=sys.stderr)
        raise ParserExit(status)


def int_arg(text: str) -> int:
    """Argument type: an integer, with a one-line message otherwise.

    Parameters
    ----------
    text : str
        The word given on the command line.

    Returns
    -------
    int
        Its value.
    """
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def add_json_option(parser, what: str = "the result as one JSON object") -> None:
    """Add ``--json`` (print *what* instead of the human summary).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser.
    what : str
        The end of the help text, after "print".
    """
    parser.add_argument("--json", action="store_true", help=f"print {what}")


def add_jobs_option(parser) -> None:
    """Add ``--jobs K``, the number of worker processes (see :func:`worker_count`).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser.
    """
    parser.add_argument("--jobs", type=int_arg, default=None, metavar="K",
                        help="worker processes (default: the number of cores, at most 4; "
                             "never more than the cores unless --oversubscribe)")
    parser.add_argument("--oversubscribe", action="store_true",
                        help="allow --jobs above the number of cores (the stored times are "
                             "then those of processes sharing cores)")


def print_json(obj) -> None:
    """Print *obj* as one strict JSON document (non-finite numbers sanitised).

    Parameters
    ----------
    obj : object
        Anything :func:`lcpbench.jsonsafe.sanitise` accepts.
    """
    from ..jsonsafe import sanitise

    print(json.dumps(sanitise(obj), allow_nan=False))


def format_rows(rows) -> str:
    """Key/value rows as aligned lines: the keys padded to the widest.

    Parameters
    ----------
    rows : sequence of (str, str)
        The label and the value of each line.

    Returns
    -------
    str
        The lines joined by newlines.
    """
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def node_ranges(nodes) -> str:
    """'20-22 (3 nodes)' from sorted 1-based node numbers; 'none' if empty.

    Parameters
    ----------
    nodes : iterable of int
        Sorted 1-based node numbers.

    Returns
    -------
    str
        The runs of consecutive nodes and their count.
    """
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


def has_matplotlib() -> bool:
    """Whether matplotlib can be imported (the figures need it).

    Returns
    -------
    bool
        True when ``import matplotlib`` succeeds.
    """
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    return True


class ProgressBar:
    """tqdm progress bars with an ETA, fed by the sweep's progress callback.

    With ``phases`` (rows still to compute per phase, e.g. ``{"references": 108,
    "runs": 4320}``) each phase gets its own bar, so the ETA of the cheap runs
    is not taken from the rate of the expensive references. The rate is the
    average since the phase began (``smoothing=0``), not tqdm's moving average
    of the last few rows, which swings by 100× when a 2 ms solve follows a
    1.7 s baseline.
    """

    def __init__(self, phases: dict[str, int] | None = None):
        from tqdm import tqdm

        self.tqdm = tqdm
        self.phases = {k: v for k, v in (phases or {}).items() if v > 0}
        self.bars: dict[str, object] = {}
        self.bar = None  # the bar of the last update (one bar without phases)
        self.failed = 0
        self.expected = 0

    def _bar(self, phase: str, done: int, total: int):
        bar = self.bars.get(phase)
        if bar is not None and not self.phases and (bar.total != total or bar.n != done - 1):
            bar.reset(total=total)  # another sweep on this bar (select probes twice):
            bar.initial = bar.n = done - 1  # its stored rows, not in its rate (as at start)
            bar.refresh()
        if phase not in self.bars:
            if self.phases:
                size = self.phases.get(phase, 0)
                self.bars[phase] = self.tqdm(total=size, unit="row", file=sys.stderr,
                                             dynamic_ncols=True, smoothing=0,
                                             desc=f"{phase:>10}", position=len(self.bars))
            else:
                self.bars[phase] = self.tqdm(total=total, initial=done - 1, unit="run",
                                             file=sys.stderr, dynamic_ncols=True,
                                             smoothing=0, desc="sweep")
        return self.bars[phase]

    def update(self, done, total, job, row) -> None:
        """Advance by one run; count the runs that were not solved (and how many of
        those are documented expected failures, :mod:`lcpbench.bench.expected`).

        Parameters
        ----------
        done, total : int
            Runs finished (this one included) and planned.
        job : object
            The job just finished (its ``backend`` and ``settings`` are shown).
        row : dict
            Its stored row (its ``status`` is counted).
        """
        phase = phase_of(job) if self.phases else "sweep"
        self.bar = self._bar(phase, done, total)
        if phase != "references" and row.get("status") != "solved":
            from ..bench.expected import is_expected

            self.failed += 1
            # no reference here: entries that need the run's error do not count
            self.expected += is_expected(job.backend, job.settings,
                                         str(row.get("status")), run=row)
        if phase != "references":
            # (at least: the report counts those its references show expected too)
            self.bar.set_postfix_str(f"{job.backend} {job.settings}; not solved "
                                     f"{self.failed} (at least {self.expected} expected)",
                                     refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        """Close the bars that were ever shown."""
        for bar in self.bars.values():
            bar.close()


def phase_of(job) -> str:
    """The progress phase of a sweep job: "references" or "runs"."""
    from ..bench.jobs import ReferenceJob

    return "references" if isinstance(job, ReferenceJob) else "runs"


def progress_bar(quiet: bool, phases: dict[str, int] | None = None) -> ProgressBar | None:
    """A progress bar, or None with ``--quiet``.

    Parameters
    ----------
    quiet : bool
        The ``--quiet`` flag.
    phases : dict, optional
        Rows to compute per phase (one bar each); without it, one bar.

    Returns
    -------
    ProgressBar or None
    """
    return None if quiet else ProgressBar(phases)


def names_list(text: str) -> list[str]:
    """The distinct non-empty items of a comma list, in order.

    Parameters
    ----------
    text : str
        For example ``"lemke, pgs,lemke"``.

    Returns
    -------
    list of str
        For example ``["lemke", "pgs"]``.
    """
    return list(dict.fromkeys(x.strip() for x in text.split(",") if x.strip()))


def worker_count(jobs: int | None, oversubscribe: bool = False) -> int:
    """The number of worker processes: ``--jobs``, or the harness's default.

    More workers than cores would store the times of processes sharing a
    core, so ``--jobs`` is refused above the core count unless
    ``oversubscribe`` is given.

    Parameters
    ----------
    jobs : int or None
        The ``--jobs`` value.
    oversubscribe : bool
        The ``--oversubscribe`` flag.

    Returns
    -------
    int
        At least 1.

    Raises
    ------
    ProblemError
        When *jobs* is below 1, or above the core count without *oversubscribe*.
    """
    import os

    from ..bench.sweep import default_workers
    from ..errors import ProblemError

    n = default_workers() if jobs is None else jobs
    if n < 1:
        raise ProblemError(f"jobs must be an integer >= 1, got {n}")
    cores = os.cpu_count() or 1
    if n > cores and not oversubscribe:
        raise ProblemError(f"jobs must be at most the {cores} cores of this machine, got {n} "
                           "(add --oversubscribe to run more workers than cores)")
    return n
