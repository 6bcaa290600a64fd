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
