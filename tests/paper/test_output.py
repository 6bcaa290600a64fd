"""The CSV/JSON writers of a run (:mod:`lcpbench.paper.output`)."""

import csv
import json
import math

import numpy as np

from lcpbench.paper.output import Output, csv_cell, jsonable


def test_csv_cells_keep_full_precision():
    x = 1 / 3
    assert float(csv_cell(np.float64(x))) == x
    assert csv_cell([0.1, 2]) == "0.1 2"


def test_jsonable_turns_numpy_into_python():
    v = jsonable({1: np.arange(2), "b": np.bool_(True), "f": np.float32(0.5)})
    assert v == {"1": [0, 1], "b": True, "f": 0.5}
    assert type(v["1"][0]) is int and type(v["b"]) is bool


def test_output_writes_and_remembers(tmp_path):
    out = Output(tmp_path)
    out.csv("a.csv", [{"x": 1.0}, {"x": 2.0, "y": math.pi}])
    out.json("a.json", {"v": np.array([1.5])})
    assert out.files == ["a.csv", "a.json"]
    rows = list(csv.DictReader(open(tmp_path / "a.csv")))
    assert rows[1]["y"] == repr(math.pi) and rows[0]["y"] == ""
    assert json.loads((tmp_path / "a.json").read_text()) == {"v": [1.5]}
