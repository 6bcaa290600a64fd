"""The results store: one SQLite file a sweep writes to and a report reads from.

Every finished run is committed on its own, so a sweep killed at any moment
(SIGKILL included) loses at most the runs that were still being computed;
SQLite's journal rolls back a half-written commit the next time the file is
opened. A run is identified by (scene, back-end, settings, tol, method): a
restarted sweep skips what is already there, and ``replace=True`` (the
CLI's ``--rerun``) overwrites it. Nothing else ever overwrites a row.

A file that is not an lcpbench store (not SQLite, another program's
database, another schema version, a failed integrity check) raises
:class:`~lcpbench.errors.StoreError` and is left untouched.

Tables
------
``runs``        one row per (scene, back-end, settings, tol, method): status,
                forces, gaps, shape, iterations, times, certificate.
``refs``        the per-scene high-accuracy reference, computed once.
``meta``        schema version and when the store was created.
"""

from __future__ import annotations

import csv
import json
import os
import sqlite3
import time
from pathlib import Path

import numpy as np

from ..errors import StoreError

SCHEMA_VERSION = 1
DEFAULT_STORE = Path("results") / "lcpbench.sqlite"

RUN_KEY = ("scene", "backend", "settings", "tol", "method")
SCENE_COLUMNS = ("theta", "height", "links", "length", "EI", "weight", "channel")
ARRAYS = ("forces", "gaps", "x", "y")
RUN_SCALARS = (
    "status", "converged", "reason", "total_force", "outer_iterations", "inner_iterations",
    "wall_time", "solver_time", "certificate", "version", "created",
)
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
    forces BLOB, gaps BLOB, x BLOB, y BLOB,
    PRIMARY KEY ({", ".join(RUN_KEY)})
);
CREATE TABLE IF NOT EXISTS refs (
    scene TEXT PRIMARY KEY,
    theta REAL, height REAL, links INTEGER, length REAL, EI REAL, weight REAL, channel INTEGER,
    total_force REAL, converged INTEGER, tol REAL, check_error REAL, wall_time REAL,
    reason TEXT, created TEXT,
    forces BLOB, gaps BLOB, x BLOB, y BLOB
);
"""


def _blob(values) -> bytes | None:
    return None if values is None else np.asarray(values, dtype="<f8").tobytes()


def _array(blob) -> np.ndarray | None:
    return None if blob is None else np.frombuffer(blob, dtype="<f8").copy()


class Store:
    """An lcpbench results store at ``path`` (created, with its folder, if absent).

    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, path: str | os.PathLike = DEFAULT_STORE, *, create: bool = True):
        self.path = Path(path)
        if self.path.is_dir():
            raise StoreError(f"store {self.path}: is a folder; give a file path (e.g. "
                             f"{self.path / 'lcpbench.sqlite'})")
        exists = self.path.exists() and self.path.stat().st_size > 0
        if not exists and not create:
            raise StoreError(f"store {self.path}: no such file (run `lcpbench sweep` first)")
        if not exists:
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise StoreError(f"store {self.path}: cannot create its folder ({exc})") from exc
        try:
            self.db = sqlite3.connect(self.path, timeout=30.0)
        except sqlite3.Error as exc:
            raise StoreError(f"store {self.path}: cannot open it ({exc})") from exc
        try:
            self._check_or_create(exists)
        except BaseException:
            self.db.close()
            raise

    # -- opening ------------------------------------------------------------------
    def _check_or_create(self, exists: bool) -> None:
        where = f"store {self.path}"
        try:
            ok = self.db.execute("PRAGMA quick_check").fetchone()[0]
            tables = {r[0] for r in self.db.execute(
                "SELECT name FROM sqlite_master WHERE type = 'table'")}
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"{where}: not a readable SQLite file ({exc}); it was left as "
                             "it is: move it away or pass another --store") from exc
        if ok != "ok":
            raise StoreError(f"{where}: fails SQLite's integrity check ({ok}); it was left "
                             "as it is: move it away or pass another --store")
        if exists and tables and "meta" not in tables:
            raise StoreError(f"{where}: an SQLite file that is not an lcpbench store "
                             f"(tables {', '.join(sorted(tables))}); it was left as it is")
        if "meta" in tables:
            row = self.db.execute("SELECT value FROM meta WHERE key = 'schema'").fetchone()
            if row is None or row[0] != str(SCHEMA_VERSION):
                found = "none" if row is None else row[0]
                raise StoreError(f"{where}: schema version {found}, this lcpbench writes "
                                 f"{SCHEMA_VERSION}; it was left as it is: move it away or "
                                 "pass another --store")
            return
        try:
            with self.db:
                self.db.executescript(_SCHEMA)
                self.db.execute("INSERT INTO meta VALUES ('schema', ?)", (str(SCHEMA_VERSION),))
                self.db.execute("INSERT INTO meta VALUES ('created', ?)", (_now(),))
        except sqlite3.Error as exc:
            raise StoreError(f"{where}: cannot write to it ({exc})") from exc

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
        cols = (*RUN_KEY, *SCENE_COLUMNS, *RUN_SCALARS, *ARRAYS)
        values = tuple(_blob(row.get(c)) if c in ARRAYS else _cell(row.get(c)) for c in cols)
        verb = "INSERT OR REPLACE" if replace else "INSERT OR IGNORE"
        before = self.db.total_changes
        self._write(f"{verb} INTO runs ({', '.join(cols)}) VALUES "
                    f"({', '.join('?' * len(cols))})", values)
        return self.db.total_changes > before

    def put_ref(self, row: dict, *, replace: bool = False) -> None:
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

    def runs(self, *, arrays: bool = True, where: str = "", params: tuple = ()) -> list[dict]:
        """Every run as a dict (arrays as numpy arrays when ``arrays``), in a fixed order."""
        return self._rows("runs", RUN_KEY, arrays, where, params)

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

    def count(self, table: str = "runs") -> int:
        return int(self._query(f"SELECT COUNT(*) FROM {table}")[0][0])

    def export_csv(self, path: str | os.PathLike) -> int:
        """Write every run, joined with its reference force, as CSV; returns the row count."""
        rows = self.runs(arrays=False)
        refs = self.refs(arrays=False)
        cols = [*RUN_KEY, *SCENE_COLUMNS, *RUN_SCALARS, "reference_force"]
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

