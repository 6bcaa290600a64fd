"""``lcpbench report --format qpbenchmark``: the store's runs as qpbenchmark's results CSV."""

import math

import numpy as np
import pytest

from lcpbench.bench.grid import Grid
from lcpbench.bench.store import Store
from lcpbench.bench.sweep import plan_sweep, sweep
from lcpbench.bench.testset import SWEEP_RESULTS, read_results
from lcpbench.cli import main

#: qpbenchmark's results columns, as qpbenchmark/results.py (Results.__init__) lists them
QPBENCHMARK_COLUMNS = ["problem", "solver", "settings", "runtime", "found", "primal_residual",
                       "dual_residual", "duality_gap"]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("qpb")
    # θ = 10° clears the wall (no contact), θ = 150° at h = 3 mm touches it
    grid = Grid(theta=(10.0, 150.0), height=(3.0,), links=(20,))
    jobs = plan_sweep(grid, ["active-set", "lemke"], ["default", "high"], baselines=("baseline",))
    with Store(tmp / "s.sqlite") as st:
        sweep(st, jobs, workers=2)
        runs = st.runs(arrays=False)
    assert main(["report", "--format", "qpbenchmark", "--store", str(tmp / "s.sqlite"),
                 "--out", str(tmp / "out")]) == 0
    return runs, tmp / "out" / SWEEP_RESULTS


def test_the_columns_are_qpbenchmarks(exported):
    _, path = exported
    with open(path) as fh:
        assert fh.readline().strip().split(",") == QPBENCHMARK_COLUMNS
        found = {line.split(",")[4] for line in fh}
    assert found <= {"True", "False"}  # what pandas reads as a boolean column


def test_qpbenchmarks_results_loader_reads_it(exported):
    _, path = exported
    pandas = pytest.importorskip("pandas")
    # what qpbenchmark.Results does with an existing CSV: concat onto its typed frame,
    # then check that "found" is boolean
    empty = pandas.DataFrame([], columns=QPBENCHMARK_COLUMNS).astype(
        {"problem": str, "solver": str, "settings": str, "runtime": float, "found": bool,
         "primal_residual": float, "dual_residual": float, "duality_gap": float})
    df = pandas.concat([empty, pandas.read_csv(path)])
    assert isinstance(df["found"].dtype, np.dtypes.BoolDType)
    assert not df.duplicated(subset=["problem", "solver", "settings"]).any()


def test_one_row_per_run_found_means_converged(exported):
    runs, path = exported
    rows = read_results(path)
    assert len(rows) == len(runs) == 2 * (2 * 2 + 1)
    assert {r["settings"] for r in rows} == {"default", "high_accuracy"}
    assert {r["solver"] for r in rows} == {"active-set", "lemke", "baseline"}
    by_solver = {}
    for r in rows:
        by_solver.setdefault((r["solver"], r["settings"]), []).append(r)
    for run in runs:
        settings = {"default": "default", "high": "high_accuracy", "-": "default"}[
            run["settings"]]
        mine = [r for r in by_solver[(run["backend"], settings)]
                if ("T10-" in r["problem"]) == (run["theta"] == 10.0)]
        assert len(mine) == 1
        assert mine[0]["found"] == bool(run["converged"])
        assert mine[0]["runtime"] == pytest.approx(run["wall_time"], rel=1e-12)


def test_residuals_follow_the_physics(exported):
    """No contact: no reaction, nothing to complement, nothing penetrated: the gap
    exactly 0, the primal residual 0 to the round-off of the closure (the right pin's
    height, a sum of N = 20 terms a·sin α: a few ulps of ℓ). In contact, every converged
    answer is feasible to the judge's allowance (penetration 1e-6 ℓ) and balanced
    (torque residual small)."""
    _, path = exported
    rows = [r for r in read_results(path) if r["found"]]
    assert rows
    free = [r for r in rows if "-T10-" in r["problem"]]
    touch = [r for r in rows if "-T150-" in r["problem"]]
    assert free and touch
    for r in free:
        assert r["primal_residual"] <= 1e-15 and r["duality_gap"] == 0.0
    for r in rows:
        vals = (r["primal_residual"], r["dual_residual"], r["duality_gap"])
        assert all(math.isfinite(v) and v >= 0 for v in vals)
        assert r["primal_residual"] <= 1e-6 and r["dual_residual"] <= 1e-3


def test_an_unknown_format_exits_2(tmp_path, capsys):
    assert main(["report", "--format", "csv", "--store", str(tmp_path / "none.sqlite")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--format" in err[0]
