"""The results store: one SQLite file a sweep writes to and a report reads from.

Every finished run is committed on its own, so a sweep killed at any moment
(SIGKILL included) loses at most the runs that were still being computed;
SQLite's journal rolls back a half-written commit the next time the file is
opened. A run is identified by (scene, back-end, settings, tol, method): a
restarted sweep skips what is already there, and ``replace=True`` (the
CLI's ``--rerun``) overwrites it. Nothing else ever overwrites a row.

A file that is not an lcpbench store raises
:class:`~lcpbench.errors.StoreError` in one line and is left untouched: it
is inspected through a read-only, immutable connection, so SQLite neither
rolls back its ``-journal`` nor replays its ``-wal`` (their bytes and the
file's stay as they are, no ``-shm`` is made) and no lock file is created.
Refused: not SQLite, a failed integrity check, an empty file (0 bytes), an
SQLite database with no tables, or with only views or other programs'
tables, a ``meta`` table of another shape, a newer schema version, or
missing ``runs``/``refs`` tables. Only a store found to be lcpbench's is then
opened as usual (SQLite rolls back a hot journal of its own there) and
checked for integrity.

Sweeps take an exclusive lock (:meth:`Store.lock`): ``flock`` on
``<store>.lock`` beside the store, which records who holds it (pid, host,
start time, owner, sweep id) and is removed when the lock is released
(:mod:`.store_lock`). A second sweep on the same store gets a StoreError
naming the holder, or waits with ``wait=True``. The kernel drops the lock
when its process dies, so a stale lock file never blocks. Every run
written while the lock is held carries its ``sweep_id``, so a report can
count only what one sweep wrote (``Store.runs(sweep_id=...)``).
:meth:`Store.in_memory` is a store without a file (its lock: no lock file).

Tables
------
``runs``        one row per (scene, back-end, settings, tol, method): status,
                forces, gaps, shape, iterations, times, certificate, and the
                ``sweep_id`` of the sweep that wrote it (NULL: written
                without a lock, or before schema 2).
``refs``        the per-scene high-accuracy reference, computed once.
``sweeps``      one row per locked sweep: id, owner, pid, host, start time,
                and its machine record (JSON, :mod:`.machine`).
``meta``        schema version and when the store was created.
``plans``       what each ``lcpbench sweep`` set out to run (its run keys, as
                scenes × (back-end, settings, tol, method)), so ``lcpbench
                report`` can cover the runs of the last sweep. Optional: made
                on first use, absent in older stores (no schema change).

Schema versions: 1 (no ``sweep_id``, no ``sweeps``) and 2 (no timing
columns ``setup_time``, ``repeats``, ``wall_time_min``, ``wall_time_max``,
no ``sweeps.machine``) are read as they are (the missing columns read as
None: not measured) and migrated to 3, one transaction per version, the first
time they are written to (a run, or a lock); a version above
:data:`SCHEMA_VERSION` is refused.
"""

from __future__ import annotations

import csv
import json
import os
import socket
import sqlite3
import time
import uuid
from contextlib import contextmanager, nullcontext
from pathlib import Path

import numpy as np

from ..errors import StoreError
from .store_lock import hold_lock

SCHEMA_VERSION = 3
#: Older versions this lcpbench reads, and migrates when it writes.
READABLE_VERSIONS = (1, 2, 3)
DEFAULT_STORE = Path("results") / "lcpbench.sqlite"

RUN_KEY = ("scene", "backend", "settings", "tol", "method")
SCENE_COLUMNS = ("theta", "height", "links", "length", "EI", "weight", "channel")
ARRAYS = ("forces", "gaps", "x", "y")
RUN_SCALARS = (
    "status", "converged", "reason", "total_force", "outer_iterations", "inner_iterations",
    "wall_time", "solver_time", "certificate", "version", "created",
)
#: schema 3: the setup part of the wall time, and the repeats (wall_time is their median)
TIMING_COLUMNS = ("setup_time", "repeats", "wall_time_min", "wall_time_max")
REF_SCALARS = ("total_force", "converged", "tol", "check_error", "wall_time", "reason",
               "created")

