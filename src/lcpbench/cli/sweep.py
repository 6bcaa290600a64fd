"""Commands over the results store: ``sweep``, ``report`` and ``select``.

::

    lcpbench sweep [--grid paper|hard|anchoring|tissue|friction] [--wall-stiffness LIST] [--theta A:B:STEP] [--height A:B:STEP] ...
                   [--solvers A,B] [--settings P,Q] [--continuation [PREDICTOR]]
                   [--store PATH] [--out DIR] [--jobs K] [--time-limit S] [--repeat K]
    lcpbench report [--store PATH] [--out DIR] [--all] [--format F] [--table2-height MM] [--no-plots]
    lcpbench select [scene options] [--force-tol REL] [--time-budget S] [--solvers A,B] [--repeat K]
                    [--formulation NAME|best]
"""

from __future__ import annotations

import math
import sys

from ..bench.store import DEFAULT_STORE
from ..bench.sweep import CONTINUATION, DEFAULT_TIME_LIMIT
from ..errors import ProblemError
from ..problems.scenes import DEFAULT_EI, DEFAULT_LENGTH, DEFAULT_LINKS, DEFAULT_WEIGHT
from ._common import (
    add_jobs_option,
    add_json_option,
    error_line,
    has_matplotlib,
    int_arg,
    names_list,
    print_json,
    progress_bar,
    worker_count,
)
from ._scene_args import DEFAULT_METHOD, add_scene_options, scene_from
from ._sweep_scenes import sweep_scenes

#: solves timed per run of the standard run (issue 16: one timing carried 2x noise)
DEFAULT_REPEAT = 3
#: What ``lcpbench sweep`` runs unless told otherwise, and what ``--standard`` runs
#: (the committed standard run, results/sweep). The main job fits in about two
#: minutes on two cores (issue 15): the documented never-converging back-ends
#: (:func:`~lcpbench.bench.expected.never_converges`), settings ``high``, the
#: finite-difference baseline and repeated timings are what make the standard run
#: take many times longer. Explicit options override either.
MAIN_JOB = {"settings": "default", "baseline": "analytic", "repeat": 1, "solvers": "main"}
STANDARD_RUN = {"settings": "default,high", "baseline": "both", "repeat": DEFAULT_REPEAT,
                "solvers": "all"}


def _add_store_options(parser) -> None:
    parser.add_argument("--store", default=str(DEFAULT_STORE), metavar="PATH",
                        help=f"SQLite results store (default {DEFAULT_STORE})")
    parser.add_argument("--out", default=None, metavar="DIR",
                        help="where the report goes (default: beside the store, a folder "
                             "named after it: results/lcpbench.sqlite -> "
                             "results/lcpbench-report; the committed standard report is "
                             "rewritten only with --out results/sweep)")


