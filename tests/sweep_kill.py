"""A sweep killed without warning once its first run is stored (the resume tests)."""

import os
import signal
import sqlite3
import subprocess
import time


def stored_runs(path) -> int:
    """The runs in the store at ``path`` (0 where it cannot be read yet)."""
    try:
        with sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=5) as db:
            return db.execute("SELECT COUNT(*) FROM runs").fetchone()[0]
    except sqlite3.Error:
        return 0


def killed_after_first_run(command, tmp_path, runs: int, *, group: bool, attempts: int = 3):
    """``(store, process)``: ``command(store)`` run in a session of its own and killed
    (SIGKILL: its whole process group where ``group``, else the process alone) once its
    first run is stored, with some of its ``runs`` and not all. Where the poll saw the
    first run only after the last (a loaded machine can keep it off a core that long: the
    suite's other worker), the sweep runs again into a new store, up to ``attempts``
    times. The caller kills what the process left (``os.killpg(process.pid, ...)``)."""
    for attempt in range(attempts):
        store = tmp_path / f"killed-{attempt}.sqlite"
        proc = subprocess.Popen(command(store), start_new_session=True,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 120
        while stored_runs(store) < 1 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.005)
        (os.killpg if group else os.kill)(proc.pid, signal.SIGKILL)
        proc.wait()
        if 1 <= stored_runs(store) < runs:
            return store, proc
        try:  # what this attempt left
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    raise AssertionError(f"the sweep was not killed in the middle in {attempts} attempts")
