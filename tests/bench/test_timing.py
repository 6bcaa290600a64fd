"""Honest timing: setup and solve apart, repeated solves, the machine record, schema 3."""

import json
import os
import shlex
import sqlite3

import pytest

from lcpbench.bench.grid import Grid
from lcpbench.bench.machine import (
    command_line,
    machine_record,
    machine_section,
    overloaded,
    refuse_overwrite,
    timing_rows,
)
from lcpbench.bench.rows import repeated
from lcpbench.bench.store import SCHEMA_VERSION, Store
from lcpbench.bench.sweep import plan_sweep, sweep
from lcpbench.cli import main
from lcpbench.errors import ProblemError


def _row(wall, solver=0.5, setup=0.1, force=0.4, converged=True):
    return {"wall_time": wall, "solver_time": solver, "setup_time": setup,
            "total_force": force, "outer_iterations": 3, "inner_iterations": 7,
            "converged": converged, "reason": "converged"}


def test_repeated_takes_the_median_and_keeps_the_spread():
    more = iter([_row(5.0, 0.7, 0.3), _row(2.0, 0.6, 0.2)])
    r = repeated(_row(3.0), more.__next__, 3)
    assert r["wall_time"] == 3.0 and r["solver_time"] == 0.6 and r["setup_time"] == 0.2
    assert (r["repeats"], r["wall_time_min"], r["wall_time_max"]) == (3, 2.0, 5.0)
    assert r["reason"] == "converged"
    # an even count: the median is the mean of the middle two
    r = repeated(_row(1.0), iter([_row(4.0)]).__next__, 2)
    assert r["wall_time"] == 2.5


def test_a_failed_run_is_timed_once_and_a_different_answer_is_named():
    def never():
        raise AssertionError("a failed run must not be repeated")

    r = repeated(_row(9.0, converged=False), never, 5)
    assert r["repeats"] == 1 and r["wall_time"] == 9.0
    r = repeated(_row(1.0), iter([_row(1.0), _row(1.0, force=0.5)]).__next__, 3)
    assert "repeat(s) 3 gave another answer" in r["reason"] and r["total_force"] == 0.4


def test_overload_is_reported_only_above_the_worker_count():
    rec = {"workers": 2, "load_start": [1.5, 1.0, 1.0], "load_end": [1.9, 1.0, 1.0]}
    assert overloaded(rec) is None
    rec["load_end"] = [3.2, 2.0, 1.0]
    assert "3.2 at the end" in overloaded(rec) and "2 worker" in overloaded(rec)


def test_machine_record_fields():
    rec = machine_record(workers=2, repeat=3)
    assert rec["cores"] == os.cpu_count() and rec["workers"] == 2 and rec["repeat"] == 3
    assert isinstance(rec["cpu"], str) and rec["cpu"]
    assert rec["blas_threads_workers"] == 1
    assert rec["load_start"] is None or len(rec["load_start"]) == 3
    assert json.loads(json.dumps(rec)) == rec  # storable as JSON


def test_repeat_must_be_a_positive_integer():
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ProblemError, match="repeat"):
            plan_sweep(Grid(theta=(150.0,), height=(3.0,), links=(20,)), ["active-set"],
                       ["default"], repeat=bad)