def register(subparsers) -> None:
    """Add ``sweep``, ``report`` and ``select`` to the command line.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The top-level parser's sub-commands.
    """
    sw = subparsers.add_parser(
        "sweep", help="run a grid of scenes over back-ends and settings into the results store",
        description="Run every scene of a theta x height grid (and optionally N, EI, w, "
                    "length) with every back-end and settings profile, plus the root-finding "
                    "baseline, into an SQLite store; then write the report. A killed sweep "
                    "resumes where it stopped when run again. With no arguments, the main "
                    "job: the paper's grid (theta 10-180 by 10, h 2-7 mm by 1, N = 140), "
                    "every installed back-end but those documented never to converge on its "
                    "contact steps (PGS/SOR, Siconos PGS and Newton-min at any N; Siconos' "
                    "enumeration and its Murty, Bard and path-search pivot rules from "
                    "N = 140 on), settings default, "
                    "the analytic-Jacobian baseline, each run timed once (about 2 minutes "
                    "on 2 cores). --standard: the standard run (every installed back-end, "
                    "settings default and high, both baselines, times the median of 3; "
                    "many times longer: PGS runs out its sweeps on every scene with contact, "
                    "the finite-difference baseline takes seconds a scene). With --continuation each back-end solves every line of the "
                    "grid (all parameters but theta equal) in order of theta, each scene "
                    "started from its neighbours' answers; those runs are stored as driver "
                    "globalised+secant (or +previous), apart from the cold ones.")
    sw.add_argument("--grid", choices=("paper", "hard", "anchoring", "tissue", "friction"),
                    default="paper",
                    help="paper: the theta x height grid below (default); hard: the "
                         "hard-case suite (theta 170-180, h down to 0.02 l, N up to 2000, "
                         "grazing, no contact, heavy, EI 1-1000, channel); anchoring: the "
                         "anchoring actuator (alternating sections ..., -theta, +theta, -theta, "
                         "... of --length each, pinned at its two ends, in the channel of walls "
                         "at +-height) over --sections-count x height x --pressure (default "
                         "1,3 sections x h 4.5,5.5,6.5 x the paper's 10 pressures; --theta "
                         "instead of pressures; links 140 per section unless --links gives N "
                         "over the whole actuator; no baseline: the appendix's baseline models one section); tissue: "
                         "elastic walls, the paper's pressures (theta by actuator 1's "
                         "calibration) x h 4.5,5.5,6.5 mm x wall stiffness 0.01,0.1,1,inf N/mm "
                         "per mm, in the channel; friction: the pull-out force (lcpbench."
                         "pull_out, sliders at both ends) over --friction x --pressure x "
                         "--height in the paper's channel, theta by actuator 1's calibration "
                         "(default mu 0,0.1,0.3,0.5 x 68.95,103.42,137.9,172.37 kPa x h "
                         "4.5,5.5,6.5 mm, N 140), into the store's pull_outs table")
    sw.add_argument("--friction", default=None, metavar="LIST",
                    help="--grid friction: Coulomb coefficients mu (a comma list or "
                         "A:B:STEP; 0 gives a pull-out force of 0)")
    sw.add_argument("--pressure", default=None, metavar="LIST",
                    help="--grid anchoring and friction: input pressures, kPa (A:B:STEP or a "
                         "comma list), "
                         "theta from actuator 1's calibration (eq. 40); default the paper's "
                         "17.24-172.37 kPa in 10 steps unless --theta is given")
    sw.add_argument("--sections-count", default=None, metavar="LIST",
                    help="--grid anchoring: numbers of alternating sections, odd (default "
                         "1,3: the paper's single-section model and its 3-section actuator, "
                         "in the same channel)")
    sw.add_argument("--wall-stiffness", default=None, metavar="LIST",
                    help="Winkler stiffnesses of the walls, N/mm per mm of wall; inf is "
                         "rigid (default inf; --grid tissue: 0.01,0.1,1,inf)")
    sw.add_argument("--theta", default=None, metavar="A:B:STEP",
                    help="bend angles, degrees: start:stop:step (stop included), a comma list "
                         "or one value; items may carry units: 90deg:180deg:30deg, 2.6rad "
                         "(default 10:180:10)")
    sw.add_argument("--height", default=None, metavar="A:B:STEP",
                    help="wall heights, mm, or with units: 2mm:7mm:1mm, 0.002m,0.003m "
                         "(default 2:7:1)")
    sw.add_argument("--links", default=None, metavar="LIST",
                    help=f"numbers of links (default {DEFAULT_LINKS}; --grid anchoring: "
                         f"N over the whole actuator, default {DEFAULT_LINKS} per section)")
    sw.add_argument("--EI", default=None, metavar="LIST", help="bending stiffnesses, N*mm^2 "
                    f"(default {DEFAULT_EI:g})")
    sw.add_argument("--weight", default=None, metavar="LIST",
                    help=f"weights per length, N/mm (default {DEFAULT_WEIGHT:g})")
    sw.add_argument("--length", default=None, metavar="LIST",
                    help=f"section lengths, mm (default {DEFAULT_LENGTH:g})")
    sw.add_argument("--channel", action="store_true", help="two walls, at +h and -h")
    sw.add_argument("--standard", action="store_true",
                    help="the standard run (results/sweep): every installed back-end, "
                         "--settings default,high, --baseline both, --repeat 3; the options "
                         "below still override it")
    sw.add_argument("--solvers", default=None, metavar="A,B,..",
                    help="back-ends to run, or 'all' (default: every installed one but "
                         "pgs, psor, siconos-pgs, siconos-newton-min, which are documented "
                         "never to converge on a contact step; --standard: all)")
    sw.add_argument("--settings", default=None, metavar="P,Q,..",
                    help="settings profiles among default, low, mid, high (default "
                         "default; --standard: default,high)")
    sw.add_argument("--tol", type=float, default=None, metavar="RAD",
                    help="driver tolerance of every run (default: per profile, 1e-3 for "
                         "default and low, 1e-6 mid, 1e-9 high)")
    sw.add_argument("--method", default=DEFAULT_METHOD, metavar="M[,M]",
                    help=f"outer iteration(s): globalised, newton, undamped, comma-separated "
                         f"(default {DEFAULT_METHOD})")
    sw.add_argument("--formulation", default=None, metavar="NAME|best",
                    help="the form each contact step is handed to every back-end in (gaps, "
                         "heights, lifted, reactions, angles, each also +ruiz; best: each "
                         "back-end's on the committed evidence); stored as method "
                         "DRIVER@NAME; default: each back-end's own form")
    sw.add_argument("--continuation", nargs="?", const="adaptive", default=None,
                    choices=CONTINUATION, metavar="PREDICTOR",
                    help="warm-start along theta: run each back-end over each line of "
                         "scenes (every parameter but theta equal), theta ascending, each "
                         "scene started from the extrapolation of the previous answers: "
                         "adaptive (the polynomial through up to six, of the degree where "
                         "successive degrees agree best; the default when given without a "
                         "value, as in solve_many), quadratic (the last three), secant (the line through the last two) or "
                         "previous (the last answer); stored as driver "
                         "globalised+PREDICTOR, so a cold sweep into the same store "
                         "compares with it in the report. Globalised driver only; the time "
                         "limit of a line is --time-limit per scene")
    sw.add_argument("--baseline", choices=("analytic", "fd", "both", "none"),
                    default=None,
                    help="the root-finding baseline: analytic Jacobian (default), finite "
                         "differences as fsolve would (about 2 s per scene), both "
                         "(--standard), or none")
    _add_store_options(sw)
    sw.add_argument("--no-report", action="store_true", help="do not write the report")
    sw.add_argument("--all", action="store_true",
                    help="report every run in the store (default: the runs of this sweep)")
    add_jobs_option(sw)
    sw.add_argument("--time-limit", type=float, default=DEFAULT_TIME_LIMIT, metavar="S",
                    help=f"seconds per solve before it is killed and recorded as a timeout "
                         f"(default {DEFAULT_TIME_LIMIT:g})")
    sw.add_argument("--dask", nargs="?", const="local", default=None, metavar="ADDRESS",
                    help="run the jobs on Dask distributed: a local cluster of --jobs "
                         "workers, or the scheduler at ADDRESS (tcp://HOST:PORT); each task "
                         "runs its jobs in the pool's isolated worker with the time limit "
                         "(pip install 'lcpbench[cluster]')")
    sw.add_argument("--repeat", type=int_arg, default=None, metavar="K",
                    help=f"solves timed per run: a converged run's times are the median of "
                         f"K, their spread is stored (default {MAIN_JOB['repeat']}; "
                         f"--standard: {DEFAULT_REPEAT})")
    sw.add_argument("--rerun", action="store_true",
                    help="recompute runs that are already in the store")
    sw.add_argument("--quiet", action="store_true", help="no progress bar")
    sw.add_argument("--wait", action="store_true",
                    help="wait for another sweep on the same store to finish (default: exit 2 "
                         "and say who holds it)")
    sw.set_defaults(func=cmd_sweep)

    rp = subparsers.add_parser(
        "report", help="tables, CSV and figures from a results store",
        description="Build the comparison tables, the paper's Table II, the CSV of every "
                    "run and the figures from the store alone (nothing is solved).")
    _add_store_options(rp)
    rp.add_argument("--table2-height", type=float, default=None, metavar="MM",
                    help="wall height of the Table II-style table (default: the smallest)")
    rp.add_argument("--no-plots", action="store_true", help="tables and CSV only")
    rp.add_argument("--all", action="store_true",
                    help="report every run in the store (default: the runs of the last "
                         "`lcpbench sweep` into it: its grid, back-ends and settings)")
    rp.add_argument("--format", choices=("lcpbench", "qpbenchmark"), default="lcpbench",
                    help="qpbenchmark: only qpbenchmark_results.csv, every run in "
                         "qpbenchmark's results schema (default: the full report)")
    rp.set_defaults(func=cmd_report)

    se = subparsers.add_parser(
        "select", help="the fastest back-end that meets an accuracy on this kind of scene",
        description="Probe every installed back-end and settings profile on four scenes of "
                    "this kind (N, length, EI, w, channel), cache the runs in the store, and "
                    "print the fastest one whose total-force error is within --force-tol on all of "
                    "them.")
    se.add_argument("--force-tol", type=float, default=1e-6, metavar="REL",
                    help="largest relative error of the total force (default 1e-6)")
    se.add_argument("--time-budget", type=float, default=None, metavar="S",
                    help="largest mean time of one solve, seconds (default: none)")
    add_scene_options(se)
    se.add_argument("--solvers", default="all", metavar="A,B,..",
                    help="candidate back-ends (default: every installed one)")
    se.add_argument("--store", default=None, metavar="PATH",
                    help=f"where the probes are cached (default $LCPBENCH_STORE or "
                         f"{DEFAULT_STORE})")
    se.add_argument("--repeat", type=int_arg, default=3, metavar="K",
                    help="timings of each converged probe run, its time their median "
                         "(default 3)")
    se.add_argument("--evidence", action="append", default=None, metavar="CSV|none",
                    help="runs.csv of an earlier sweep whose failures rule candidates out "
                         "before probing (default: the committed results/sweep/runs.csv "
                         "when present; 'none': only the store's own runs)")
    se.add_argument("--formulation", default=None, metavar="NAME|best",
                    help="the form every candidate's contact steps are probed in (gaps, "
                         "heights, lifted, reactions, angles, each also +ruiz; best: each "
                         "back-end's on the committed evidence, docs/formulations.md); "
                         "default: each back-end's own form")
    add_jobs_option(se)
    add_json_option(se, "the selection as JSON")
    se.add_argument("--quiet", action="store_true", help="no progress bar")
    se.set_defaults(func=cmd_select)


