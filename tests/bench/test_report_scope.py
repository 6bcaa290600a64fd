"""A sweep's report: where it goes, what it covers, what it says is missing or expected.

Issue 15: a scratch store never writes into results/sweep/; a small sweep into a
store that holds other runs reports its own runs; the back-ends that did not run
are listed with why; failures are split into documented (expected) and not.
"""

import csv

from lcpbench.bench.expected import OFF_REFERENCE, is_expected, never_converges
from lcpbench.bench.report import default_out
from lcpbench.bench.store import Store
from lcpbench.cli import main

SMALL = ["--height", "3", "--links", "20", "--settings", "default", "--baseline", "none",
         "--jobs", "1", "--quiet"]


def test_default_report_folder_follows_the_store(tmp_path):
    assert default_out("results/lcpbench.sqlite").as_posix() == "results/lcpbench-report"
    assert default_out(tmp_path / "scratch.db") == tmp_path / "scratch-report"


def test_scratch_sweep_writes_beside_its_store_not_into_results(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "--theta", "150", "--solvers", "active-set", "--store", "scratch.db",
                 *SMALL]) == 0
    assert (tmp_path / "scratch-report" / "report.md").exists()
    assert not (tmp_path / "results").exists()
    assert "scratch-report/report.md" in capsys.readouterr().out


