"""The results store: one commit per run, no duplicates, foreign files left alone."""

import csv
import sqlite3

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