def test_cli_refuses_repeat_zero(tmp_path, capsys):
    code = main(["sweep", "--theta", "150", "--height", "3", "--links", "20", "--solvers",
                 "active-set", "--baseline", "none", "--repeat", "0", "--store",
                 str(tmp_path / "s.sqlite"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "repeat" in err[0]


def test_repeated_sweep_stores_setup_solve_spread_and_machine(tmp_path):
    path = tmp_path / "s.sqlite"
    grid = Grid(theta=(120.0, 180.0), height=(3.0,), links=(20,))
    with Store(path) as st, st.lock("test") as sweep_id:
        sweep(st, plan_sweep(grid, ["active-set", "lemke"], ["default"], repeat=3),
              workers=1)
        runs = st.runs(arrays=False)
        (sw,) = [s for s in st.sweeps() if s["sweep_id"] == sweep_id]
    assert sw["machine"]["repeat"] == 3 and sw["machine"]["workers"] == 1
    assert "load_end" in sw["machine"]
    assert {r["backend"] for r in runs if r["converged"]} >= {"active-set", "lemke"}
    for r in runs:  # a converged run is timed three times, a failure once
        assert r["repeats"] == (3 if r["converged"] else 1)
        assert r["wall_time_min"] <= r["wall_time"] <= r["wall_time_max"]
        # the compiled kernel (the active set's default path) times no parts: its
        # setup (assembly) is inside its one call, stored as 0
        assert 0.0 <= r["setup_time"] < r["wall_time_max"]
        if r["backend"] == "lemke":
            assert r["setup_time"] > 0.0  # building the dense LCP
    text = machine_section([sw], runs)
    assert "Machine and timing" in text and "`lemke`" in text
    rows = {(t["backend"], t["method"]): t for t in timing_rows(runs)}
    assert rows["lemke", "globalised"]["repeats"] == [3]


def test_setup_and_solve_are_parts_of_the_wall_time(tmp_path):
    path = tmp_path / "s.sqlite"
    grid = Grid(theta=(150.0,), height=(3.0,), links=(30,))
    with Store(path) as st:
        sweep(st, plan_sweep(grid, ["active-set", "lemke", "osqp"], ["default"]), workers=1)
        runs = st.runs(arrays=False)
    for r in runs:  # one solve each: its parts cannot exceed the whole
        assert r["repeats"] == 1
        assert r["setup_time"] >= 0 and r["solver_time"] >= 0
        assert r["setup_time"] + r["solver_time"] <= r["wall_time"]


V2_SCRIPT = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE runs (
    scene TEXT NOT NULL, backend TEXT NOT NULL, settings TEXT NOT NULL,
    tol REAL NOT NULL, method TEXT NOT NULL,
    theta REAL, height REAL, links INTEGER, length REAL, EI REAL, weight REAL, channel INTEGER,
    status TEXT NOT NULL, converged INTEGER NOT NULL, reason TEXT, total_force REAL,
    outer_iterations INTEGER, inner_iterations INTEGER, wall_time REAL, solver_time REAL,
    certificate TEXT, version TEXT, created TEXT,
    forces BLOB, gaps BLOB, x BLOB, y BLOB, sweep_id TEXT,
    PRIMARY KEY (scene, backend, settings, tol, method)
);
CREATE TABLE sweeps (sweep_id TEXT PRIMARY KEY, owner TEXT, pid INTEGER, host TEXT,
                     started TEXT);
CREATE TABLE refs (
    scene TEXT PRIMARY KEY,
    theta REAL, height REAL, links INTEGER, length REAL, EI REAL, weight REAL, channel INTEGER,
    total_force REAL, converged INTEGER, tol REAL, check_error REAL, wall_time REAL,
    reason TEXT, created TEXT,
    forces BLOB, gaps BLOB, x BLOB, y BLOB
);
INSERT INTO meta VALUES ('schema', '2');
INSERT INTO sweeps VALUES ('old', 'lcpbench sweep', 1, 'h', '2026-01-01');
INSERT INTO runs (scene, backend, settings, tol, method, status, converged, total_force,
                  wall_time, sweep_id)
    VALUES ('{"theta": 10.0}', 'lemke', 'default', 0.001, 'globalised', 'solved', 1, 0.25,
            0.01, 'old');
"""


def test_schema_2_store_is_read_as_it_is_and_migrated_on_write(tmp_path):
    path = tmp_path / "v2.sqlite"
    with sqlite3.connect(path) as db:
        db.executescript(V2_SCRIPT)
    before = path.read_bytes()
    with Store(path, create=False) as st:
        assert st.schema == 2
        (r,) = st.runs()
        assert r["setup_time"] is None and r["repeats"] is None  # not measured then
        assert [s["sweep_id"] for s in st.sweeps()] == ["old"]
        assert "No machine record" in machine_section(st.sweeps(), st.runs())
    assert path.read_bytes() == before  # reading wrote nothing
    with Store(path) as st, st.lock("test") as sid:
        assert st.schema == SCHEMA_VERSION == 3
        st.put_run({"scene": '{"theta": 20.0}', "backend": "lemke", "settings": "default",
                    "tol": 1e-3, "method": "globalised", "status": "solved", "converged": 1,
                    "total_force": 0.4, "setup_time": 0.002, "repeats": 3})
        st.put_machine(sid, {"cpu": "x", "workers": 1})
    with Store(path) as st:
        by = {r["total_force"]: r for r in st.runs()}
        assert by[0.25]["repeats"] is None and by[0.4]["repeats"] == 3
        assert {s["sweep_id"]: s["machine"] for s in st.sweeps()}[sid] == {"cpu": "x",
                                                                           "workers": 1}
        version = st.db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()[0]
        assert version == "3"


def test_a_timing_script_keeps_existing_results_unless_forced(tmp_path, capsys):
    kept, new = tmp_path / "perf.md", tmp_path / "perf.json"
    kept.write_text("committed")
    refuse_overwrite([new], force=False)  # nothing there: go on
    with pytest.raises(SystemExit) as stop:
        refuse_overwrite([kept, new], force=False)
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(kept) in err and "--force" in err
    refuse_overwrite([kept, new], force=True)  # told to: go on
    assert kept.read_text() == "committed"  # the guard itself writes nothing


def test_the_recorded_command_runs_as_it_was_given():
    """A benchmark's recorded command, split as a shell splits it, is the call that ran:
    the environment prefix, the script, each argument whole (one with a space too)."""
    got = command_line("mixed_batch.py", ["--rounds", "9", "--out", "/tmp/a b"], "LCPBENCH_AOT=0 ")
    assert shlex.split(got) == ["LCPBENCH_AOT=0", "python", "benchmarks/mixed_batch.py",
                                "--rounds", "9", "--out", "/tmp/a b"]
    assert command_line("fit_ei.py", []) == "python benchmarks/fit_ei.py"
