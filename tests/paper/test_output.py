"""The CSV/JSON writers of a run (:mod:`lcpbench.paper.output`)."""

import csv
import json
import math

import numpy as np

from lcpbench.paper.output import Output, csv_cell, jsonable, same_numbers


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
    assert not (tmp_path / "a.csv").exists()  # staged until finish()
    out.finish()
    assert out.written == ["a.csv", "a.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.csv", "a.json"]  # no staging
    rows = list(csv.DictReader(open(tmp_path / "a.csv")))
    assert rows[1]["y"] == repr(math.pi) and rows[0]["y"] == ""
    assert json.loads((tmp_path / "a.json").read_text()) == {"v": [1.5]}


def test_round_off_rule():
    assert same_numbers({"f": 0.4021}, {"f": 0.4021 * (1 + 2e-10)})  # the issue's 2e-10
    assert not same_numbers({"f": 0.4021}, {"f": 0.4021 * (1 + 1e-5)})
    assert same_numbers([1e-17], [-3e-17])  # round-off around zero
    assert same_numbers(["0.1 0.2", "x"], ["0.10000000000001 0.2", "x"])
    assert not same_numbers(["x"], ["y"]) and not same_numbers([1.0], [1.0, 2.0])
    assert same_numbers(float("nan"), float("nan")) and not same_numbers(1.0, float("nan"))


def _run(root, data, rows):
    out = Output(root)
    out.json("d.json", data)
    out.csv("d.csv", rows)
    out.finish()
    return out


def test_files_that_changed_only_at_round_off_are_left_alone(tmp_path):
    import os

    first = _run(tmp_path, {"force": 0.4021, "n": 140}, [{"x": 1 / 3}])
    assert first.written == ["d.json", "d.csv"]
    for name in ("d.json", "d.csv"):
        os.utime(tmp_path / name, (1e9, 1e9))  # an old modification time
    before = {n: (tmp_path / n).read_bytes() for n in ("d.json", "d.csv")}
    again = _run(tmp_path, {"force": 0.4021 * (1 + 2e-10), "n": 140},
                 [{"x": 1 / 3 * (1 - 1e-12)}])
    assert again.written == [] and again.unchanged == ["d.json", "d.csv"]
    for name, data in before.items():
        assert (tmp_path / name).read_bytes() == data
        assert (tmp_path / name).stat().st_mtime == 1e9
    changed = _run(tmp_path, {"force": 0.41, "n": 140}, [{"x": 1 / 3}])
    assert changed.written == ["d.json"] and changed.unchanged == ["d.csv"]
    assert json.loads((tmp_path / "d.json").read_text())["force"] == 0.41


def test_csv_round_off_is_judged_against_its_column(tmp_path):
    """A disagreement of 2e-8 % beside one of 50 % in the same column (fig26): the small
    one's change of 5e-5 relative is round-off of the column, not a new result."""
    from lcpbench.paper.output import same_content

    old, new = tmp_path / "old.csv", tmp_path / "new.csv"
    old.write_text("theta,percent\n10,50.0\n20,1.99232e-08\n")
    new.write_text("theta,percent\n10,50.0\n20,1.99222e-08\n")
    assert same_content(old, new)
    new.write_text("theta,percent\n10,50.1\n20,1.99232e-08\n")
    assert not same_content(old, new)
    new.write_text("theta,percent,extra\n10,50.0,1\n20,1.99232e-08,1\n")
    assert not same_content(old, new)
