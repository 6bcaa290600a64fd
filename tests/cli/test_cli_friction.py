"""`lcpbench solve --friction MU --left-end E --right-end E --pull N` (issue 39)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import lcpbench
from lcpbench.cli import main

ARGS = ["solve", "--theta", "150", "--height", "3", "--links", "30", "--friction", "0.3",
        "--left-end", "slider", "--right-end", "slider"]


def test_solve_friction_json_is_the_library_path(capsys):
    """Route against route: the CLI is a front end to the same call, so the
    library's answer is the expectation; what is tested is that the options pass
    through and the answer is printed."""
    code = main([*ARGS, "--pull", "0.05", "--json"])
    d = json.loads(capsys.readouterr().out)
    scene = lcpbench.ActuatorScene(theta=150, height=3, links=30, friction=0.3,
                                   left_end="slider", right_end="slider", pull=0.05)
    (ref,) = lcpbench.solve_path(scene)
    assert code == 0 and d["converged"] and d["route"] == "frictional"
    for key in ("tangential_forces", "stick", "slip", "forces"):
        assert len(d[key]) == scene.links - 1
    np.testing.assert_allclose(d["tangential_forces"], ref.tangential_forces, rtol=0,
                               atol=1e-15)
    assert d["stick"] == ref.stick.tolist()
    assert sum(d["tangential_forces"]) == pytest.approx(-0.05, rel=1e-6)  # ΣT + P = 0
    assert {k: d["units"][k] for k in ("tangential_forces", "slip", "forces", "pull")} == {
        "tangential_forces": "N", "slip": "mm", "forces": "N", "pull": "N"}
    assert set(d["units"]) <= set(d)  # every unit names a field


def test_solve_friction_gross_slip_is_exit_1(capsys):
    code = main([*ARGS, "--pull", "0.5"])
    out = capsys.readouterr().out
    assert code == 1 and "gross slip" in out


@pytest.mark.parametrize("argv,words", [
    (["--friction", "-1"], "friction must be"),
    (["--friction", "abc"], "--friction"),
    (["--friction", "0.3", "--pull", "0.1"], "pull acts on the right end"),
    (["--left-end", "slider", "--right-end", "slider"], "nothing holds the chain"),
    (["--friction", "0.3", "--right-end", "slider", "--sensitivities"], "--sensitivities"),
    (["--friction", "0.3", "--left-end", "free", "--right-end", "free", "--channel"],
     "cannot both be 'free'"),
    (["--friction", "0.3", "--right-end", "free"], "needs channel=True"),
    (["--friction", "0.3", "--right-end", "slider", "--links", "auto"], "--links auto"),
    (["--friction", "nan"], "friction must be"),
    (["--friction", "inf"], "friction must be"),
    (["--friction", "0.3", "--left-end", "slider", "--right-end", "slider", "--pull", "nan"],
     "pull must be"),
])
def test_solve_bad_friction_input_is_one_line_exit_2(argv, words, capsys):
    code = main(["solve", "--links", "20", *argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0] and "Traceback" not in err[0]


def test_solve_without_friction_options_is_unchanged(capsys):
    code = main(["solve", "--links", "30", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and "friction" not in d["scene"] and "tangential_forces" not in d
