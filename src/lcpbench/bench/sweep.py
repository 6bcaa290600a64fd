"""The sweep: scenes × back-ends × settings (+ the baseline) into the store.

A sweep is a list of typed jobs (:mod:`.jobs`), planned by :func:`plan_sweep`.
Each job runs in a worker process with a time limit (:mod:`.pool`): a
back-end that hangs is killed and costs ``timeout`` rows, one that crashes
its process costs ``crashed`` rows, and the sweep goes on. Only the parent
writes to the store, one committed row at a time, so a sweep killed at any
moment restarts where it stopped (jobs whose rows are already in the store
are skipped).

The driver tolerance of a run follows its settings profile unless given
(:data:`~.jobs.PROFILE_TOL`): a profile is a target accuracy for the whole
solve, not only for the contact step.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from ..errors import ProblemError
from .grid import Grid, scene_key
from .jobs import (
    BASELINES,
    DEFAULT_TIME_LIMIT,
    PROFILE_TOL,
    BaselineJob,
    Job,
    LineJob,
    ReferenceJob,
    RunJob,
)
from .pool import run_jobs
from .rows import scene_columns
from .store import Store

#: predictors of a continuation sweep (studies.continuation); the rows' method is
#: "globalised+<predictor>"
CONTINUATION = ("adaptive", "quadratic", "secant", "previous")

__all__ = ["CONTINUATION", "DEFAULT_TIME_LIMIT", "SweepPlan", "default_workers",
           "plan_sweep", "sweep"]


@dataclass
class SweepPlan:
    """The jobs of a sweep, split into what is stored already and what is left.

    ``done`` and ``todo`` count jobs; a line job is several rows, so
    ``rows``, ``rows_done`` and ``rows_todo`` count rows (store entries).
    """

    jobs: list[Job]
    todo: list[Job] = field(default_factory=list)

    @property
    def done(self) -> int:
        return len(self.jobs) - len(self.todo)

    @property
    def rows(self) -> int:
        return sum(j.size for j in self.jobs)

    @property
    def rows_todo(self) -> int:
        return sum(j.size for j in self.todo)

    @property
    def rows_done(self) -> int:
        return self.rows - self.rows_todo


def _lines(scenes: list) -> list[list]:
    """Scenes grouped into lines: equal in every parameter but θ, θ ascending.

    Lines come in the order of their first scene; repeated scenes are dropped.
    """
    groups: dict[str, dict] = {}
    for s in scenes:
        key = scene_key(s)
        rest = json.loads(key)
        rest.pop("theta")
        groups.setdefault(json.dumps(rest, sort_keys=True), {}).setdefault(key, s)
    return [sorted(g.values(), key=lambda s: s.theta) for g in groups.values()]


def plan_sweep(grid: Grid | Iterable, backends: list[str], settings: list[str], *,
               tol: float | None = None, method: str | Iterable[str] = "globalised",
               baselines: Iterable[str] = ("baseline",),
               continuation: str | None = None, repeat: int = 1,
               formulation: str | None = None) -> list[Job]:
    """Every job of a sweep, in a fixed order: references, then scene by scene.

    ``method`` is one driver scheme or several (each back-end runs with each).
    ``continuation`` ("adaptive", "quadratic", "secant" or "previous"): the back-end runs become line
    jobs, one per back-end × settings and per line of scenes (all parameters
    but θ equal, θ ascending), run after the references; method
    "globalised+<continuation>". It needs the globalised driver only.
    ``repeat``: solves timed per run (back-ends and baselines; a converged
    run's times are the median of ``repeat``, the spread is stored).
    ``formulation``: the contact step's form for every back-end run
    (:mod:`lcpbench.model.formulations`; "best": each back-end's, resolved here), stored
    in the method as ``driver@formulation``; a back-end's own form is the plain run.
    """
    from ..model.formulations import resolve_formulation
    from ..model.outer import METHODS
    from ..solvers.registry import get_backend

    forms = {(name, p): resolve_formulation(get_backend(name), formulation, p)
             for name in backends for p in settings} if formulation is not None else {}
    if forms and continuation is not None:
        raise ProblemError("--formulation runs single solves; not with --continuation")

    methods = [method] if isinstance(method, str) else list(method)
    for m in methods:
        if m not in METHODS:
            raise ProblemError(f"method must be among {', '.join(METHODS)}, got {m!r}")
    if continuation is not None:
        if continuation not in CONTINUATION:
            raise ProblemError(f"continuation must be one of {', '.join(CONTINUATION)}, got "
                               f"{continuation!r}")
        if set(methods) != {"globalised"}:
            raise ProblemError("--continuation needs the globalised driver: a warm start "
                               "is not defined for --method undamped")
    if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
        raise ProblemError(f"repeat must be an integer >= 1, got {repeat!r}")
    scenes = grid.scenes() if isinstance(grid, Grid) else list(grid)
    if not scenes:
        raise ProblemError("the grid is empty: no scenes to run")
    for b in baselines:
        if b not in BASELINES:
            raise ProblemError(f"baseline must be one of {', '.join(BASELINES)}, got {b!r}")
    keys = list(dict.fromkeys(scene_key(s) for s in scenes))
    jobs: list[Job] = [ReferenceJob(k) for k in keys]
    if continuation is not None:
        for line in _lines(scenes):
            line_keys = tuple(scene_key(s) for s in line)
            for name in backends:
                for p in settings:
                    jobs.append(LineJob(line_keys[0], name, p,
                                        PROFILE_TOL[p] if tol is None else tol,
                                        predictor=continuation, scenes=line_keys,
                                        repeat=repeat))
    for k in keys:
        # the appendix's root-finding baseline knows rigid walls only: none for elastic ones
        for b in baselines if '"wall_stiffness"' not in k else ():
            jobs.append(BaselineJob(k, b, repeat=repeat))
        if continuation is not None:
            continue
        for m in methods:
            for name in backends:
                for p in settings:
                    form = forms.get((name, p))
                    jobs.append(RunJob(k, name, p, PROFILE_TOL[p] if tol is None else tol,
                                       driver=m, repeat=repeat,
                                       formulation=None if form is None else str(form)))
    return jobs


def _versions(names: Iterable[str]) -> dict[str, str]:
    """The version of each back-end's library (scipy's for the baselines)."""
    import scipy

    from .. import __version__
    from ..solvers.registry import get_backend

    return {n: (f"scipy {scipy.__version__}" if n in BASELINES
                else f"lcpbench {__version__}" if n == "reference"
                else get_backend(n).version() or "?") for n in names}


def sweep(store: Store, jobs: list[Job], *, workers: int = 1,
          time_limit: float = DEFAULT_TIME_LIMIT, rerun: bool = False,
          progress: Callable[[int, int, Job, dict], None] | None = None,
          runner: Callable | None = None) -> SweepPlan:
    """Run the jobs that are not in ``store`` yet (all of them with ``rerun``).

    Every finished row is committed at once. ``progress(done, total, job,
    row)`` is called after each stored row, with ``done`` and ``total``
    counting rows (a line job is one row per scene; it is then passed with
    ``scene`` set to that row's scene). A line job is skipped only when all
    its rows are stored; a partly stored line is run again in full and its
    rows replaced. A job that failed as a whole (error, timeout, crash)
    stores failure rows only where nothing is stored yet. ``runner``: what
    runs the jobs, :func:`~.pool.run_jobs` (the local pool) by default, or
    :func:`~.cluster.dask_runner`'s. Returns the plan (what was skipped and run).
    """
    have_runs = set() if rerun else store.run_keys()
    have_refs = set() if rerun else store.ref_keys()
    todo = [j for j in jobs if not j.is_stored(have_runs, have_refs)]
    plan = SweepPlan(jobs, todo)
    versions = _versions({j.backend for j in todo})
    done, total = plan.rows_done, plan.rows
    record = None
    if store.sweep_id is not None:  # a locked sweep: its machine record, start and end
        from .machine import load_average, machine_record

        record = machine_record(workers=workers, repeat=max((j.repeat for j in todo),
                                                            default=1))
        store.put_machine(store.sweep_id, record)
    for job, result in (runner or run_jobs)(todo, workers=workers, time_limit=time_limit):
        created = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        # a finished line replaces every row of the line (the continuation made
        # them together); a failed job leaves stored rows alone
        replace = rerun or (result.complete and job.size > 1)
        entries = [(scene, row) for scene, store_key, row
                   in zip(job.scene_keys, job.keys, result.rows)
                   if result.complete or store_key not in have_runs]
        done += job.size - len(entries)  # stored rows a failed line left alone
        for scene, row in entries:
            row.update(scene_columns(scene))
            row["created"] = created
            row.update(job.identity(scene, versions))
            job.put(store, row, replace)
            done += 1
            if progress is not None:
                progress(done, total, job if scene == job.scene else
                         dataclasses.replace(job, scene=scene), row)
    if record is not None and store.sweep_id is not None:
        record["load_end"] = load_average()
        store.put_machine(store.sweep_id, record)
    return plan


def default_workers() -> int:
    """Both cores of a 2-core machine; at most 4 by default."""
    return max(1, min(4, os.cpu_count() or 1))
