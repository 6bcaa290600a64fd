"""Sweeps on Dask distributed, with the pool's isolation inside each task.

``pip install 'lcpbench[cluster]'``; ``lcpbench sweep --dask`` (a local
cluster of ``--jobs`` workers) or ``--dask tcp://HOST:PORT`` (a running
scheduler).

Dask cannot interrupt a running task (distributed #1434, #391), so a task
does not run a job itself: it runs :func:`~.pool.run_jobs` on its chunk of
jobs, which starts the pool's worker subprocess *on the Dask worker's
machine*, gives each job its time limit, kills and replaces the subprocess
past it (``timeout`` rows) and turns a dead subprocess into ``crashed``
rows, exactly as a local sweep does (benchopt runs its joblib back-ends the
same way). The rows come back to the one process that writes the store, as
each task finishes, so resume, crash rows and "parallel = serial" hold as
for the local pool. A task that Dask itself loses (its worker died) gives
``crashed`` rows for its jobs.

A Dask worker needs lcpbench importable (the same version) and one thread
(``--nthreads 1``), so two tasks do not share a core; the subprocess it
starts is pinned to one BLAS thread like the pool's.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

from ..errors import ProblemError
from .jobs import Job, Rows
from .pool import run_jobs
from .rows import failed_row


def run_chunk(jobs: list[Job], time_limit: float) -> list[tuple[Job, Rows]]:
    """A Dask task: ``jobs`` through the pool's isolated worker, one at a time."""
    return list(run_jobs(jobs, workers=1, time_limit=time_limit))


def _client(address: str | None, workers: int, processes: bool):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ProblemError("--dask needs Dask distributed: pip install "
                           "'lcpbench[cluster]'") from None
    if address in (None, "", "local"):
        cluster = LocalCluster(n_workers=max(1, workers), threads_per_worker=1,
                               processes=processes, dashboard_address=None)
        return Client(cluster), cluster
    addr = address[len("dask://"):] if address.startswith("dask://") else address
    if "://" not in addr:
        addr = f"tcp://{addr}"
    try:
        return Client(addr, timeout=30), None
    except OSError as exc:
        raise ProblemError(f"dask: cannot reach the scheduler at {addr} ({exc})") from exc


#: the most jobs in one Dask task when the chunk is automatic
MAX_CHUNK = 64


def auto_chunk(jobs: int, workers: int) -> int:
    """Jobs per Dask task: about four tasks per worker, at most :data:`MAX_CHUNK`.

    Each task starts one worker subprocess (importing lcpbench and the back-ends
    costs about a second), so a task of one job would spend longer starting
    than solving (0.28 s per run of the standard sweep, see docs/bench.md).
    """
    return max(1, min(MAX_CHUNK, -(-jobs // (4 * max(1, workers)))))


def dask_runner(address: str | None = None, *, chunk: int | None = None,
                processes: bool = True) -> Callable[..., Iterator[tuple[Job, Rows]]]:
    """A ``run_jobs``-shaped runner for :func:`~.sweep.sweep` on Dask.

    ``address``: a scheduler (``tcp://host:port``, ``dask://host:port`` or
    ``host:port``), or None/"local" for a :class:`distributed.LocalCluster` of
    the sweep's ``workers`` (processes, or threads with ``processes=False``;
    each task starts its own subprocess either way). ``chunk``: jobs per task
    (None: :func:`auto_chunk`). A task's rows reach the store when the task ends.
    """
    if chunk is not None and chunk < 1:
        raise ProblemError(f"chunk must be >= 1, got {chunk}")

    def runner(jobs: list[Job], *, workers: int = 1, time_limit: float
               ) -> Iterator[tuple[Job, Rows]]:
        if not jobs:
            return
        from distributed import as_completed

        client, cluster = _client(address, workers, processes)
        try:
            size = chunk or auto_chunk(len(jobs), workers)
            chunks = [jobs[i:i + size] for i in range(0, len(jobs), size)]
            futures = {client.submit(run_chunk, c, time_limit, pure=False): c
                       for c in chunks}
            started = time.monotonic()
            for fut in as_completed(futures):
                try:
                    done = fut.result()
                except Exception as exc:  # noqa: BLE001 - the task was lost, not the sweep
                    why = f"the Dask task was lost ({type(exc).__name__}: {exc})"
                    done = [(j, j.failure(failed_row("crashed", why,
                                                     time.monotonic() - started)))
                            for j in futures[fut]]
                yield from done
        finally:
            client.close()
            if cluster is not None:
                cluster.close()

    return runner