_SCHEMA = f"""
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS runs (
    scene TEXT NOT NULL, backend TEXT NOT NULL, settings TEXT NOT NULL,
    tol REAL NOT NULL, method TEXT NOT NULL,
    theta REAL, height REAL, links INTEGER, length REAL, EI REAL, weight REAL, channel INTEGER,
    status TEXT NOT NULL, converged INTEGER NOT NULL, reason TEXT, total_force REAL,
    outer_iterations INTEGER, inner_iterations INTEGER, wall_time REAL, solver_time REAL,
    certificate TEXT, version TEXT, created TEXT,
    forces BLOB, gaps BLOB, x BLOB, y BLOB, sweep_id TEXT,
    setup_time REAL, repeats INTEGER, wall_time_min REAL, wall_time_max REAL,
    PRIMARY KEY ({", ".join(RUN_KEY)})
);
CREATE TABLE IF NOT EXISTS sweeps (
    sweep_id TEXT PRIMARY KEY, owner TEXT, pid INTEGER, host TEXT, started TEXT,
    machine TEXT
);
CREATE TABLE IF NOT EXISTS refs (
    scene TEXT PRIMARY KEY,
    theta REAL, height REAL, links INTEGER, length REAL, EI REAL, weight REAL, channel INTEGER,
    total_force REAL, converged INTEGER, tol REAL, check_error REAL, wall_time REAL,
    reason TEXT, created TEXT,
    forces BLOB, gaps BLOB, x BLOB, y BLOB
);
"""

_PLANS = """
CREATE TABLE IF NOT EXISTS plans (
    sweep_id TEXT PRIMARY KEY, started TEXT, scenes TEXT NOT NULL, combos TEXT NOT NULL
);
"""

_MIGRATE_1_TO_2 = """
BEGIN;
ALTER TABLE runs ADD COLUMN sweep_id TEXT;
CREATE TABLE IF NOT EXISTS sweeps (
    sweep_id TEXT PRIMARY KEY, owner TEXT, pid INTEGER, host TEXT, started TEXT
);
UPDATE meta SET value = '2' WHERE key = 'schema';
COMMIT;
"""
_MIGRATE_2_TO_3 = """
BEGIN;
ALTER TABLE runs ADD COLUMN setup_time REAL;
ALTER TABLE runs ADD COLUMN repeats INTEGER;
ALTER TABLE runs ADD COLUMN wall_time_min REAL;
ALTER TABLE runs ADD COLUMN wall_time_max REAL;
ALTER TABLE sweeps ADD COLUMN machine TEXT;
UPDATE meta SET value = '3' WHERE key = 'schema';
COMMIT;
"""
_MIGRATIONS = {1: _MIGRATE_1_TO_2, 2: _MIGRATE_2_TO_3}
#: Columns an existing store must have, per table (a subset check).
_REQUIRED = {
    "meta": ("key", "value"),
    "runs": (*RUN_KEY, *SCENE_COLUMNS, *RUN_SCALARS, *ARRAYS),
    "refs": ("scene", *SCENE_COLUMNS, *REF_SCALARS, *ARRAYS),
}


def _blob(values) -> bytes | None:
    return None if values is None else np.asarray(values, dtype="<f8").tobytes()


def _array(blob) -> np.ndarray | None:
    return None if blob is None else np.frombuffer(blob, dtype="<f8").copy()


