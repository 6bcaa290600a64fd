"""The results store: one commit per run, no duplicates, foreign files left alone."""

import csv
import os
import signal
import sqlite3
import subprocess
import sys
import time

import numpy as np
import pytest

from lcpbench.bench.store import SCHEMA_VERSION, Store
from lcpbench.errors import StoreError


def _row(backend="lemke", theta=150.0, force=0.4, status="solved"):
    return {"scene": f'{{"theta": {theta}}}', "backend": backend, "settings": "default",
            "tol": 1e-3, "method": "globalised", "theta": theta, "height": 3.0, "links": 4,
            "length": 30.0, "EI": 32.01, "weight": 0.0, "channel": False, "status": status,
            "converged": status == "solved", "reason": "r", "total_force": force,
            "outer_iterations": 3, "inner_iterations": 7, "wall_time": 0.01,
            "solver_time": 0.005, "certificate": {"min_gap": 0.0}, "version": "1",
            "created": "now", "forces": np.array([0.1, 0.3, 0.0]), "gaps": np.zeros(3),
            "x": np.arange(5.0), "y": np.zeros(5)}


def test_runs_round_trip_and_are_never_duplicated(tmp_path):
    path = tmp_path / "s.sqlite"
    with Store(path) as st:
        assert st.put_run(_row())
        assert not st.put_run(_row(force=9.9))  # already there: nothing written
        assert st.count() == 1
        assert st.runs()[0]["total_force"] == 0.4
        assert st.put_run(_row(force=9.9), replace=True)  # --rerun
        (r,) = st.runs()
        assert r["total_force"] == 9.9
        np.testing.assert_array_equal(r["forces"], [0.1, 0.3, 0.0])
        assert st.run_keys() == {('{"theta": 150.0}', "lemke", "default", 1e-3, "globalised")}
    # committed: a new connection sees it
    with Store(path) as st:
        assert st.count() == 1


def test_csv_export(tmp_path):
    with Store(tmp_path / "s.sqlite") as st:
        st.put_run(_row("lemke"))
        st.put_run(_row("osqp", force=0.5))
        st.put_ref({"scene": '{"theta": 150.0}', "total_force": 0.41, "converged": True})
        n = st.export_csv(tmp_path / "runs.csv")
    rows = list(csv.DictReader(open(tmp_path / "runs.csv")))
    assert n == len(rows) == 2
    assert {r["backend"] for r in rows} == {"lemke", "osqp"}
    assert all(float(r["reference_force"]) == 0.41 for r in rows)


def test_corrupt_file_is_refused_and_left_untouched(tmp_path):
    path = tmp_path / "s.sqlite"
    junk = b"this is not a database\x00" * 100
    path.write_bytes(junk)
    with pytest.raises(StoreError, match="not a readable SQLite file.*left as it is"):
        Store(path)
    assert path.read_bytes() == junk


