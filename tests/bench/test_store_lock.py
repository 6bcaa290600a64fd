"""The sweep lock file is removed on release, safely (issue 40, item 6).

Removing a file that ``flock`` waiters may hold open could let two holders in:
one on the removed file, one on the new file at the path. The holder removes
the file while it still holds the lock, and a process granted the lock checks
that the file it locked is still the one at the path, else starts again.
"""

from __future__ import annotations

import fcntl
import json
import sqlite3
import subprocess
import sys
import threading
from types import SimpleNamespace

import pytest

import lcpbench.bench.store_lock as store_lock
from lcpbench.bench.store import Store
from lcpbench.errors import StoreError


def test_no_lock_file_is_left_after_the_lock(tmp_path):
    path = tmp_path / "s.sqlite"
    with Store(path) as st:
        with st.lock("test") as sweep_id:
            assert json.loads(st.lock_path.read_text())["sweep_id"] == sweep_id
        assert sorted(p.name for p in tmp_path.iterdir()) == ["s.sqlite"]
        with pytest.raises(RuntimeError, match="the sweep failed"):
            with st.lock("test"):
                raise RuntimeError("the sweep failed")
        assert sorted(p.name for p in tmp_path.iterdir()) == ["s.sqlite"]
        with st.lock("test"):  # and it can be taken again
            pass


def _unmigratable(path):
    """An lcpbench store that says schema 1 but has the later columns: its migration
    to 2 fails (runs already has sweep_id), so it is refused once the lock is held."""
    Store(path).close()
    with sqlite3.connect(path) as db:
        db.execute("UPDATE meta SET value = '1' WHERE key = 'schema'")
    db.close()


def test_a_lock_refused_after_it_was_taken_leaves_no_lock_file(tmp_path):
    path = tmp_path / "s.sqlite"
    _unmigratable(path)
    with Store(path) as st:
        with pytest.raises(StoreError, match="cannot migrate it from schema version 1"):
            with st.lock("test"):
                pass
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.sqlite"]
    out = subprocess.run(
        [sys.executable, "-m", "lcpbench.cli", "sweep", "--theta", "150", "--height", "3",
         "--links", "20", "--solvers", "active-set", "--settings", "default", "--baseline",
         "none", "--quiet", "--no-report", "--store", str(path)],
        capture_output=True, text=True, timeout=300)
    assert out.returncode == 2 and len(out.stderr.strip().splitlines()) == 1, out.stderr
    assert "Traceback" not in out.stderr and "cannot migrate it" in out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.sqlite"]


def test_a_waiter_granted_a_removed_lock_file_does_not_hold_the_lock(tmp_path, monkeypatch):
    """The interleaving that would let two holders in, forced step by step:

    1. A holds the lock; the waiter W has opened the lock file and waits on it.
    2. A releases: removes the file, closes it; W is granted the removed file.
    3. Before W goes on, C takes the lock: a new file at the path, free.
    4. W must not enter while C holds it: it starts again and waits on C's file.
    """
    path = tmp_path / "s.sqlite"
    Store(path).close()
    waiter, calls = {}, []
    waiting, granted, c_holds, decided = (threading.Event() for _ in range(4))

    def flock(fh, op):  # the waiter's flock, with the steps above made visible
        mine = threading.current_thread() is waiter.get("thread")
        if mine:
            calls.append(op)
            if len(calls) == 1:
                waiting.set()
            else:
                decided.set()  # W locks again: it found its file removed (step 4)
        fcntl.flock(fh, op)
        if mine and len(calls) == 1:
            granted.set()
            assert c_holds.wait(60)

    monkeypatch.setattr(store_lock, "fcntl", SimpleNamespace(
        flock=flock, LOCK_EX=fcntl.LOCK_EX, LOCK_NB=fcntl.LOCK_NB))
    c_inside, seen, errors = [False], [], []

    def wait_for_the_lock():
        try:
            with Store(path) as w, w.lock("waiter", wait=True) as sweep_id:
                info = json.loads(w.lock_path.read_text())
                seen.append((c_inside[0], info["sweep_id"] == sweep_id))
                decided.set()
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)
            decided.set()

    with Store(path) as a, Store(path) as c:
        with a.lock("A"):
            waiter["thread"] = threading.Thread(target=wait_for_the_lock)
            waiter["thread"].start()
            assert waiting.wait(60)
        assert granted.wait(60)  # W was granted the removed file
        with c.lock("C") as sweep_id:
            c_inside[0] = True
            assert json.loads(c.lock_path.read_text())["sweep_id"] == sweep_id
            c_holds.set()
            assert decided.wait(60)
            c_inside[0] = False
        waiter["thread"].join(60)
    assert not errors, errors
    assert seen == [(False, True)]  # W entered after C left, on the file at the path
    assert len(calls) >= 2 and sorted(p.name for p in tmp_path.iterdir()) == ["s.sqlite"]