class Store:
    """An lcpbench results store at ``path`` (created, with its folder, if absent).

    Use as a context manager, or call :meth:`close`.

    Parameters
    ----------
    path : str or path-like
        The SQLite file.
    create : bool
        Create the store if the file does not exist (else StoreError).

    Attributes
    ----------
    schema : int
        The schema version of the file (1 until first written to, then 2).
    sweep_id : str or None
        The id of the sweep holding :meth:`lock` through this object; stamped
        on every run :meth:`put_run` writes meanwhile.
    """

    def __init__(self, path: str | os.PathLike = DEFAULT_STORE, *, create: bool = True):
        self.path = Path(path)
        self.memory = False
        self.sweep_id: str | None = None
        self.schema = SCHEMA_VERSION
        where = f"store {self.path}"
        if self.path.is_dir():
            raise StoreError(f"{where}: is a folder; give a file path (e.g. "
                             f"{self.path / 'lcpbench.sqlite'})")
        exists = self.path.exists()
        if not exists and not create:
            raise StoreError(f"{where}: no such file (run `lcpbench sweep` first)")
        if exists:
            if self.path.stat().st_size == 0:
                raise StoreError(f"{where}: an empty file (0 bytes), not an lcpbench store; "
                                 "it was left as it is: remove it or pass another --store")
            self._inspect()  # before anything may recover, write or lock it
        else:
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise StoreError(f"{where}: cannot create its folder ({exc})") from exc
        try:
            self.db = sqlite3.connect(self.path, timeout=30.0)
        except sqlite3.Error as exc:
            raise StoreError(f"{where}: cannot open it ({exc})") from exc
        try:
            if exists:  # lcpbench's: a hot journal of its own is rolled back here, and
                # the integrity is checked under SQLite's locks (a sweep may be writing)
                self.schema = self._check(self.db, integrity=True)
            else:
                self._create()
        except BaseException:
            self.db.close()
            raise

    @classmethod
    def in_memory(cls) -> Store:
        """A new store that lives in memory only (gone when closed); no file, no lock file."""
        store = cls.__new__(cls)
        store.path, store.sweep_id, store.schema = Path(":memory:"), None, SCHEMA_VERSION
        store.memory = True
        store.db = sqlite3.connect(":memory:")
        store._create()
        return store

    # -- opening ------------------------------------------------------------------
    def _inspect(self) -> int:
        """Check an existing file is an lcpbench store without letting SQLite touch it.

        Opened read-only and immutable: SQLite neither replays a ``-wal`` file nor
        rolls back a ``-journal`` (a foreign database's recovery is not ours to
        run), creates no ``-shm`` and takes no lock. Returns the schema version.
        """
        where = f"store {self.path}"
        try:
            uri = self.path.resolve().as_uri() + "?mode=ro&immutable=1"
            db = sqlite3.connect(uri, uri=True)
        except sqlite3.Error as exc:
            raise StoreError(f"{where}: cannot open it ({exc})") from exc
        try:
            # no integrity verdict here: without locks or recovery the file alone may be
            # mid-commit; it is checked once the store, found to be lcpbench's, is opened
            return self._check(db, integrity=False)
        finally:
            db.close()

    def _recovery_files(self) -> list[str]:
        """The store's ``-journal``/``-wal`` files that exist (SQLite would recover them)."""
        return [f"{self.path.name}{s}" for s in ("-journal", "-wal")
                if Path(f"{self.path}{s}").exists()]

    def _check(self, db: sqlite3.Connection, *, integrity: bool) -> int:
        """Refuse (StoreError, one line) what is not an lcpbench store; its schema version."""
        where = f"store {self.path}"
        beside = " and ".join(self._recovery_files())
        left = (f"it was left as it is{f' (with its {beside})' if beside else ''}: "
                "move it away or pass another --store")
        try:
            ok = db.execute("PRAGMA quick_check").fetchone()[0] if integrity else "ok"
            objects = db.execute("SELECT type, name FROM sqlite_master "
                                 "WHERE name NOT LIKE 'sqlite_%'").fetchall()
            tables = {name for kind, name in objects if kind == "table"}
            columns = {t: [r[1] for r in db.execute(f"PRAGMA table_info({t})")]
                       for t in _REQUIRED if t in tables}
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"{where}: not a readable SQLite file ({exc}); {left}") from exc
        if ok != "ok":
            raise StoreError(f"{where}: fails SQLite's integrity check ({ok}); {left}")
        if "meta" not in tables:
            found = ", ".join(f"{k} {n}" for k, n in sorted(objects)) or "nothing"
            raise StoreError(f"{where}: an SQLite file that is not an lcpbench store "
                             f"(holds {found}); {left}")
        if columns["meta"] != list(_REQUIRED["meta"]):
            raise StoreError(f"{where}: its meta table has columns "
                             f"({', '.join(columns['meta'])}), not (key, value): not an "
                             f"lcpbench store; {left}")
        try:
            row = db.execute("SELECT value FROM meta WHERE key = 'schema'").fetchone()
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"{where}: not a readable SQLite file ({exc}); {left}") from exc
        found = "none" if row is None else str(row[0])
        if found not in {str(v) for v in READABLE_VERSIONS}:
            raise StoreError(f"{where}: schema version {found}, this lcpbench reads "
                             f"{', '.join(map(str, READABLE_VERSIONS))}; {left}")
        for table, need in _REQUIRED.items():
            missing = [c for c in need if c not in columns.get(table, [])]
            if missing:
                what = (f"no {table} table" if table not in columns else
                        f"table {table} lacks column(s) {', '.join(missing)}")
                raise StoreError(f"{where}: not a complete lcpbench store ({what}); {left}")
        return int(found)

    def _create(self) -> None:
        try:
            with self.db:
                self.db.executescript(_SCHEMA)
                self.db.execute("INSERT INTO meta VALUES ('schema', ?)", (str(SCHEMA_VERSION),))
                self.db.execute("INSERT INTO meta VALUES ('created', ?)", (_now(),))
        except sqlite3.Error as exc:
            raise StoreError(f"store {self.path}: cannot write to it ({exc})") from exc

    def _upgrade(self) -> None:
        """Migrate a schema-1 store to the current schema (one transaction)."""
        while self.schema < SCHEMA_VERSION:
            try:
                self.db.executescript(_MIGRATIONS[self.schema])
            except sqlite3.Error as exc:
                if self.db.in_transaction:
                    self.db.rollback()
                raise StoreError(f"store {self.path}: cannot migrate it from schema version "
                                 f"{self.schema} to {SCHEMA_VERSION} ({exc})") from exc
            self.schema += 1

    # -- the sweep lock -----------------------------------------------------------
    @property
    def lock_path(self) -> Path:
        """The lock file beside the store: ``<store>.lock``."""
        return self.path.with_name(self.path.name + ".lock")

    @contextmanager
    def lock(self, owner: str = "lcpbench sweep", *, wait: bool = False):
        """Hold the store's exclusive sweep lock; yields the new ``sweep_id``.

        Parameters
        ----------
        owner : str
            What holds the lock, shown to whoever finds it taken.
        wait : bool
            Block until the lock is free instead of raising.

        Yields
        ------
        str
            The sweep's id, also set as :attr:`sweep_id` (and recorded in the
            ``sweeps`` table) until the block ends.

        Raises
        ------
        StoreError
            ``"store X is locked by pid N on host H (owner, started T); ..."``
            when another sweep holds it and ``wait`` is False, or the lock file
            cannot be created.

        The lock file is removed when the block ends, also when it raises.
        """
        held = nullcontext() if self.memory else hold_lock(self.lock_path, self.path,
                                                           wait=wait)
        with held as fh:
            sweep_id = uuid.uuid4().hex
            info = {"pid": os.getpid(), "host": socket.gethostname(), "owner": owner,
                    "started": _now(), "sweep_id": sweep_id}
            if fh is not None:  # who holds it, for whoever finds it taken
                fh.write(json.dumps(info) + "\n")
                fh.flush()
            self._upgrade()
            self._write("INSERT INTO sweeps (sweep_id, owner, pid, host, started) "
                        "VALUES (?, ?, ?, ?, ?)", (sweep_id, owner, info["pid"], info["host"],
                                                   info["started"]))
            self.sweep_id = sweep_id
            try:
                yield sweep_id
            finally:
                self.sweep_id = None

    def close(self) -> None:
        self.db.close()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- writing ------------------------------------------------------------------
    def _write(self, sql: str, values: tuple) -> None:
        try:
            with self.db:  # one transaction per row: committed at once
                self.db.execute(sql, values)
        except sqlite3.Error as exc:
            raise StoreError(f"store {self.path}: cannot write to it ({exc})") from exc

    def put_run(self, row: dict, *, replace: bool = False) -> bool:
        """Insert one run (a dict with the key, scene columns, scalars and arrays).

        Returns False, writing nothing, when the run is already there and
        ``replace`` is False.
        """
        self._upgrade()
        row = {**row, "sweep_id": row.get("sweep_id", self.sweep_id)}
        cols = (*RUN_KEY, *SCENE_COLUMNS, *RUN_SCALARS, *ARRAYS, "sweep_id", *TIMING_COLUMNS)
        values = tuple(_blob(row.get(c)) if c in ARRAYS else _cell(row.get(c)) for c in cols)
        verb = "INSERT OR REPLACE" if replace else "INSERT OR IGNORE"
        before = self.db.total_changes
        self._write(f"{verb} INTO runs ({', '.join(cols)}) VALUES "
                    f"({', '.join('?' * len(cols))})", values)
        return self.db.total_changes > before

    def put_ref(self, row: dict, *, replace: bool = False) -> None:
        self._upgrade()
        cols = ("scene", *SCENE_COLUMNS, *REF_SCALARS, *ARRAYS)
        values = tuple(_blob(row.get(c)) if c in ARRAYS else _cell(row.get(c)) for c in cols)
        verb = "INSERT OR REPLACE" if replace else "INSERT OR IGNORE"
        self._write(f"{verb} INTO refs ({', '.join(cols)}) VALUES "
                    f"({', '.join('?' * len(cols))})", values)

    # -- reading ------------------------------------------------------------------
    def _query(self, sql: str) -> list[tuple]:
        try:
            return self.db.execute(sql).fetchall()
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"store {self.path}: cannot read it ({exc})") from exc

    def run_keys(self) -> set[tuple]:
        return set(self._query(f"SELECT {', '.join(RUN_KEY)} FROM runs"))

    def ref_keys(self) -> set[str]:
        return {r[0] for r in self._query("SELECT scene FROM refs")}

    def runs(self, *, arrays: bool = True, where: str = "", params: tuple = (),
             sweep_id: str | None = None) -> list[dict]:
        """Every run as a dict (arrays as numpy arrays when ``arrays``), in a fixed order.

        ``where``/``params``: an SQL ``WHERE`` clause and its values. ``sweep_id``:
        only the runs that sweep wrote (none, on a schema-1 store). Each row has
        a ``sweep_id`` key (None for runs written without a lock).
        """
        if sweep_id is not None:
            if self.schema < 2:
                return []
            where = f"{where} AND sweep_id = ?" if where else "WHERE sweep_id = ?"
            params = (*params, sweep_id)
        rows = self._rows("runs", RUN_KEY, arrays, where, params)
        for r in rows:
            r.setdefault("sweep_id", None)
            for c in TIMING_COLUMNS:  # stores before schema 3: not measured
                r.setdefault(c, None)
        return rows

    def sweeps(self) -> list[dict]:
        """The locked sweeps recorded in the store, oldest first (none on schema 1)."""
        if self.schema < 2:
            return []
        cols = ("sweep_id", "owner", "pid", "host", "started") + (
            ("machine",) if self.schema >= 3 else ())
        out = [dict(zip(cols, r)) for r in self._query(
            f"SELECT {', '.join(cols)} FROM sweeps ORDER BY started, rowid")]
        for d in out:
            d["machine"] = json.loads(d["machine"]) if d.get("machine") else None
        return out

    def put_machine(self, sweep_id: str, record: dict) -> None:
        """Record (or update) the machine record of a locked sweep (schema 3)."""
        self._upgrade()
        self._write("UPDATE sweeps SET machine = ? WHERE sweep_id = ?",
                    (json.dumps(record), sweep_id))

    def put_plan(self, sweep_id: str, keys) -> None:
        """Record the run keys a sweep set out to compute (for :meth:`last_plan`).

        Stored compactly as its scenes and its (back-end, settings, tol, method)
        combinations when the keys are exactly their product (every sweep's
        are), else as the full list of keys.
        """
        keys = {tuple(k) for k in keys}
        scenes = sorted({k[0] for k in keys})
        combos = sorted({k[1:] for k in keys}, key=repr)
        if len(keys) != len(scenes) * len(combos):  # not a product: every key
            scenes, combos = [], sorted(keys, key=repr)
        self._upgrade()
        try:
            with self.db:
                self.db.executescript(_PLANS)
                self.db.execute("INSERT OR REPLACE INTO plans VALUES (?, ?, ?, ?)",
                                (sweep_id, _now(), json.dumps(scenes), json.dumps(combos)))
        except sqlite3.Error as exc:
            raise StoreError(f"store {self.path}: cannot write to it ({exc})") from exc

    def last_plan(self) -> tuple[str, str, set[tuple]] | None:
        """(sweep id, when it started, its run keys) of the newest recorded sweep
        plan, or None (a store without plans: older, or written without the CLI)."""
        if not self._query("SELECT name FROM sqlite_master WHERE type = 'table' "
                           "AND name = 'plans'"):
            return None
        rows = self._query("SELECT sweep_id, started, scenes, combos FROM plans "
                           "ORDER BY started DESC, rowid DESC LIMIT 1")
        if not rows:
            return None
        sweep_id, started, scenes, combos = rows[0]
        scenes, combos = json.loads(scenes), [tuple(c) for c in json.loads(combos)]
        keys = ({(s, *c) for s in scenes for c in combos} if scenes else set(combos))
        return sweep_id, started, keys

    def refs(self, *, arrays: bool = True) -> dict[str, dict]:
        return {r["scene"]: r for r in self._rows("refs", ("scene",), arrays, "", ())}

    def _rows(self, table, order, arrays, where, params) -> list[dict]:
        try:
            cur = self.db.execute(f"SELECT * FROM {table} {where} ORDER BY "
                                  f"{', '.join(order)}", params)
            names = [d[0] for d in cur.description]
            records = cur.fetchall()
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"store {self.path}: cannot read it ({exc})") from exc
        out = []
        for values in records:
            row = dict(zip(names, values))
            for a in ARRAYS:
                row[a] = _array(row[a]) if arrays else None
            out.append(row)
        return out

    def count(self, table: str = "runs", *, sweep_id: str | None = None) -> int:
        """Rows of ``table``; of ``runs``, only those of ``sweep_id`` if given."""
        if sweep_id is None:
            return int(self._query(f"SELECT COUNT(*) FROM {table}")[0][0])
        return len(self.runs(arrays=False, sweep_id=sweep_id))

    def export_csv(self, path: str | os.PathLike, runs: list[dict] | None = None) -> int:
        """Write every run (or only ``runs``, rows of :meth:`runs`), joined with its
        reference force, as CSV; returns the row count."""
        rows = self.runs(arrays=False) if runs is None else [dict(r) for r in runs]
        refs = self.refs(arrays=False)
        cols = [*RUN_KEY, *SCENE_COLUMNS, *RUN_SCALARS, *TIMING_COLUMNS, "reference_force"]
        cols.remove("certificate")
        with open(path, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(cols)
            for r in rows:
                ref = refs.get(r["scene"])
                r["reference_force"] = None if ref is None else ref["total_force"]
                writer.writerow([_csv(r.get(c)) for c in cols])
        return len(rows)


def _cell(value):
    if isinstance(value, (dict, list)):
        return json.dumps(value)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, bool):
        return int(value)
    return value


def _csv(value):
    if isinstance(value, float):
        return repr(value)
    return "" if value is None else value


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S%z")

