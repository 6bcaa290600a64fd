"""The friction grid (issue 39): pull-out over μ × pressure × h, resumable."""

from __future__ import annotations

import csv

import pytest

import lcpbench
from lcpbench.bench.friction_grid import FrictionGrid, friction_rows, run_friction_grid
from lcpbench.bench.store import Store
from lcpbench.cli import main

GRID = FrictionGrid(friction=(0.0, 0.2, 0.4), pressure=(103.42, 172.37), height=(4.5,),
                    links=30)


def test_grid_pull_out_is_zero_without_friction_and_mu_sum_n_with_it():
    with Store.in_memory() as store:
        done, there = run_friction_grid(store, GRID)
        rows = friction_rows(store)
    assert (done, there) == (len(GRID), 0) and len(rows) == len(GRID)
    for r in rows:
        assert r["converged"], r
        if r["friction"] == 0:  # nothing holds the chain along x
            assert r["pull_out_force"] == 0.0
            plain = lcpbench.solve(lcpbench.ActuatorScene(
                theta=r["theta"], height=r["height"], links=30, channel=True), tol=1e-10)
            assert r["normal_force_total"] == pytest.approx(plain.total_force, rel=1e-9)
        else:  # gross slip on flat walls: P* = μ ΣN(P*), and ΣN falls as the pull grows,
            # so from the last state held (pull P_h): P_h <= P* <= μ ΣN(P_h)
            P, Ph = r["pull_out_force"], r["held_pull"]
            muN = r["friction"] * r["normal_force_total"]  # μ as given, ΣN as stored
            assert 0 < Ph <= P <= muN * (1 + 1e-9)
            assert P == pytest.approx(muN, rel=1e-5)


def test_grid_resumes_computing_only_the_missing_points(tmp_path):
    path = tmp_path / "s.sqlite"
    part = FrictionGrid(friction=(0.0, 0.2), pressure=(172.37,), height=(4.5,), links=30)
    full = FrictionGrid(friction=(0.0, 0.2, 0.4), pressure=(172.37,), height=(4.5,),
                        links=30)
    with Store(path) as store:
        assert run_friction_grid(store, part) == (2, 0)
    with Store(path) as store:
        assert run_friction_grid(store, full) == (1, 2)
        assert run_friction_grid(store, full) == (0, 3)
        assert len(friction_rows(store, full)) == 3
        assert run_friction_grid(store, part, rerun=True) == (2, 0)
    with Store.in_memory() as fresh:  # --rerun into a new store
        assert run_friction_grid(fresh, part, rerun=True) == (2, 0)


def test_sweep_grid_friction_cli_writes_csv_in_newtons(tmp_path, capsys):
    store, out = tmp_path / "f.sqlite", tmp_path / "rep"
    code = main(["sweep", "--grid", "friction", "--friction", "0,0.3", "--pressure",
                 "172.37", "--height", "4.5", "--links", "30", "--store", str(store),
                 "--out", str(out), "--quiet"])
    assert code == 0
    with open(out / "pull-out.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r["friction"]) for r in rows] == [0.0, 0.3]
    assert float(rows[0]["pull_out_force_n"]) == 0.0
    assert float(rows[1]["pull_out_force_n"]) == pytest.approx(
        0.3 * float(rows[1]["normal_force_total_n"]), rel=1e-5)


@pytest.mark.parametrize("argv,words", [
    (["--theta", "100"], "takes no --theta"),
    (["--friction", "-0.2"], "friction must be"),
    (["--links", "30,40"], "one --links"),
])
def test_sweep_grid_friction_bad_input_is_one_line_exit_2(argv, words, tmp_path, capsys):
    code = main(["sweep", "--grid", "friction", *argv, "--store", str(tmp_path / "x.db")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0]


def test_friction_list_is_only_for_the_friction_grid(tmp_path, capsys):
    code = main(["sweep", "--friction", "0.3", "--store", str(tmp_path / "x.db")])
    assert code == 2 and "--grid friction" in capsys.readouterr().err
