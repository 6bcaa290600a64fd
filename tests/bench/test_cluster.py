"""Sweeps on Dask distributed: the serial rows, time limits and crashes as in the pool."""

import pytest

from lcpbench.bench.grid import Grid
from lcpbench.bench.store import Store
from lcpbench.bench.sweep import plan_sweep, sweep

pytest.importorskip("distributed")

from lcpbench.bench.cluster import dask_runner  # noqa: E402

#: what a run is, apart from when it ran and how long it took
KEEP = ("scene", "backend", "settings", "tol", "method", "status", "converged", "reason",
        "total_force", "outer_iterations", "inner_iterations", "certificate")


def _rows(path):
    with Store(path) as st:
        return sorted((tuple(r[k] for k in KEEP) for r in st.runs(arrays=False)),
                      key=repr), {k: r["total_force"] for k, r in st.refs().items()}


def test_local_cluster_gives_the_serial_rows(tmp_path):
    """Route against route: the rows must not depend on the executor or on a
    restart (determinism); the serial rows are checked against the sweep's
    reference, itself against the energy minimum, in tests/bench/test_sweep.py."""
    grid = Grid(theta=(90.0, 150.0, 180.0), height=(3.0,), links=(20,))
    jobs = plan_sweep(grid, ["active-set", "lemke", "pgs"], ["default"])
    with Store(tmp_path / "serial.sqlite") as st:
        sweep(st, jobs, workers=1)
    with Store(tmp_path / "dask.sqlite") as st:
        plan = sweep(st, jobs, workers=2, runner=dask_runner("local", chunk=2,
                                                             processes=False))
    assert plan.rows_todo == plan.rows == 3 * 3 + 3 + 3  # runs, baselines, references
    assert _rows(tmp_path / "dask.sqlite") == _rows(tmp_path / "serial.sqlite")


def test_time_limits_and_crashes_hold_inside_dask_tasks(tmp_path, misbehaving_backends):
    grid = Grid(theta=(150.0,), height=(3.0,), links=(20,))
    jobs = plan_sweep(grid, ["test-hang", "test-crash", "test-raise", "active-set"],
                      ["default"], baselines=())
    with Store(tmp_path / "s.sqlite") as st:
        sweep(st, jobs, workers=2, time_limit=8.0,
              runner=dask_runner("local", processes=False))
        status = {r["backend"]: r["status"] for r in st.runs(arrays=False)}
    assert status == {"test-hang": "timeout", "test-crash": "crashed",
                      "test-raise": "not_converged", "active-set": "solved"}


# -- a Dask sweep whose client is SIGKILLed resumes to the serial rows -----------------------
RESUME_ARGS = ["sweep", "--theta", "120,150", "--height", "3", "--links", "20",
               "--solvers", "active-set,lemke", "--settings", "default", "--baseline", "none",
               "--repeat", "1", "--dask", "--jobs", "2", "--oversubscribe", "--quiet",
               "--no-report"]
RESUME_RUNS = 2 * 2  # 2 scenes x 2 back-ends (and 2 references), one job a task


def test_a_dask_sweep_resumes_after_a_sigkill_of_its_client(tmp_path):
    """The client (the one store writer) is killed without warning after its first row;
    its cluster's processes are left orphaned until the end. The same command again
    finishes the sweep, and the store holds exactly the rows of a serial sweep."""
    import os
    import signal
    import subprocess
    import sys

    from sweep_kill import killed_after_first_run

    def command(store):
        return [sys.executable, "-m", "lcpbench.cli", *RESUME_ARGS, "--store", str(store)]

    # the client only, mid-sweep: its cluster's processes are left orphaned
    killed, proc = killed_after_first_run(command, tmp_path, RESUME_RUNS, group=False)
    try:
        again = subprocess.run(command(killed), capture_output=True, text=True, timeout=300)
        assert again.returncode == 0, again.stderr
    finally:
        try:  # the orphaned cluster of the killed client
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    grid = Grid(theta=(120.0, 150.0), height=(3.0,), links=(20,))
    with Store(tmp_path / "serial.sqlite") as st:
        sweep(st, plan_sweep(grid, ["active-set", "lemke"], ["default"], baselines=()),
              workers=1)
    rows_killed, refs_killed = _rows(killed)
    rows_serial, refs_serial = _rows(tmp_path / "serial.sqlite")
    assert len(rows_killed) == RESUME_RUNS  # nothing lost, nothing twice
    assert rows_killed == rows_serial
    assert refs_killed == refs_serial
