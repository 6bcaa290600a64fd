"""``lcpbench solve --formulation``: the form each step is handed in, and its errors."""

import json

from lcpbench.cli import main


def test_solve_formulation_json_says_what_ran(capsys):
    code = main(["solve", "--links", "30", "--theta", "150", "--height", "3", "--solver",
                 "lemke", "--formulation", "reactions", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and d["converged"] and d["formulation"] == "reactions"


def test_solve_formulation_default_json_unchanged(capsys):
    main(["solve", "--links", "30", "--json"])
    assert "formulation" not in json.loads(capsys.readouterr().out)


def test_bad_formulation_is_one_line_and_status_2(capsys):
    for args in (["--formulation", "squares"], ["--solver", "lemke", "--formulation", "lifted"]):
        code = main(["solve", "--links", "30", *args])
        err = capsys.readouterr().err.strip()
        assert code == 2 and "\n" not in err and "formulation" in err
        assert "Traceback" not in err