def test_truncated_store_is_refused(tmp_path):
    path = tmp_path / "s.sqlite"
    with Store(path) as st:
        for k in range(200):
            st.put_run(_row(theta=float(k)))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(StoreError):
        st = Store(path)
        st.runs()  # a truncated file may open: reading it must fail, not return rubbish
    assert path.read_bytes() == data[: len(data) // 2]


def test_foreign_database_is_refused(tmp_path):
    path = tmp_path / "other.sqlite"
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE accounts (id INTEGER)")
    with pytest.raises(StoreError, match="not an lcpbench store"):
        Store(path)


def test_other_schema_version_is_refused(tmp_path):
    path = tmp_path / "s.sqlite"
    Store(path).close()
    with sqlite3.connect(path) as db:
        db.execute("UPDATE meta SET value = ? WHERE key = 'schema'", (str(SCHEMA_VERSION + 1),))
    with pytest.raises(StoreError, match="schema version"):
        Store(path)


def test_unusable_paths(tmp_path):
    with pytest.raises(StoreError, match="is a folder"):
        Store(tmp_path)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(StoreError, match="cannot create its folder"):
        Store(blocker / "sub" / "s.sqlite")
    with pytest.raises(StoreError, match="no such file"):
        Store(tmp_path / "missing.sqlite", create=False)


# -- files lcpbench did not create are refused, untouched --------------------------------
def _fingerprint(path):
    st = path.stat()
    return path.read_bytes(), st.st_mtime_ns, st.st_size


def _empty_sqlite(path):
    with sqlite3.connect(path) as db:
        db.execute("PRAGMA user_version = 7")  # writes the header page: a valid, empty DB


def _view_only(path):
    with sqlite3.connect(path) as db:
        db.execute("CREATE VIEW meta_view AS SELECT 1 AS one")


def _odd_meta(path):
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE meta (name TEXT, version INTEGER, note TEXT)")
        db.execute("INSERT INTO meta VALUES ('schema', 2, 'x')")


def _meta_only(path):
    with sqlite3.connect(path) as db:
        db.execute("CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)")
        db.execute(f"INSERT INTO meta VALUES ('schema', '{SCHEMA_VERSION}')")


@pytest.mark.parametrize("make,message", [
    (lambda p: p.write_bytes(b""), r"an empty file \(0 bytes\)"),
    (_empty_sqlite, r"not an lcpbench store \(holds nothing\)"),
    (_view_only, r"not an lcpbench store \(holds view meta_view\)"),
    (_odd_meta, r"meta table has columns \(name, version, note\)"),
    (_meta_only, r"not a complete lcpbench store \(no runs table\)"),
], ids=["zero-bytes", "empty-sqlite", "view-only", "meta-of-another-shape", "meta-only"])
def test_files_lcpbench_did_not_create_are_refused_untouched(tmp_path, make, message):
    path = tmp_path / "s.sqlite"
    make(path)
    before = _fingerprint(path)
    time.sleep(0.01)  # a write would move the mtime past the resolution of the clock
    for create in (True, False):
        with pytest.raises(StoreError, match=message) as info:
            Store(path, create=create)
        assert "\n" not in str(info.value) and "left as it is" in str(info.value)
    assert _fingerprint(path) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.sqlite"]  # no journal, no lock


# -- schema 1 stores: read as they are, migrated on the first write ----------------------
V1_SCHEMA = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE runs (
    scene TEXT NOT NULL, backend TEXT NOT NULL, settings TEXT NOT NULL,
    tol REAL NOT NULL, method TEXT NOT NULL,
    theta REAL, height REAL, links INTEGER, length REAL, EI REAL, weight REAL, channel INTEGER,
    status TEXT NOT NULL, converged INTEGER NOT NULL, reason TEXT, total_force REAL,
    outer_iterations INTEGER, inner_iterations INTEGER, wall_time REAL, solver_time REAL,
    certificate TEXT, version TEXT, created TEXT,
    forces BLOB, gaps BLOB, x BLOB, y BLOB,
    PRIMARY KEY (scene, backend, settings, tol, method)
);
CREATE TABLE refs (
    scene TEXT PRIMARY KEY,
    theta REAL, height REAL, links INTEGER, length REAL, EI REAL, weight REAL, channel INTEGER,
    total_force REAL, converged INTEGER, tol REAL, check_error REAL, wall_time REAL,
    reason TEXT, created TEXT,
    forces BLOB, gaps BLOB, x BLOB, y BLOB
);
INSERT INTO meta VALUES ('schema', '1');
INSERT INTO runs (scene, backend, settings, tol, method, status, converged, total_force)
    VALUES ('{"theta": 10.0}', 'lemke', 'default', 0.001, 'globalised', 'solved', 1, 0.25);
"""


def test_schema_1_store_is_read_unchanged_and_migrated_on_write(tmp_path):
    path = tmp_path / "v1.sqlite"
    with sqlite3.connect(path) as db:
        db.executescript(V1_SCHEMA)
    before = _fingerprint(path)
    with Store(path, create=False) as st:  # what `lcpbench report` does
        assert st.schema == 1
        (r,) = st.runs()
        assert r["total_force"] == 0.25 and r["sweep_id"] is None
        assert st.runs(sweep_id="anything") == [] and st.sweeps() == []
    assert _fingerprint(path)[0] == before[0]  # reading wrote nothing
    with Store(path) as st:
        st.put_run(_row(theta=20.0))
        assert st.schema == SCHEMA_VERSION
    with Store(path) as st:
        assert st.schema == SCHEMA_VERSION and st.count() == 2  # the old run is kept
        assert {r["total_force"] for r in st.runs()} == {0.25, 0.4}


# -- the sweep lock -----------------------------------------------------------------------
def test_second_lock_is_refused_naming_the_holder(tmp_path):
    path = tmp_path / "s.sqlite"
    with Store(path) as a, Store(path) as b:
        with a.lock("lcpbench sweep") as sweep:
            assert a.sweep_id == sweep
            with pytest.raises(StoreError) as info:
                with b.lock("lcpbench sweep"):
                    pass
            msg = str(info.value)
            assert msg.startswith(f"store {path} is locked by pid {os.getpid()} on host ")
            assert "(lcpbench sweep, started " in msg and "\n" not in msg
        assert a.sweep_id is None
        with b.lock():  # released at the end of the block
            pass


def test_runs_carry_the_sweep_that_wrote_them(tmp_path):
    path = tmp_path / "s.sqlite"
    with Store(path) as st:
        st.put_run(_row("unlocked"))
        with st.lock() as first:
            st.put_run(_row("lemke"))
            st.put_run(_row("pgs"))
        with st.lock() as second:
            st.put_run(_row("osqp"))
            assert not st.put_run(_row("lemke"))  # already there: still the first sweep's
        assert first != second
        assert [r["backend"] for r in st.runs(sweep_id=first)] == ["lemke", "pgs"]
        assert [r["backend"] for r in st.runs(sweep_id=second)] == ["osqp"]
        assert st.count(sweep_id=first) == 2 and st.count() == 4
        assert [s["sweep_id"] for s in st.sweeps()] == [first, second]
        assert {r["backend"]: r["sweep_id"] for r in st.runs()}["unlocked"] is None
        # a filter combines with a caller's WHERE clause
        assert len(st.runs(where="WHERE backend = ?", params=("pgs",), sweep_id=first)) == 1


HOLD = """
import sys, time
from lcpbench.bench.store import Store
st = Store(sys.argv[1])
with st.lock("test holder"):
    print("locked", flush=True)
    time.sleep(float(sys.argv[2]))
print("released", flush=True)
"""


def _holder(path, seconds):
    proc = subprocess.Popen([sys.executable, "-c", HOLD, str(path), str(seconds)],
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "locked"
    return proc


def test_lock_of_another_process_refused_then_waited_for(tmp_path):
    path = tmp_path / "s.sqlite"
    Store(path).close()
    t0 = time.monotonic()
    proc = _holder(path, 1.0)  # holds the lock for 1 s after saying so
    try:
        with Store(path) as st:
            with pytest.raises(StoreError, match=f"locked by pid {proc.pid} .*test holder"):
                with st.lock():
                    pass
            with st.lock(wait=True):
                assert time.monotonic() - t0 >= 1.0  # granted only after the holder let go
                assert proc.stdout.readline().strip() == "released"
    finally:
        proc.kill()
        proc.wait()


def test_lock_of_a_killed_process_does_not_block(tmp_path):
    path = tmp_path / "s.sqlite"
    Store(path).close()
    proc = _holder(path, 600)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert str(proc.pid) in (tmp_path / "s.sqlite.lock").read_text()  # stale details remain
    with Store(path) as st, st.lock() as sweep:
        assert sweep and str(os.getpid()) in (tmp_path / "s.sqlite.lock").read_text()