# -- sweep --------------------------------------------------------------------
def _positive_number(value, name) -> float:
    if not (math.isfinite(value) and value > 0):
        raise ProblemError(f"{name} must be a number > 0, got {value:g}")
    return value


def _apply_preset(args) -> None:
    """Fill the options not given from the main job, or from the standard run."""
    preset = STANDARD_RUN if args.standard else MAIN_JOB
    for name, value in preset.items():
        if getattr(args, name) is None:
            setattr(args, name, value)


def sweep_backends(args) -> tuple[list[str], list[str]]:
    """The back-ends and settings profiles of ``--solvers`` and ``--settings``, checked."""
    from ..bench.expected import never_converges
    from ..solvers.registry import available_backends, get_backend, get_settings

    if args.solvers.strip() == "all":
        solvers = available_backends()
    elif args.solvers == "main":  # the main job's default, not a name a user types
        solvers = [b for b in available_backends() if never_converges(b) is None]
    else:
        solvers = names_list(args.solvers)
        if not solvers:
            raise ProblemError("solvers must list at least one back-end, or be 'all'")
        for name in solvers:
            get_backend(name)  # unknown or not installed: SolverNotFound, exit 2
    settings = names_list(args.settings)
    if not settings:
        raise ProblemError("settings must list at least one of default, low, mid, high")
    for p in settings:
        get_settings(p)
    return solvers, settings


