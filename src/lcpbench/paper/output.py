"""The files of a ``reproduce`` run: CSV and JSON writers that remember what they wrote.

Floats are written in full precision (``repr``) so that every figure can be
redrawn, and every number the README quotes recomputed, from its files.

Nothing is written in place: every file goes to a staging folder first, and
:meth:`Output.finish` moves into the output folder only the files whose
content changed beyond round-off (:func:`same_numbers`: every number within
``rtol`` relatively or ``atol`` absolutely, the rest of the text equal; a
figure or other binary file byte for byte). Regenerating committed results
therefore rewrites only what changed (measured times, new numbers).
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

#: Two numbers agree to round-off when |a − b| <= RTOL·max(|a|, |b|) + ATOL (and, in
#: a CSV column, + RTOL·the column's largest magnitude). 1e-6 and not 1e-15: many
#: numbers here are differences of converged solves (the change of the force from
#: one N to the next, the baseline's disagreement with the LCP), where the solves'
#: own round-off, ~1e-14 of the force, is ~1e-8 of the difference or more; a real
#: change of the model moves them far more, and the README quotes 2-4 digits.
RTOL = 1e-6
ATOL = 1e-12


class Output:
    """Writes the files of a run into one directory and remembers them.

    Files are staged and moved into ``root`` by :meth:`finish`, each only if
    it differs from the file already there beyond round-off.
    """

    def __init__(self, root: Path, rtol: float = RTOL, atol: float = ATOL):
        self.root = Path(root)
        self.rtol, self.atol = rtol, atol
        self.files: list[str] = []
        self.written: list[str] = []
        self.unchanged: list[str] = []
        self.root.mkdir(parents=True, exist_ok=True)
        self._stage = Path(tempfile.mkdtemp(prefix=".staging-", dir=self.root))

    def path(self, name: str) -> Path:
        """Where to write ``name`` (in the staging folder until :meth:`finish`)."""
        self.files.append(name)
        return self._stage / name

    def json(self, name: str, data: object) -> None:
        with open(self.path(name), "w") as f:
            json.dump(jsonable(data), f, indent=1, allow_nan=True)
            f.write("\n")

    def csv(self, name: str, rows: list[dict]) -> None:
        head: list[str] = []
        for r in rows:
            head += [k for k in r if k not in head]
        with open(self.path(name), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=head)
            w.writeheader()
            for r in rows:
                w.writerow({k: csv_cell(v) for k, v in r.items()})

    def finish(self) -> None:
        """Move each staged file into ``root`` if it changed beyond round-off."""
        try:
            for name in dict.fromkeys(self.files):
                new = self._stage / name
                if not new.is_file():
                    continue
                old = self.root / name
                if old.is_file() and same_content(old, new, self.rtol, self.atol):
                    self.unchanged.append(name)
                    continue
                os.replace(new, old)
                self.written.append(name)
        finally:
            shutil.rmtree(self._stage, ignore_errors=True)


def same_content(old: Path, new: Path, rtol: float = RTOL, atol: float = ATOL) -> bool:
    """True when ``new`` says what ``old`` says, to round-off (by file type)."""
    a, b = old.read_bytes(), new.read_bytes()
    if a == b:
        return True
    suffix = new.suffix.lower()
    try:
        if suffix == ".json":
            return same_numbers(json.loads(a), json.loads(b), rtol, atol)
        if suffix == ".csv":
            return _same_csv(a.decode(), b.decode(), rtol, atol)
    except (ValueError, UnicodeDecodeError):
        return False
    return False


def _same_csv(a: str, b: str, rtol: float, atol: float) -> bool:
    """Same header and cells; numbers to round-off of their column's largest magnitude."""
    rows_a = list(csv.reader(io.StringIO(a)))
    rows_b = list(csv.reader(io.StringIO(b)))
    if len(rows_a) != len(rows_b) or not rows_a or rows_a[0] != rows_b[0]:
        return False
    width = len(rows_a[0])
    scale = [0.0] * width
    for row in rows_a[1:] + rows_b[1:]:
        if len(row) != width:
            return False
        for j, cell in enumerate(row):
            x = _number(cell)
            if x is not None and math.isfinite(x):
                scale[j] = max(scale[j], abs(x))
    return all(same_numbers(x, y, rtol, atol + rtol * scale[j])
               for ra, rb in zip(rows_a[1:], rows_b[1:])
               for j, (x, y) in enumerate(zip(ra, rb)))


def _number(v: object) -> float | None:
    if isinstance(v, bool):
        return None
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, str):
        try:
            return float(v)
        except ValueError:
            return None
    return None


def same_numbers(a: object, b: object, rtol: float = RTOL, atol: float = ATOL) -> bool:
    """Equal structures whose numbers agree within ``rtol``/``atol`` (NaN equals NaN).

    Strings that read as numbers (CSV cells, space-separated sequences in a
    cell) are compared as numbers; every other string must be equal.
    """
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_numbers(a[k], b[k], rtol, atol) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same_numbers(x, y, rtol, atol) for x, y in zip(a, b))
    x, y = _number(a), _number(b)
    if x is not None and y is not None:
        if math.isnan(x) or math.isnan(y):
            return math.isnan(x) and math.isnan(y)
        if math.isinf(x) or math.isinf(y):
            return x == y
        return abs(x - y) <= rtol * max(abs(x), abs(y)) + atol
    if isinstance(a, str) and isinstance(b, str) and " " in a.strip() and " " in b.strip():
        return same_numbers(a.split(), b.split(), rtol, atol) if a != b else True
    return a == b


def csv_cell(v: object) -> object:
    """A CSV cell: floats in full precision, sequences space-separated."""
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, (list, tuple, np.ndarray)):
        return " ".join(str(csv_cell(x)) for x in v)
    return v


def jsonable(v: object) -> object:
    """``v`` with numpy scalars and arrays turned into plain Python."""
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return [jsonable(x) for x in v.tolist()]
    if isinstance(v, (np.floating,)):
        return float(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


