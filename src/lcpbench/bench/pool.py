"""The sweep's worker processes: jobs run with a time limit, crashes cost one job.

Workers are plain subprocesses (``python -m lcpbench.bench.pool``, through
:class:`lcpbench.worker.WorkerProcess`), not multiprocessing children:
nothing of the caller's ``__main__`` is re-imported, and a worker killed at
its time limit takes nothing else with it. Jobs and their :class:`Rows`
travel as length-prefixed pickles on the worker's stdin and on a copy of its
stdout; the worker's own fd 1 is pointed at stderr, so solver libraries that
print cannot corrupt the protocol. Workers die with the sweep (Linux
``PR_SET_PDEATHSIG``).
"""

from __future__ import annotations

import os
import pickle
import signal
import subprocess
import sys
import time
from collections import deque
from collections.abc import Iterator
from multiprocessing.connection import wait

from ..model.compiled import warm_up as load_kernel
from ..worker import (
    WorkerDied,
    WorkerProcess,
    child_channel,
    die_with_parent,
    read_message,
    write_message,
)
from .jobs import DEFAULT_TIME_LIMIT, Job, Rows
from .rows import failed_row

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


def _dumps(obj) -> bytes:
    return pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)


# -- the worker's side --------------------------------------------------------------------
def worker_main() -> None:
    """Answer (job, time limit) messages with the job's :class:`Rows` until told to stop."""
    die_with_parent()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C
    inp, out = child_channel()
    while True:
        try:
            msg = read_message(inp)
        except EOFError:
            return
        if msg is None:
            return
        task = pickle.loads(msg)
        if task is None:
            return
        job, time_limit = task
        rows = job.execute(time_limit)
        try:
            write_message(out, _dumps(rows))
        except (BrokenPipeError, OSError):  # the parent is gone
            return


# -- the sweep's side ---------------------------------------------------------------------
class _Worker:
    def __init__(self):
        stderr = None if os.environ.get("LCPBENCH_WORKER_STDERR") else subprocess.DEVNULL
        self.proc = WorkerProcess(["-m", "lcpbench.bench.pool"], env=worker_environment(),
                                  stderr=stderr)
        self.job: Job | None = None
        self.started = 0.0

    def fileno(self) -> int:
        return self.proc.fileno()

    def give(self, job: Job, time_limit: float) -> None:
        self.job, self.started = job, time.monotonic()
        self.proc.send(_dumps((job, time_limit)))

    def kill(self) -> None:
        self.proc.kill()

    def stop(self) -> None:
        """A clean exit for an idle worker (killed if it does not go)."""
        self.proc.stop(2.0, goodbye=_dumps(None))


def run_jobs(jobs: list[Job], *, workers: int = 1, time_limit: float = DEFAULT_TIME_LIMIT
             ) -> Iterator[tuple[Job, Rows]]:
    """Run ``jobs`` on ``workers`` processes; yield (job, rows) as each finishes.

    A job past its time limit (``time_limit`` seconds per row: times the
    number of scenes for a line) has its process killed (and replaced) and
    yields ``timeout`` rows; a process that dies yields ``crashed`` rows.
    """
    if not jobs:
        return
    load_kernel()  # the compiled kernel into numba's cache before any job is timed
    pending = deque(jobs)
    pool = [_Worker() for _ in range(max(1, min(workers, len(jobs))))]
    try:
        while pending or any(w.job is not None for w in pool):
            for w in pool:
                if w.job is None and pending:
                    w.give(pending.popleft(), time_limit)
            busy = [w for w in pool if w.job is not None]
            timeout = max(0.0, min(w.started + w.job.time_limit(time_limit)
                                   for w in busy) - time.monotonic())
            ready = wait(busy, timeout=timeout + 0.05)
            for i, w in enumerate(pool):
                job = w.job
                if job is None:
                    continue
                if w in ready:
                    try:
                        msg = w.proc.poll()
                        rows = None if msg is None else pickle.loads(msg)
                    except (WorkerDied, OSError, pickle.UnpicklingError, EOFError):
                        w.kill()
                        pool[i] = _Worker()
                        yield job, job.failure(failed_row(
                            "crashed", "the worker process died (exit code "
                            f"{w.proc.returncode})", time.monotonic() - w.started))
                        continue
                    if rows is not None:
                        w.job = None
                        if pending:  # busy again before the caller stores these rows
                            w.give(pending.popleft(), time_limit)
                        yield job, rows
                        continue
                limit = job.time_limit(time_limit)
                if time.monotonic() - w.started > limit:
                    w.kill()
                    pool[i] = _Worker()
                    yield job, job.failure(failed_row(
                        "timeout", f"killed after the time limit of "
                        f"{job.describe_limit(time_limit)}", limit))
    finally:
        for w in pool:
            if w.job is None:
                w.stop()
            else:
                w.kill()


if __name__ == "__main__":
    sys.exit(worker_main())
