"""`lcpbench solve --wall-stiffness K --pressure-limit P` (elastic walls, issue 17)."""

from __future__ import annotations

import json

import pytest

import lcpbench
from lcpbench.cli import main


def test_solve_elastic_wall_reports_pressure_and_the_limit(capsys):
    code = main(["solve", "--links", "40", "--wall-stiffness", "0.1",
                 "--pressure-limit", "0.01"])
    out = capsys.readouterr().out
    assert code == 0
    assert "wall k=0.1 N/mm per mm" in out
    assert "contact pressure" in out and "pressure limit    EXCEEDED" in out


def test_solve_elastic_json_matches_library(capsys):
    """Route against route: the CLI is a front end to the same call, so the
    library's answer is the expectation; what is tested is that the options pass
    through and the answer is printed."""
    code = main(["solve", "--links", "40", "--wall-stiffness", "0.3", "--json"])
    d = json.loads(capsys.readouterr().out)
    ref = lcpbench.solve(lcpbench.ActuatorScene(links=40, wall_stiffness=0.3))
    assert code == 0 and d["scene"]["wall_stiffness"] == 0.3
    assert d["total_force"] == pytest.approx(ref.total_force, rel=1e-12)
    assert d["max_pressure"] == pytest.approx(ref.max_pressure, rel=1e-12)
    assert d["max_indentation"] > 0 and d["pressure_exceeded"] is False


@pytest.mark.parametrize("argv,word", [
    (["--wall-stiffness", "-2"], "wall_stiffness"),
    (["--wall-stiffness", "nan"], "wall_stiffness"),
    (["--wall-stiffness", "0"], "wall_stiffness"),
    (["--pressure-limit", "-1"], "pressure_limit"),
])
def test_solve_bad_elastic_input_is_one_line_exit_2(argv, word, capsys):
    code = main(["solve", "--links", "20", *argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and word in err[0]


@pytest.mark.parametrize("argv", [
    ["solve", "--links", "30", "--sections", "150:30", "--wall-stiffness", "1"],
    ["sweep", "--grid", "anchoring", "--wall-stiffness", "1"],
])
def test_elastic_walls_with_sections_are_one_line_exit_2(argv, capsys, tmp_path):
    code = main([*argv] + (["--store", str(tmp_path / "s.sqlite")] if argv[0] == "sweep"
                           else []))
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "wall-stiffness" in err[0]