def test_report_covers_this_sweep_unless_all(tmp_path, capsys):
    store = str(tmp_path / "s.sqlite")
    assert main(["sweep", "--theta", "120", "--solvers", "active-set", "--store", store,
                 "--no-report", *SMALL]) == 0
    # the second sweep: another scene and another back-end into the same store
    out = tmp_path / "mine"
    assert main(["sweep", "--theta", "150", "--solvers", "lemke", "--store", store,
                 "--out", str(out), *SMALL]) == 0
    with (out / "runs.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [(r["backend"], float(r["theta"])) for r in rows] == [("lemke", 150.0)]
    md = (out / "report.md").read_text()
    assert "`lemke`" in md and "| `active-set`" not in md
    assert "1 runs of the sweep that built it (2 in the store" in md
    assert "of 2 in the store" in capsys.readouterr().out
    everything = tmp_path / "all"
    assert main(["sweep", "--theta", "150", "--solvers", "lemke", "--store", store,
                 "--out", str(everything), "--all", *SMALL]) == 0
    with (everything / "runs.csv").open() as f:
        assert {r["backend"] for r in csv.DictReader(f)} == {"active-set", "lemke"}


def test_missing_siconos_is_announced_and_reported(tmp_path, monkeypatch, capsys):
    # a Siconos Python that does not exist: the bridge's back-ends are not installed
    monkeypatch.setenv("LCPBENCH_SICONOS_PYTHON", str(tmp_path / "no-python"))
    out = tmp_path / "r"
    assert main(["sweep", "--theta", "150", "--solvers", "active-set", "--store",
                 str(tmp_path / "s.sqlite"), "--out", str(out), *SMALL]) == 0
    # back-ends named explicitly: one line for the rest, no install hints
    err = capsys.readouterr().err
    assert sum("not in --solvers" in ln for ln in err.splitlines()) == 1
    assert "not installed" not in err
    # the main job (every installed back-end) says which are missing and how to install
    from lcpbench.cli.sweep import _print_backends

    _print_backends(["active-set"], explicit=False, main_job=True)
    err = capsys.readouterr().err
    line = next(ln for ln in err.splitlines() if "siconos-lemke" in ln)
    assert line.startswith("skipping") and "apt-get install python3-siconos" in line
    md = (out / "report.md").read_text()
    section = md.split("## Back-ends without runs here", 1)[1].split("##", 1)[0]
    siconos = next(ln for ln in section.splitlines() if "`siconos-pgs`" in ln)
    assert "not installed: apt-get install python3-siconos" in siconos


def test_expected_failures_are_the_documented_ones():
    # README: PGS-type back-ends never converge on a contact step
    assert is_expected("pgs", "high", "not_converged")
    assert is_expected("siconos-newton-min", "default", "not_converged")
    # docs/bench.md: the baselines are invalid without contact or at small h
    assert is_expected("baseline-fd", "-", "invalid")
    # README: since the result judge no run is converged off the reference (never
    # expected); the QP back-ends the README names fail on part of the scenes, which is
    # expected but neither makes them "never converge" nor rules them out of selection
    assert not is_expected("osqp", "default", OFF_REFERENCE)
    assert is_expected("clarabel", "high", "not_converged")
    assert never_converges("clarabel") is None and never_converges("pgs") is not None
    assert not is_expected("qpsolvers-daqp", "default", "not_converged")
    # anything else is a surprise
    assert not is_expected("active-set", "default", "not_converged")
    assert not is_expected("pgs", "default", "timeout")


def test_report_counts_expected_and_unexpected(tmp_path):
    from lcpbench.bench.grid import Grid
    from lcpbench.bench.report import build_report
    from lcpbench.bench.sweep import plan_sweep, sweep

    path = tmp_path / "s.sqlite"
    jobs = plan_sweep(Grid(theta=(150.0,), height=(2.0,), links=(30,)), ["active-set"],
                      ["default"], baselines=("baseline",))
    with Store(path) as st:
        sweep(st, jobs, workers=1)
        build_report(st, tmp_path / "r", plots=False)
        runs = st.runs(arrays=False)
    base = next(r for r in runs if r["backend"] == "baseline")
    # at h = 2 mm the one-reaction baseline bows out through the wall (paper Fig. 27b)
    assert base["status"] == "invalid"
    md = (tmp_path / "r" / "report.md").read_text()
    assert "1 unsuccessful runs: **1 expected**" in md and "**0 unexpected**" in md


def test_standalone_report_covers_the_last_sweep_unless_all(tmp_path, capsys):
    store = str(tmp_path / "s.sqlite")
    assert main(["sweep", "--theta", "120", "--solvers", "active-set", "--store", store,
                 "--no-report", *SMALL]) == 0
    assert main(["sweep", "--theta", "150,160", "--solvers", "lemke", "--store", store,
                 "--no-report", *SMALL]) == 0
    capsys.readouterr()
    out = tmp_path / "last"
    assert main(["report", "--store", store, "--out", str(out), "--no-plots"]) == 0
    with (out / "runs.csv").open() as f:
        rows = list(csv.DictReader(f))
    # the second sweep's grid (two scenes) and back-end, nothing of the first
    assert sorted((r["backend"], float(r["theta"])) for r in rows) == [
        ("lemke", 150.0), ("lemke", 160.0)]
    captured = capsys.readouterr()
    assert "report of 2 runs (of 3 in the store; --all for all)" in captured.out
    assert "the last sweep" in captured.err
    everything = tmp_path / "all"
    assert main(["report", "--store", store, "--out", str(everything), "--no-plots",
                 "--all"]) == 0
    with (everything / "runs.csv").open() as f:
        assert sorted(r["backend"] for r in csv.DictReader(f)) == [
            "active-set", "lemke", "lemke"]


def test_report_of_a_store_without_plans_reports_everything(tmp_path, capsys):
    from lcpbench.bench.grid import Grid
    from lcpbench.bench.sweep import plan_sweep, sweep

    path = tmp_path / "s.sqlite"
    jobs = plan_sweep(Grid(theta=(150.0,), height=(3.0,), links=(20,)), ["active-set"],
                      ["default"], baselines=())
    with Store(path) as st:  # the library's sweep, no CLI: no plan recorded
        sweep(st, jobs, workers=1)
        assert st.last_plan() is None
    assert main(["report", "--store", str(path), "--out", str(tmp_path / "r"),
                 "--no-plots"]) == 0
    assert "no sweep plan recorded" in capsys.readouterr().err


def test_plan_round_trips_keys_product_or_not(tmp_path):
    keys = {(s, b, p, t, "globalised") for s in ("a", "b") for b in ("x", "y")
            for p, t in (("default", 1e-3), ("high", 1e-9))}
    odd = {("c", "z", "-", 1e-10, "hybr")}
    with Store(tmp_path / "s.sqlite") as st:
        st.put_plan("one", keys)
        assert st.last_plan()[2] == keys
        st.put_plan("two", keys | odd)  # not a product of scenes and combinations
        sweep_id, _, got = st.last_plan()
        assert sweep_id == "two" and got == keys | odd