def cmd_sweep(args) -> int:
    """``lcpbench sweep``: run the grid into the store, then write the report."""
    from ..api import check_tol
    from ..bench.jobs import LineJob, ReferenceJob
    from ..bench.store import Store
    from ..bench.sweep import plan_sweep, sweep

    if args.grid == "friction":
        from ._sweep_friction import sweep_friction

        return sweep_friction(args)
    if args.friction is not None:
        raise ProblemError("--friction is for --grid friction")
    if args.grid == "anchoring":
        if args.baseline not in (None, "none"):
            raise ProblemError("--grid anchoring has no baseline: the appendix's root-finding "
                               "baseline models one section (use --baseline none)")
        if args.continuation is not None:
            raise ProblemError("--continuation runs along theta of one-section grids; not "
                               "with --grid anchoring")
        args.baseline = "none"
    _apply_preset(args)
    scenes = sweep_scenes(args)
    methods = [m.strip() for m in args.method.split(",") if m.strip()]
    if args.continuation is not None and "undamped" in methods:
        raise ProblemError("--continuation needs the globalised driver; it cannot be used "
                           "with --method undamped")
    solvers, settings = sweep_backends(args)
    if args.tol is not None:
        check_tol(args.tol)
    jobs_n = worker_count(args.jobs, args.oversubscribe)
    limit = _positive_number(args.time_limit, "time-limit")
    if args.repeat < 1:
        raise ProblemError(f"repeat must be an integer >= 1, got {args.repeat}")
    runner = None
    if args.dask is not None:
        import importlib.util

        from ..bench.cluster import dask_runner

        if importlib.util.find_spec("distributed") is None:
            raise ProblemError("--dask needs Dask distributed: pip install "
                               "'lcpbench[cluster]'")
        runner = dask_runner(args.dask)
    baselines = {"analytic": ["baseline"], "fd": ["baseline-fd"],
                 "both": ["baseline", "baseline-fd"], "none": []}[args.baseline]
    jobs = plan_sweep(scenes, solvers, settings, tol=args.tol, method=methods,
                      baselines=baselines, continuation=args.continuation,
                      repeat=args.repeat, formulation=args.formulation)
    planned = {k for j in jobs if not isinstance(j, ReferenceJob) for k in j.keys}
    with Store(args.store) as store, store.lock("lcpbench sweep", wait=args.wait) as sweep_id:
        store.put_plan(sweep_id, planned)  # what `lcpbench report` covers by default
        _print_backends(solvers, explicit=args.solvers.strip() not in ("all", "main"),
                        main_job=args.solvers == "main")
        if not args.standard:
            print(f"settings {args.settings}, baseline {args.baseline}, each run timed "
                  f"{args.repeat}x (the main job's defaults where not given); the standard "
                  "run (every back-end, settings default,high, both baselines, times the "
                  "median of 3) is `lcpbench sweep --standard`", file=sys.stderr)
        bar = progress_bar(args.quiet, None if args.quiet else
                           _phase_sizes(store, jobs, args.rerun))
        try:
            plan = sweep(store, jobs, workers=jobs_n, time_limit=limit, rerun=args.rerun,
                         progress=bar.update if bar else None, runner=runner)
        except KeyboardInterrupt:
            if bar:
                bar.close()
            error_line(f"interrupted: {store.count()} runs are safe in {args.store}; run the "
                       "same command again to resume")
            return 130
        if bar:
            bar.close()
        lines = sum(isinstance(j, LineJob) for j in jobs) // max(1, len(solvers) * len(settings))
        along = (f" by {args.continuation} continuation along {lines} line(s) in theta"
                 if args.continuation else "")
        mine = store.count(sweep_id=sweep_id)
        refs = sum(j.size for j in jobs if isinstance(j, ReferenceJob))
        refs_new = sum(j.size for j in plan.todo if isinstance(j, ReferenceJob))
        print(f"{mine} runs computed by this sweep, {plan.rows_done - (refs - refs_new)} "
              f"already in {args.store}; references: {refs_new} computed, "
              f"{refs - refs_new} already in the store "
              f"({len(scenes)} scenes x {len(solvers)} back-ends x {len(settings)} settings"
              f"{f' x {len(methods)} drivers' if len(methods) > 1 else ''}{along}"
              f" + {len(baselines)} baseline(s) + references; {jobs_n} worker(s), "
              + (f"times the median of {args.repeat})" if args.repeat > 1
                 else "each run timed once)"), flush=True)
        if not args.no_report:
            print("writing the report ...", file=sys.stderr, flush=True)
            return _write_report(store, args.out, limit, None, plots=True,
                                 keys=None if args.all else planned)
    return 0


