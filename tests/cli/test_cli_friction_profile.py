"""`lcpbench solve --wall-profile ... --friction MU` and `lcpbench anchor --wall-profile`
(issue 39 with walls of any profile, docs/friction.md)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from lcpbench.cli import main
from lcpbench.problems.walls import load_profile_csv

PROFILES = Path(__file__).resolve().parents[2] / "examples" / "profiles"


def test_solve_with_a_wall_profile_and_friction_json(capsys):
    """The frictional route against examples/profiles/stenosis.csv: converged, the JSON
    names the profile, and the state balances along x with the normal reactions' x parts
    (the slopes read from the CSV's profile itself)."""
    argv = ["solve", "--theta", "150", "--wall-profile", str(PROFILES / "stenosis.csv"),
            "--friction", "0.3", "--left-end", "slider", "--right-end", "slider",
            "--pull", "0.02", "--links", "30", "--tol", "1e-10", "--json"]
    code = main(argv)
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and d["converged"], d["reason"]
    assert d["scene"]["wall_profile"]["name"] == "stenosis.csv"
    h1 = load_profile_csv(PROFILES / "stenosis.csv").slope(np.array(d["x"])[1:-1])
    c = np.sqrt(1 + h1 * h1)
    N, T = np.array(d["forces"]), np.array(d["tangential_forces"])
    assert abs(0.02 + N @ (h1 / c) + T @ (1 / c)) <= 1e-9 * d["total_force"]


def test_anchor_with_a_wall_profile(capsys):
    """anchor on a ramp (examples/profiles/ramp.csv, h from 2.5 to 3.5 mm): P* is the
    pull gross slip balances, the capacity Σ N (μ t_x − n_x), not μ ΣN."""
    code = main(["anchor", "--theta", "150", "--wall-profile", str(PROFILES / "ramp.csv"),
                 "--friction", "0.3", "--links", "30", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and d["converged"], d["reason"]
    assert d["pull_out_force"] == pytest.approx(d["capacity"], rel=1e-5)
    assert d["capacity"] < 0.3 * d["normal_force_total"]  # the rising wall pushes along +x
    assert 1 <= d["solves"] <= 20


def test_a_free_end_with_a_wall_profile_is_one_line(capsys):
    code = main(["solve", "--theta", "150", "--wall-profile", str(PROFILES / "stenosis.csv"),
                 "--channel", "--friction", "0.3", "--right-end", "free", "--links", "30"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "free end" in err[0]
