"""`lcpbench cycle` (issue 39, item 6: the load–unload plot on the command line).

Expectations: the μ = 0 limit (both branches are lcpbench.solve of the same θ: no
hysteresis without friction), Coulomb's sense of the hysteresis
(friction holds the contact nodes back as the chain bends on the way up and in the
other sense on the way down: loading below, unloading above the frictionless force),
the calibration θ = 0.81 P + 9.78 (eq. 40), and one line with exit 2 on bad input.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import lcpbench
from lcpbench.cli import main

BASE = ["cycle", "--height", "5.5", "--channel", "--links", "20",
        "--pressure", "100:150:25"]


def _json(argv, capsys):
    code = main([*BASE, *argv, "--json"])
    return code, json.loads(capsys.readouterr().out)


def test_cycle_mu_zero_is_the_frictionless_solve_and_friction_makes_a_loop(capsys):
    code, d = _json(["--friction", "0,0.3"], capsys)
    assert code == 0
    p = np.array(d["pressure"])
    np.testing.assert_allclose(p, [100, 125, 150, 125, 100])  # up, then back down
    np.testing.assert_allclose(d["theta"], 0.81 * p + 9.78, rtol=0, atol=1e-12)
    ref = [lcpbench.solve(lcpbench.ActuatorScene(theta=t, height=5.5, links=20,
                                                 channel=True), tol=1e-8).total_force
           for t in d["theta"]]
    free, rough = d["cycles"]
    assert all(free["converged"]) and all(rough["converged"])
    np.testing.assert_allclose(free["force"], ref, rtol=1e-9)
    np.testing.assert_allclose(d["frictionless_force"], ref, rtol=1e-9)
    up, down = np.array(rough["force"][:2]), np.array(rough["force"][:2:-1])
    assert np.all(up < np.array(ref[:2])) and np.all(np.array(ref[:2]) < down)
    assert d["units"]["cycles.force"] == "N" and d["units"]["pressure"] == "kPa"


def test_cycle_text_and_plot(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    f = tmp_path / "cycle.png"
    code = main([*BASE, "--friction", "0.3", "--plot", str(f)])
    out = capsys.readouterr().out
    assert code == 0 and "mu = 0.3 up / down" in out and "every state" in out
    assert f.stat().st_size > 1000 and f.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("argv,words", [
    (["--friction", "-0.1"], "friction must be"),
    (["--friction", "abc"], "friction must be"),
    (["--friction", "0.3", "--pressure", "150,100"], "increasing"),
    (["--friction", "0.3", "--pressure", "0,0,10"], "each value once"),
    (["--friction", "0.3", "--pressure", "100,110,110,120"], "each value once"),
    (["--friction", "0.3", "--actuator", "7"], "actuator must be"),
    (["--friction", "0.3", "--tol", "nan"], "tol must be"),
])
def test_cycle_bad_input_is_one_line_exit_2(argv, words, capsys):
    code = main(["cycle", "--links", "20", *argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0] and "Traceback" not in err[0]