def _phase_sizes(store, jobs, rerun: bool) -> dict[str, int]:
    """Rows still to compute per progress phase (references, runs)."""
    from ._common import phase_of

    have_runs = set() if rerun else store.run_keys()
    have_refs = set() if rerun else store.ref_keys()
    sizes: dict[str, int] = {"references": 0, "runs": 0}
    for j in jobs:
        if not j.is_stored(have_runs, have_refs):
            sizes[phase_of(j)] += j.size
    return sizes


def _print_backends(solvers: list[str], explicit: bool, main_job: bool = False) -> None:
    """Say which back-ends the sweep runs and which it skips, and why (stderr)."""
    from ..bench.expected import never_converges
    from ..solvers.registry import backends

    print(f"running {len(solvers)} back-end(s): {', '.join(solvers)}", file=sys.stderr)
    others = [name for name in backends() if name not in solvers]
    if explicit:  # the user chose: one line, not a reason per back-end left out
        if others:
            print(f"({len(others)} other back-end(s) not in --solvers)", file=sys.stderr)
        return
    skipped: dict[str, list[str]] = {}
    for name, b in backends().items():
        if name not in solvers:
            why = (f"not installed ({b.install_hint()})" if not b.available() else
                   "documented never to converge on a contact step (cond(K) ~ 1e8), left "
                   "out of the main job; --standard or --solvers all runs them"
                   if main_job and never_converges(name) else "")
            skipped.setdefault(why, []).append(name)
    for why, names in skipped.items():
        print(f"skipping {', '.join(names)}" + (f": {why}" if why else ""), file=sys.stderr)


