"""The sweep harness: scenes × back-ends × settings (+ the baseline) into the store.

A sweep is a list of jobs. Each job runs in a worker process with a time
limit: a back-end that hangs is killed and costs one ``timeout`` row, one
that crashes its process costs one ``crashed`` row, and the sweep goes on.
Only the parent writes to the store, one committed row per finished job, so
a sweep killed at any moment restarts where it stopped (jobs whose rows are
already in the store are skipped).

Kinds of job
------------
``ref``       the per-scene reference: the built-in active set at settings
              ``high`` and driver tolerance :data:`REFERENCE_TOL`, checked by
              re-solving its last contact step with Lemke (a different
              algorithm on the dense condensed LCP); computed once per scene.
``run``       ``lcpbench.solve(scene, solver=backend, settings=..., tol=...)``.
``baseline``  the paper's root-finding baseline (Appendix A) with an analytic
              (``baseline``) or finite-difference (``baseline-fd``) Jacobian.
``line``      continuation (``--continuation``): one back-end × settings × tol
              over a line of scenes that differ only in θ, θ ascending, solved
              in order by :func:`~lcpbench.studies.continuation.solve_sequence`,
              each scene started from its predecessors' answers. One row per
              scene, method ``globalised+quadratic`` (or ``+secant``,
              ``+previous``), so they
              never mix with the cold runs in the store.

The driver tolerance of a run follows its settings profile unless given
(:data:`PROFILE_TOL`): a profile is a target accuracy for the whole solve,
not only for the contact step.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pickle
import struct
import subprocess
import sys
import time
import traceback
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from multiprocessing.connection import wait

import numpy as np

from ..errors import ProblemError
from .grid import Grid, scene_from_key, scene_key
from .store import Store

#: driver tolerance (rad) per settings profile; "default" keeps the paper's 1e-3
PROFILE_TOL = {"default": 1e-3, "low": 1e-3, "mid": 1e-6, "high": 1e-9}
REFERENCE_TOL = 1e-11  # rad, driver tolerance of the reference
#: the baselines: (Jacobian, MINPACK method). With finite differences Powell's
#: hybrid method (fsolve's default, "hybr") fails at N = 140 on every scene of
#: the paper grid tried (24 of 24 at h = 4-6 mm), so "baseline-fd" is
#: Levenberg-Marquardt (fsolve's other algorithm), which converges, slowly.
BASELINES = {"baseline": ("analytic", "hybr"), "baseline-fd": ("fd", "lm")}
BASELINE_TOL = 1e-10
DEFAULT_TIME_LIMIT = 60.0  # s per job (per scene for a line)
#: predictors of a continuation sweep (bench.continuation); the rows' method is
#: "globalised+<predictor>"
CONTINUATION = ("quadratic", "secant", "previous")


@dataclass(frozen=True)
class Job:
    """One unit of work: a reference, a run of a back-end, a baseline solve, or a
    line of scenes solved by continuation (``kind="line"``: ``scenes`` holds the
    line's scene keys in order, ``scene`` the first of them, ``method``
    "globalised+<predictor>").
    """

    kind: str  # "ref", "run", "baseline" or "line"
    scene: str  # scene_key (a line: its first scene)
    backend: str = "active-set"
    settings: str = "-"
    tol: float = 0.0
    method: str = "globalised"
    scenes: tuple[str, ...] = ()  # a line's scene keys, θ ascending

    @property
    def key(self) -> tuple:
        return (self.scene, self.backend, self.settings, self.tol, self.method)

    @property
    def keys(self) -> list[tuple]:
        """The store key of every row the job writes (one, or one per scene of a line)."""
        if self.kind != "line":
            return [self.key]
        return [(s, self.backend, self.settings, self.tol, self.method) for s in self.scenes]

    @property
    def size(self) -> int:
        """How many rows the job writes."""
        return len(self.scenes) if self.kind == "line" else 1


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


def continuation_method(predictor: str) -> str:
    """The method label of a continuation run: "globalised+secant" and the like."""
    return f"globalised+{predictor}"


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
               continuation: str | None = None) -> list[Job]:
    """Every job of a sweep, in a fixed order: references, then scene by scene.

    ``method`` is one driver scheme or several (each back-end runs with each).
    ``continuation`` ("quadratic", "secant" or "previous"): the back-end runs become line
    jobs, one per back-end × settings and per line of scenes (all parameters
    but θ equal, θ ascending), run after the references; method
    "globalised+<continuation>". It needs the globalised driver only.
    """
    from ..model.driver import METHODS

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
    scenes = grid.scenes() if isinstance(grid, Grid) else list(grid)
    if not scenes:
        raise ProblemError("the grid is empty: no scenes to run")
    for b in baselines:
        if b not in BASELINES:
            raise ProblemError(f"baseline must be one of {', '.join(BASELINES)}, got {b!r}")
    keys = list(dict.fromkeys(scene_key(s) for s in scenes))
    jobs = [Job("ref", k, "reference", "high", REFERENCE_TOL, "globalised") for k in keys]
    if continuation is not None:
        label = continuation_method(continuation)
        for line in _lines(scenes):
            line_keys = tuple(scene_key(s) for s in line)
            for name in backends:
                for p in settings:
                    jobs.append(Job("line", line_keys[0], name, p,
                                    PROFILE_TOL[p] if tol is None else tol, label,
                                    line_keys))
    for k in keys:
        for b in baselines:
            jobs.append(Job("baseline", k, b, "-", BASELINE_TOL, BASELINES[b][1]))
        if continuation is not None:
            continue
        for m in methods:
            for name in backends:
                for p in settings:
                    jobs.append(Job("run", k, name, p,
                                    PROFILE_TOL[p] if tol is None else tol, m))
    return jobs


# -- what a worker does ---------------------------------------------------------------
def execute(job: Job, time_limit: float | None = None) -> dict | list[dict]:
    """Run one job and return its row for the store (never raises).

    A line job returns a list of rows, one per scene in order, or one failure
    row (a dict) for the whole line if it raised.
    """
    t0 = time.perf_counter()
    try:
        if job.kind == "line":
            return _line(job)
        scene = scene_from_key(job.scene)
        if job.kind == "ref":
            row = _reference(scene)
        elif job.kind == "baseline":
            row = _baseline(scene, job, time_limit)
        else:
            row = _run(scene, job)
    except Exception as exc:  # a back-end that raises costs one row, not the sweep
        row = failed_row("error", f"{type(exc).__name__}: {exc}",
                         time.perf_counter() - t0)
        row["traceback"] = traceback.format_exc(limit=5)
    return row


def _solution_row(res) -> dict:
    cert = res.certificate.to_dict()
    cert.pop("torque_residual", None)
    return {
        "status": "solved" if res.converged else "not_converged",
        "converged": bool(res.converged),
        "reason": res.reason,
        "total_force": float(res.total_force),
        "outer_iterations": int(res.outer_iterations),
        "inner_iterations": int(res.inner_iterations),
        "wall_time": float(res.time_s),
        "solver_time": float(sum(s.solve_time for s in res.steps)),
        "certificate": cert,
        "forces": res.forces, "gaps": res.gaps, "x": res.x, "y": res.y,
    }


_WARM: set[tuple[str, str]] = set()
WARMUP_SCENE = {"theta": 150.0, "height": 3.0, "links": 20}


def warm_up(backend: str, settings: str) -> None:
    """One untimed solve of a small scene per (back-end, settings) and process.

    The first call of a back-end pays for importing its library, JIT and
    caches (cvxpy's first solve took 0.5 s more than its second); a benchmark
    of the solve must not charge that to the first scene of the grid.
    """
    if (backend, settings) in _WARM:
        return
    _WARM.add((backend, settings))
    from ..api import solve
    from ..problems.scenes import ActuatorScene

    try:
        solve(ActuatorScene(**WARMUP_SCENE), solver=backend, settings=settings)
    except Exception:  # noqa: BLE001 - the timed run will report it
        pass


def _run(scene, job: Job) -> dict:
    from ..api import solve

    warm_up(job.backend, job.settings)
    res = solve(scene, solver=job.backend, tol=job.tol, settings=job.settings,
                method=job.method)
    return _solution_row(res)


def _line(job: Job) -> list[dict]:
    """A line of scenes by continuation: one row per scene, each its own solve's numbers.

    ``wall_time`` and the iterations of a row are those of the scene's own
    solve inside the line (``ContactResult.time_s``), as for a cold run.
    """
    from ..studies.continuation import solve_sequence

    predictor = job.method.split("+", 1)[1]
    warm_up(job.backend, job.settings)
    scenes = [scene_from_key(k) for k in job.scenes]
    results = solve_sequence(scenes, predictor=predictor, solver=job.backend, tol=job.tol,
                             settings=job.settings, method="globalised")
    rows = []
    for res in results:
        row = _solution_row(res)
        row["continuation"] = res.extra.get("continuation", "?")  # not a store column
        # a warm start that failed and was redone cold: its work counts too
        lost = res.extra.get("discarded")
        if lost:
            row["outer_iterations"] += int(lost["outer_iterations"])
            row["inner_iterations"] += int(lost["inner_iterations"])
            row["wall_time"] += float(lost["time_s"])
            row["reason"] += f" (after a failed warm start: {lost['reason']})"
        rows.append(row)
    return rows


def _reference(scene) -> dict:
    from ..api import solve
    from ..model.step import assemble_step
    from ..model.step_solver import solve_step

    res = solve(scene, solver="active-set", tol=REFERENCE_TOL, settings="high")
    tol = REFERENCE_TOL
    if not res.converged:  # round-off can stop the tightest tolerance: relax, and say so
        for tol in (1e-10, 1e-9, 1e-8):
            res = solve(scene, solver="active-set", tol=tol, settings="high")
            if res.converged:
                break
    row = _solution_row(res)
    row["tol"] = tol
    # The check: the last contact step again, by Lemke on the dense condensed LCP.
    check = float("nan")
    if res.converged:
        step = assemble_step(scene.with_links(res.links).chain(), res.alpha)
        sol = solve_step(step, "lemke", "high")
        if sol.solved:
            scale = max(abs(res.total_force), scene.EI / scene.length**2)
            check = abs(float(sol.reaction_upper.sum()) - res.total_force) / scale
    row["check_error"] = check
    return row


def _baseline(scene, job: Job, time_limit) -> dict:
    from ..baseline import solve_baseline

    if ("baseline", "") not in _WARM:
        _WARM.add(("baseline", ""))
        solve_baseline(scene.with_links(WARMUP_SCENE["links"]), tol=job.tol)
    res = solve_baseline(scene, tol=job.tol, method=job.method,
                         jacobian=BASELINES[job.backend][0], time_limit=time_limit)
    chain = scene.chain()
    gaps = chain.wall - res.y[chain.free_nodes]
    return {
        "status": "solved" if res.valid else _BASELINE_STATUS.get(
            str(res.status).split(":")[0], "not_converged"),
        "converged": bool(res.valid),
        "reason": res.message,
        "total_force": float(res.total_force) if res.valid else 0.0,
        "outer_iterations": int(res.iterations),
        "inner_iterations": int(res.jacobian_evaluations),
        "wall_time": float(res.time_s + res.setup_time_s),
        "solver_time": float(res.time_s),
        "certificate": {"max_penetration": res.max_penetration, "closure": res.closure,
                        "residual_norm": res.residual_norm,
                        "relative_torque_residual": res.relative_torque_residual},
        "forces": res.forces, "gaps": gaps, "x": res.x, "y": res.y,
    }


_BASELINE_STATUS = {"bad solution": "invalid", "no convergence": "not_converged",
                    "max evaluations": "max_iterations", "time limit": "timeout",
                    "diverged": "diverged"}


def failed_row(status: str, reason: str, wall_time: float) -> dict:
    """The row of a job that produced no answer (error, timeout, crash)."""
    return {"status": status, "converged": False, "reason": reason, "total_force": 0.0,
            "outer_iterations": 0, "inner_iterations": 0, "wall_time": float(wall_time),
            "solver_time": float("nan"), "certificate": None}


# -- the worker pool --------------------------------------------------------------------
# Workers are plain subprocesses (`python -m lcpbench.bench.harness`), not
# multiprocessing children: nothing of the caller's __main__ is re-imported,
# and a worker killed at its time limit takes nothing else with it. Jobs and
# rows travel as length-prefixed pickles on the worker's stdin and on a copy
# of its stdout; the worker's own fd 1 is pointed at stderr, so solver
# libraries that print cannot corrupt the protocol.
def _send(fh, obj) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    fh.write(struct.pack("<Q", len(data)) + data)
    fh.flush()


def _recv(fh):
    head = fh.read(8)
    if len(head) < 8:
        raise EOFError("worker closed its pipe")
    (size,) = struct.unpack("<Q", head)
    data = fh.read(size)
    if len(data) < size:
        raise EOFError("worker closed its pipe mid-message")
    return pickle.loads(data)


def _die_with_parent() -> None:
    """Linux: have the kernel SIGKILL this worker when the sweep process dies.

    Without it a worker of a killed sweep finishes (or hangs in) its current
    job before it notices the closed pipe.
    """
    import ctypes
    import signal

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL))  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # not Linux: the closed pipe still ends the worker
        pass
    if os.getppid() == 1:  # the parent died before prctl took effect
        os._exit(0)


def _worker_main() -> None:
    import signal

    _die_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    inp = sys.stdin.buffer
    while True:
        try:
            msg = _recv(inp)
        except EOFError:
            return
        if msg is None:
            return
        job, time_limit = msg
        row = execute(job, time_limit)
        try:
            _send(out, row)
        except (BrokenPipeError, OSError):  # the parent is gone
            return


#: One BLAS/OpenMP thread per worker: the sweep's parallelism is its processes.
#: Threaded BLAS in two workers on two cores oversubscribes them (Siconos's
#: Newton-min ran 4x slower), and the thread count changes the rounding, so
#: fixing it also makes a parallel sweep give the same numbers as a serial one.
SINGLE_THREAD = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                 "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")


def worker_environment() -> dict:
    env = dict(os.environ)
    env.update({k: "1" for k in SINGLE_THREAD})
    return env


class _Worker:
    def __init__(self):
        stderr = None if os.environ.get("LCPBENCH_WORKER_STDERR") else subprocess.DEVNULL
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "lcpbench.bench.harness"], env=worker_environment(),
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr)
        self.job: Job | None = None
        self.started = 0.0

    def give(self, job: Job, time_limit: float) -> None:
        self.job, self.started = job, time.monotonic()
        _send(self.proc.stdin, (job, time_limit))

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        for fh in (self.proc.stdin, self.proc.stdout):
            try:
                fh.close()
            except OSError:
                pass

    def stop(self) -> None:
        """A clean exit for an idle worker (killed if it does not go)."""
        try:
            _send(self.proc.stdin, None)
            self.proc.wait(2.0)
        except (OSError, subprocess.TimeoutExpired):
            pass
        self.kill()


def job_time_limit(job: Job, time_limit: float) -> float:
    """The time limit of a job: ``time_limit`` per row (per scene of a line)."""
    return time_limit * job.size


def run_jobs(jobs: list[Job], *, workers: int = 1, time_limit: float = DEFAULT_TIME_LIMIT
             ) -> Iterator[tuple[Job, dict | list[dict]]]:
    """Run ``jobs`` on ``workers`` processes; yield (job, row) as each finishes.

    A job past its time limit (``time_limit`` seconds, times the number of
    scenes for a line) has its process killed (and replaced) and yields a
    ``timeout`` row; a process that dies yields ``crashed``. A line job that
    finishes yields a list of rows, one per scene; one that fails yields one
    failure row (a dict).
    """
    if not jobs:
        return
    pending = deque(jobs)
    pool = [_Worker() for _ in range(max(1, min(workers, len(jobs))))]
    try:
        while pending or any(w.job is not None for w in pool):
            for w in pool:
                if w.job is None and pending:
                    w.give(pending.popleft(), time_limit)
            busy = [w for w in pool if w.job is not None]
            timeout = max(0.0, min(w.started + job_time_limit(w.job, time_limit)
                                   for w in busy) - time.monotonic())
            ready = wait([w.proc.stdout for w in busy], timeout=timeout + 0.05)
            for i, w in enumerate(pool):
                job = w.job
                if job is None:
                    continue
                if w.proc.stdout in ready:
                    try:
                        row = _recv(w.proc.stdout)
                    except (EOFError, OSError, pickle.UnpicklingError):
                        w.kill()
                        pool[i] = _Worker()
                        yield job, failed_row("crashed", "the worker process died (exit code "
                                              f"{w.proc.returncode})",
                                              time.monotonic() - w.started)
                        continue
                    w.job = None
                    yield job, row
                elif time.monotonic() - w.started > (limit := job_time_limit(job, time_limit)):
                    w.kill()
                    pool[i] = _Worker()
                    what = (f"{limit:g} s ({time_limit:g} s per scene)"
                            if job.kind == "line" else f"{limit:g} s")
                    yield job, failed_row("timeout", f"killed after the time limit of {what}",
                                          limit)
    finally:
        for w in pool:
            if w.job is None:
                w.stop()
            else:
                w.kill()


# -- a sweep ------------------------------------------------------------------------------
def _scene_columns(key: str) -> dict:
    d = json.loads(key)
    return {k: d[k] for k in ("theta", "height", "links", "length", "EI", "weight", "channel")}


def _versions(names: Iterable[str]) -> dict[str, str]:
    """The version of each back-end's library (scipy's for the baselines)."""
    import scipy

    from .. import __version__
    from ..solvers.registry import get_backend

    return {n: (f"scipy {scipy.__version__}" if n in BASELINES
                else f"lcpbench {__version__}" if n == "reference"
                else get_backend(n).version() or "?") for n in names}


def _line_rows(job: Job, result: dict | list[dict], have_runs: set) -> list[tuple]:
    """(scene key, row, replace) for each row a finished line job stores.

    A finished line replaces every row of the line (the continuation made
    them together). A line that failed (timeout, crash, error: one dict)
    costs one failure row for each of its scenes not stored yet; stored ones
    stay.
    """
    if isinstance(result, list) and len(result) == job.size:
        return [(k, row, True) for k, row in zip(job.scenes, result)]
    if isinstance(result, list):  # cannot happen; never store rows against wrong scenes
        result = failed_row("error", f"the line returned {len(result)} rows for "
                            f"{job.size} scenes", 0.0)
    out = []
    for k, key in zip(job.scenes, job.keys):
        if key in have_runs:
            continue
        row = dict(result)
        row["wall_time"] = float(result["wall_time"]) / job.size
        row["reason"] = f"{result['reason']}, for the continuation line of {job.size} scenes"
        out.append((k, row, False))
    return out


def sweep(store: Store, jobs: list[Job], *, workers: int = 1,
          time_limit: float = DEFAULT_TIME_LIMIT, rerun: bool = False,
          progress: Callable[[int, int, Job, dict], None] | None = None) -> SweepPlan:
    """Run the jobs that are not in ``store`` yet (all of them with ``rerun``).

    Every finished job is committed at once. ``progress(done, total, job,
    row)`` is called after each stored row, with ``done`` and ``total``
    counting rows (a line job is one row per scene; it is then passed with
    ``scene`` set to that row's scene). A line job is skipped only when all
    its rows are stored; a partly stored line is run again in full and its
    rows replaced. Returns the plan (what was skipped and run).
    """
    have_runs = set() if rerun else store.run_keys()
    have_refs = set() if rerun else store.ref_keys()
    todo = [j for j in jobs
            if (j.scene not in have_refs if j.kind == "ref"
                else not all(k in have_runs for k in j.keys))]
    plan = SweepPlan(jobs, todo)
    versions = _versions({j.backend for j in todo})
    done, total = plan.rows_done, plan.rows
    for job, result in run_jobs(todo, workers=workers, time_limit=time_limit):
        created = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        if job.kind == "line":
            entries = _line_rows(job, result, have_runs)
            done += job.size - len(entries)  # stored rows a failed line left alone
        else:
            entries = [(job.scene, result, rerun)]
        for key, row, replace in entries:
            row.update(_scene_columns(key))
            row["created"] = created
            if job.kind == "ref":
                row["scene"] = key
                row.setdefault("tol", job.tol)
                row.setdefault("check_error", float("nan"))
                store.put_ref(row, replace=replace)
            else:
                row.update(scene=key, backend=job.backend, settings=job.settings,
                           tol=job.tol, method=job.method, version=versions[job.backend])
                store.put_run(row, replace=replace or rerun)
            done += 1
            if progress is not None:
                progress(done, total, job if key == job.scene else
                         dataclasses.replace(job, scene=key), row)
    return plan


def default_workers() -> int:
    """Both cores of a 2-core machine; at most 4 by default."""
    return max(1, min(4, os.cpu_count() or 1))


def error_of(total_force: float, reference: float, force_scale: float) -> float:
    """The force error of a run: |F − F_ref| / max(|F_ref|, EI/ℓ²).

    Relative where the reference force exceeds the chain's own force unit
    EI/ℓ², in that unit below it (so no-contact scenes, F_ref = 0, are judged
    too).
    """
    if not np.isfinite(total_force):
        return float("inf")
    return abs(total_force - reference) / max(abs(reference), force_scale)


if __name__ == "__main__":
    _worker_main()
