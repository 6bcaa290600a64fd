"""SQLite databases lcpbench did not create stay untouched (issue 36, item 7).

Not only their bytes: SQLite would recover a database it opens as usual (roll
back a hot ``-journal``, replay and checkpoint a ``-wal``, make or remove the
``-shm``), so a foreign store must be inspected without letting it. Each case
below is refused through the API and through the command line (exit 2, one
line on stderr, no traceback), and every file beside it keeps its bytes: the
folder lists the same names, each with the same sha256.
"""

from __future__ import annotations

import hashlib
import shutil
import sqlite3
import subprocess
import sys
from contextlib import contextmanager

import pytest

from lcpbench.bench.store import Store
from lcpbench.errors import StoreError


def _snapshot(folder) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir()}


def _accounts(db, rows=range(50)):
    db.execute("CREATE TABLE accounts (id INTEGER PRIMARY KEY, owner TEXT)")
    db.executemany("INSERT INTO accounts VALUES (?, ?)", [(i, f"owner {i}") for i in rows])


@contextmanager
def _plain(folder):
    path = folder / "other.sqlite"
    with sqlite3.connect(path) as db:
        _accounts(db)
    db.close()
    yield path


def _wal_writer(path):
    """A WAL database whose rows are all in its -wal file (never checkpointed)."""
    db = sqlite3.connect(path, isolation_level=None)
    assert db.execute("PRAGMA journal_mode=WAL").fetchone()[0] == "wal"
    db.execute("PRAGMA wal_autocheckpoint=0")
    db.execute("BEGIN")
    _accounts(db)
    db.execute("COMMIT")
    return db


@contextmanager
def _wal_copied(folder):
    """The files of a WAL database copied while its writer was open: the main file
    and a -wal holding the committed frames, no -shm (as after a crash)."""
    source = folder.parent / f"{folder.name}-source"
    source.mkdir()
    db = _wal_writer(source / "other.sqlite")
    try:
        for suffix in ("", "-wal"):
            shutil.copyfile(source / f"other.sqlite{suffix}", folder / f"other.sqlite{suffix}")
    finally:
        db.close()
    assert (folder / "other.sqlite-wal").stat().st_size > 0
    yield folder / "other.sqlite"


@contextmanager
def _wal_open(folder):
    """A WAL database whose writer keeps its connection open meanwhile (-wal and -shm)."""
    path = folder / "other.sqlite"
    db = _wal_writer(path)
    try:
        assert {p.name for p in folder.iterdir()} == {
            "other.sqlite", "other.sqlite-wal", "other.sqlite-shm"}
        yield path
    finally:
        db.close()


@contextmanager
def _hot_journal(folder):
    """A rollback-journal database and its -journal copied in the middle of a
    transaction that had already written pages to the main file (a hot journal)."""
    source = folder.parent / f"{folder.name}-source"
    source.mkdir()
    with sqlite3.connect(source / "other.sqlite") as db:
        _accounts(db)
    db.close()
    db = sqlite3.connect(source / "other.sqlite", isolation_level=None)
    try:
        db.execute("PRAGMA cache_size=1")  # spill the changes into the main file early
        db.execute("BEGIN")
        db.executemany("INSERT INTO accounts VALUES (?, ?)",
                       [(i, "x" * 200) for i in range(1000, 6000)])
        assert (source / "other.sqlite-journal").stat().st_size > 0
        for suffix in ("", "-journal"):
            shutil.copyfile(source / f"other.sqlite{suffix}",
                            folder / f"other.sqlite{suffix}")
        db.execute("ROLLBACK")
    finally:
        db.close()
    yield folder / "other.sqlite"


FOREIGN = {"plain": _plain, "wal-copied": _wal_copied, "wal-open": _wal_open,
           "hot-journal": _hot_journal}


@pytest.fixture
def folder(tmp_path):
    d = tmp_path / "data"
    d.mkdir()
    return d


@pytest.mark.parametrize("make", FOREIGN.values(), ids=FOREIGN.keys())
def test_api_refuses_a_foreign_database_and_leaves_every_file_as_it_is(folder, make):
    with make(folder) as path:
        before = _snapshot(folder)
        for create in (True, False):
            with pytest.raises(StoreError, match="not an lcpbench store") as info:
                Store(path, create=create)
            assert "\n" not in str(info.value) and "left as it is" in str(info.value)
        assert _snapshot(folder) == before


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "lcpbench.cli", *args], capture_output=True,
                          text=True, timeout=300)


SWEEP = ("sweep", "--theta", "150", "--height", "3", "--links", "20", "--solvers",
         "active-set", "--settings", "default", "--baseline", "none", "--quiet")
REPORT = ("report",)
SELECT = ("select", "--force-tol", "1e-3", "--links", "20", "--solvers", "active-set",
          "--quiet", "--evidence", "none")


@pytest.mark.parametrize("make,command", [
    *((m, SWEEP) for m in FOREIGN.values()),
    (_wal_open, REPORT), (_hot_journal, REPORT),
    (_wal_open, SELECT), (_hot_journal, SELECT),
], ids=[*(f"sweep-{k}" for k in FOREIGN), "report-wal-open", "report-hot-journal",
        "select-wal-open", "select-hot-journal"])
def test_cli_refuses_a_foreign_database_in_one_line_and_leaves_it_as_it_is(
        folder, tmp_path, make, command):
    with make(folder) as path:
        before = _snapshot(folder)
        out = _cli(*command, "--store", str(path), *(
            ("--out", str(tmp_path / "out")) if command[0] != "select" else ()))
        assert _snapshot(folder) == before
    assert out.returncode == 2, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr
    assert "not an lcpbench store" in out.stderr and "left as it is" in out.stderr
    assert not (tmp_path / "out").exists()


def test_own_store_with_a_hot_journal_is_rolled_back_and_opened(tmp_path):
    """lcpbench's own store killed mid-commit: SQLite's recovery is wanted there."""
    source, copy = tmp_path / "source", tmp_path / "copy"
    source.mkdir(), copy.mkdir()
    Store(source / "s.sqlite").close()
    db = sqlite3.connect(source / "s.sqlite", isolation_level=None)
    try:
        db.execute("PRAGMA cache_size=1")
        db.execute("BEGIN")
        db.executemany("INSERT INTO refs (scene, reason) VALUES (?, ?)",
                       [(f"scene {i}", "x" * 200) for i in range(5000)])
        for suffix in ("", "-journal"):
            shutil.copyfile(source / f"s.sqlite{suffix}", copy / f"s.sqlite{suffix}")
        db.execute("ROLLBACK")
    finally:
        db.close()
    with Store(copy / "s.sqlite", create=False) as st:
        assert st.count("refs") == 0  # the cut-short transaction is undone
    assert sorted(p.name for p in copy.iterdir()) == ["s.sqlite"]
