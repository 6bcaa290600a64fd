"""The files of a ``reproduce`` run: CSV and JSON writers that remember what they wrote.

Floats are written in full precision (``repr``) so that every figure can be
redrawn, and every number the README quotes recomputed, from its files.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np


class Output:
    """Writes the files of a run into one directory and remembers them."""

    def __init__(self, root: Path):
        self.root = root
        self.files: list[str] = []

    def path(self, name: str) -> Path:
        self.files.append(name)
        return self.root / name

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


