"""Metrics and the report, from a small stored sweep."""

import math

import pytest

from lcpbench.bench.grid import Grid
from lcpbench.bench.metrics import (
    error_of,
    evaluate,
    shifted_geometric_mean,
    success_tol,
    summarise,
    time_table,
)
from lcpbench.bench.report import build_report
from lcpbench.bench.store import Store
from lcpbench.bench.sweep import plan_sweep, sweep


def test_shifted_geometric_mean_by_hand():
    assert shifted_geometric_mean([0.0, 0.0]) == pytest.approx(0.0, abs=1e-12)
    assert shifted_geometric_mean([10.0, 30.0]) == pytest.approx(math.sqrt(20 * 40) - 10)
    assert shifted_geometric_mean([5.0], shift=1.0) == pytest.approx(5.0)
    # shift-invariant ordering and bounded by the arithmetic mean
    v = [1.0, 4.0, 100.0]
    assert shifted_geometric_mean(v) <= sum(v) / 3
    with pytest.raises(ValueError):
        shifted_geometric_mean([-1.0])


def test_error_and_success_rules():
    assert error_of(0.402, 0.4, 0.0356) == pytest.approx(0.002 / 0.4)
    assert error_of(0.001, 0.0, 0.0356) == pytest.approx(0.001 / 0.0356)  # no contact
    assert error_of(float("nan"), 0.4, 0.0356) == math.inf
    assert success_tol(1e-3) == 1e-3 and success_tol(1e-6) == pytest.approx(1e-4)
    assert success_tol(1e-9) == pytest.approx(1e-7)


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    path = tmp_path_factory.mktemp("rep") / "s.sqlite"
    grid = Grid(theta=(60.0, 150.0, 180.0), height=(2.0, 5.0), links=(30,))
    jobs = plan_sweep(grid, ["active-set", "lemke", "pgs"], ["default", "high"])
    with Store(path) as st:
        sweep(st, jobs, workers=2)
    return path


def test_summary_rows(store):
    with Store(store) as st:
        ev = evaluate(st.runs(), st.refs())
    summary = summarise(ev)
    by = {(r["backend"], r["settings"]): r for r in summary}
    assert set(by) == {(b, s) for b in ("active-set", "lemke", "pgs")
                       for s in ("default", "high")} | {("baseline", "-")}
    for b in ("active-set", "lemke"):  # exact methods: every run a success
        for s in ("default", "high"):
            assert by[b, s]["success"] == 1.0 and by[b, s]["runs"] == 6
    # PGS at 'high' stops on its sweep budget or with a last step the runner marks
    # inaccurate (force error ~1e-6 > the 1e-7 threshold of driver tol 1e-9): never all
    assert by["pgs", "high"]["success"] < 1.0
    for (b, s), r in by.items():  # the 'converged but off' count, recounted by hand
        off = [e for e in ev if (e.backend, e.settings) == (b, s) and e.row["converged"]
               and e.error > success_tol(e.row["tol"])]
        assert r["converged_but_off"] == len(off)
    assert min(r["time_sgm_rel"] for r in summary) == pytest.approx(1.0)
    assert min(r["error_sgm_rel"] for r in summary) == pytest.approx(1.0)
    # the baseline is valid where a single midspan reaction is right (h >= 4 mm) only
    assert 0.0 < by["baseline", "-"]["success"] < 1.0
    # a success is within its threshold of the reference by construction
    for e in ev:
        if e.success:
            assert e.error <= success_tol(e.row["tol"])


def test_table_two_is_normalised_to_its_fastest(store):
    with Store(store) as st:
        ev = evaluate(st.runs(), st.refs())
    thetas, cells, best_ms = time_table(ev, 2.0)
    assert thetas == [60.0, 150.0, 180.0] and best_ms > 0
    values = [v for row in cells.values() for v in row.values() if v is not None]
    assert min(values) == pytest.approx(1.0) and all(v >= 1.0 for v in values)


def test_report_files(store, tmp_path):
    with Store(store) as st:
        info = build_report(st, tmp_path, plots=True)
    md = (tmp_path / "report.md").read_text()
    for b in ("active-set", "lemke", "pgs", "baseline"):
        assert f"`{b}`" in md
    assert "Table II" in md and "work-precision.png" in md
    for f in ("runs.csv", "summary.json", "work-precision.png", "force-vs-theta.png",
              "shapes.png"):
        assert (tmp_path / f).stat().st_size > 0
    assert info["runs"] == 3 * 2 * (3 * 2 + 1)