# -- report -------------------------------------------------------------------
def _write_report(store, out, time_limit, table2_height, plots: bool, keys=None) -> int:
    from ..bench.report import build_report, default_out

    out = out if out is not None else default_out(store.path)

    if plots and not has_matplotlib():
        plots = False
        print("matplotlib is not installed: tables only (pip install 'lcpbench[plot]')",
              file=sys.stderr)
    try:
        info = build_report(store, out, time_limit=time_limit, plots=plots,
                            table2_height=table2_height, keys=keys)
    except OSError as exc:
        raise ProblemError(f"out {out}: cannot write the report there ({exc})") from exc
    also = (f" (of {info['stored']} in the store; --all for all)"
            if info["stored"] != info["runs"] else "")
    print(f"report of {info['runs']} runs{also} in {info['out']}/report.md")
    return 0


def cmd_report(args) -> int:
    """``lcpbench report``: tables, CSV and figures from the store alone."""
    from ..bench.store import Store

    with Store(args.store, create=False) as store:
        if args.format == "qpbenchmark":
            return _write_qpbenchmark(store, args.out)
        plan = None if args.all else store.last_plan()
        if plan is not None:
            print(f"reporting the runs of the last sweep (started {plan[1]}); --all for "
                  "every run in the store", file=sys.stderr)
        elif not args.all:
            print("no sweep plan recorded in this store: reporting every run in it",
                  file=sys.stderr)
        return _write_report(store, args.out, DEFAULT_TIME_LIMIT, args.table2_height,
                             plots=not args.no_plots, keys=None if plan is None else plan[2])


def _write_qpbenchmark(store, out) -> int:
    """``report --format qpbenchmark``: the runs in qpbenchmark's results CSV."""
    from pathlib import Path

    from ..bench.report import default_out
    from ..bench.testset import SWEEP_RESULTS, run_result_rows, write_results

    folder = Path(out if out is not None else default_out(store.path))
    rows = run_result_rows(store.runs(arrays=False))
    try:
        folder.mkdir(parents=True, exist_ok=True)
        write_results(rows, folder / SWEEP_RESULTS)
    except OSError as exc:
        raise ProblemError(f"out {folder}: cannot write there ({exc})") from exc
    print(f"{len(rows)} runs in qpbenchmark's results schema in {folder / SWEEP_RESULTS}")
    return 0


# -- select -------------------------------------------------------------------
def _evidence(values: list[str] | None) -> list[str] | None:
    """``--evidence``: None (the default files), [] for 'none', else the files (must exist)."""
    import os

    if values is None:
        return None
    if any(v.strip().lower() == "none" for v in values):
        return []
    for v in values:
        if not os.path.isfile(v):
            raise ProblemError(f"--evidence must be a runs.csv file or 'none', got {v!r} "
                               "(no such file)")
    return list(values)


def _select_store(store: str | None) -> str:
    """``--store`` of ``select``: given, else ``$LCPBENCH_STORE``, else the default store
    (the command caches its probes on disk; the API keeps them in memory)."""
    import os

    from ..bench.select import STORE_ENV

    return store or os.environ.get(STORE_ENV) or str(DEFAULT_STORE)


def cmd_select(args) -> int:
    """``lcpbench select``: 0 with a back-end that meets ``--force-tol``, 1 with none."""
    from ..bench.select import select_backend

    scene = scene_from(args, resolve_links=False)
    if scene.links == "auto":
        raise ProblemError("links must be a number for select (the kind of scene is N, "
                           "length, EI, w and channel)")
    candidates = None if args.solvers.strip() == "all" else [
        x.strip() for x in args.solvers.split(",") if x.strip()]
    workers = worker_count(args.jobs, args.oversubscribe)
    bar = progress_bar(args.quiet)
    try:
        sel = select_backend(scene, force_tol=args.force_tol, time_budget=args.time_budget,
                             store=_select_store(args.store), candidates=candidates, workers=workers,
                             progress=bar.update if bar else None, repeat=args.repeat,
                             evidence=_evidence(args.evidence),
                             formulation=args.formulation)
    finally:
        if bar:
            bar.close()
    if args.json:
        print_json(sel.to_dict())
    elif sel.backend is None:
        print(f"no back-end: {sel.reason}")
    else:
        # the options of `lcpbench solve` that run it as selected: the profile's ε, and the
        # driver tol the probes ran at (the accuracy's, not the profile's)
        form = f" --formulation {sel.formulation}" if sel.formulation else ""
        print(f"--solver {sel.backend} --settings {sel.settings} --tol {sel.driver_tol:g}"
              f"{form}: {sel.reason}")
    return 0 if sel.backend is not None else 1
