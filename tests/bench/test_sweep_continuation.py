"""`lcpbench sweep --continuation`: lines in θ as jobs, rows checked against cold runs.

The expected values come from properties (a warm start changes the path, not
the equilibrium; the first scene of a line has no neighbour, so it is a cold
solve; resuming skips exactly what is stored) or from independent runs (the
cold sweep of the same scenes, the per-scene reference), never from the
continuation code's own output.
"""

import json
import shutil
import sqlite3
from dataclasses import asdict

import numpy as np
import pytest

from lcpbench.bench.grid import Grid, hard_scenes, scene_key
from lcpbench.bench.metrics import error_of, evaluate, success_tol, time_table
from lcpbench.bench.report import build_report
from lcpbench.bench.store import Store
from lcpbench.bench.sweep import plan_sweep, sweep
from lcpbench.cli import main
from lcpbench.errors import ProblemError
from lcpbench.problems.scenes import ActuatorScene

# Two lines of five bend angles (N = 20): in contact from about 100 deg at h = 3 mm.
THETAS = (100.0, 120.0, 140.0, 160.0, 180.0)
GRID = Grid(theta=THETAS, height=(3.0, 5.0), links=(20,))
TIGHT = 1e-10  # rad: the driver tolerance of the "high" runs here
LABEL = "globalised+secant"  # the tests run the secant predictor explicitly


def _plan(continuation=None):
    """settings default at the paper's 1e-3 rad, and high at TIGHT; no baselines."""
    jobs = (plan_sweep(GRID, ["active-set"], ["default"], baselines=(),
                       continuation=continuation)
            + plan_sweep(GRID, ["active-set"], ["high"], tol=TIGHT, baselines=(),
                         continuation=continuation))
    return list(dict.fromkeys(jobs))  # the references appear in both halves


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    path = tmp_path_factory.mktemp("cont") / "s.sqlite"
    calls = []
    with Store(path) as st:
        cold_plan = sweep(st, _plan(), workers=2)
        cont_plan = sweep(st, _plan("secant"), workers=2,
                          progress=lambda d, t, j, r: calls.append((d, t, j.scene, j.kind)))
        runs, refs = st.runs(), st.refs()
    return path, cold_plan, cont_plan, calls, runs, refs


def _rest(key):
    d = json.loads(key)
    d.pop("theta")
    return d


# -- the plan ---------------------------------------------------------------------------------
def test_plan_has_one_line_job_per_line_backend_and_settings():
    # scenes handed over out of order: the lines must still be theta-ascending
    grid = Grid(theta=(140.0, 100.0, 180.0, 120.0, 160.0), height=(3.0, 5.0), links=(20, 30))
    backends, settings = ["active-set", "lemke"], ["default", "high"]
    cold = plan_sweep(grid, backends, settings)
    cont = plan_sweep(grid, backends, settings, continuation="secant")
    lines = [j for j in cont if j.kind == "line"]
    # 2 heights x 2 link counts = 4 lines, each for every back-end and settings
    assert len(lines) == 2 * 2 * len(backends) * len(settings)
    assert not any(j.kind == "run" for j in cont)
    for j in lines:
        thetas = [json.loads(k)["theta"] for k in j.scenes]
        assert thetas == sorted(THETAS)
        assert all(_rest(k) == _rest(j.scenes[0]) for k in j.scenes)
        assert j.label == LABEL and j.scene == j.scenes[0] and j.size == 5
    # the line rows are exactly the cold runs' (scene, back-end, settings, tol)
    row_keys = [k[:4] for j in lines for k in j.keys]
    assert len(row_keys) == len(set(row_keys))
    assert set(row_keys) == {j.key[:4] for j in cold if j.kind == "run"}
    # references and baselines do not change
    assert [j for j in cont if j.kind in ("ref", "baseline")] == \
        [j for j in cold if j.kind in ("ref", "baseline")]
    hash(lines[0])  # still a frozen, hashable job


def test_plan_groups_a_list_of_scenes_into_lines():
    scenes = hard_scenes()
    jobs = plan_sweep(scenes, ["active-set"], ["default"], baselines=(),
                      continuation="previous")
    lines = [j for j in jobs if j.kind == "line"]
    groups = {json.dumps({k: v for k, v in asdict(s).items() if k != "theta"}, sort_keys=True)
              for s in scenes}
    assert len(lines) == len(groups)
    covered = [k for j in lines for k in j.scenes]
    assert sorted(covered) == sorted(scene_key(s) for s in scenes)
    for j in lines:
        thetas = [json.loads(k)["theta"] for k in j.scenes]
        assert thetas == sorted(thetas) and j.label == "globalised+previous"
    assert max(j.size for j in lines) > 1 and min(j.size for j in lines) == 1


def test_plan_refuses_the_undamped_driver_and_unknown_predictors():
    for method in ("undamped", ["globalised", "undamped"]):
        with pytest.raises(ProblemError, match="--continuation"):
            plan_sweep(GRID, ["active-set"], ["default"], method=method,
                       continuation="secant")
    with pytest.raises(ProblemError, match="continuation"):
        plan_sweep(GRID, ["active-set"], ["default"], continuation="magic")


# -- a real sweep -----------------------------------------------------------------------------
def test_one_row_per_scene_and_settings_with_its_own_label(swept):
    _, cold_plan, cont_plan, calls, runs, _ = swept
    cont = [r for r in runs if r["method"] == LABEL]
    cold = [r for r in runs if r["method"] == "globalised"]
    assert len(cont) == len(cold) == len(GRID) * 2
    assert {(r["scene"], r["settings"]) for r in cont} == \
        {(r["scene"], r["settings"]) for r in cold}
    assert {r["method"] for r in runs} == {"globalised", LABEL}
    # the second sweep ran 2 lines x 2 settings (references already stored)
    assert len(cont_plan.todo) == 4 and all(j.kind == "line" for j in cont_plan.todo)
    # progress: one call per stored row, counting rows (10 refs + 20 line rows)
    assert len(calls) == 20 and calls[-1][:2] == (30, 30)
    assert [c[0] for c in calls] == list(range(11, 31))
    assert sorted(c[2] for c in calls) == sorted(r["scene"] for r in cont)


def test_continuation_reaches_the_cold_equilibrium(swept):
    *_, runs, refs = swept
    cold = {(r["scene"], r["settings"]): r for r in runs if r["method"] == "globalised"}
    for r in runs:
        if r["method"] != LABEL:
            continue
        c = cold[(r["scene"], r["settings"])]
        assert r["converged"] and r["tol"] == c["tol"]
        scale = r["EI"] / r["length"] ** 2
        # against the independent reference (1e-11 rad): the success criterion of its tol
        assert error_of(r["total_force"], refs[r["scene"]]["total_force"], scale) \
            <= success_tol(r["tol"])
        if r["tol"] == TIGHT:
            # at 1e-10 rad warm and cold runs end at the same equilibrium: both within
            # 100*tol = 1e-8 of the force (what an exact back-end reaches at that tol)
            assert error_of(r["total_force"], c["total_force"], scale) <= 1e-8
            assert np.max(np.abs(r["forces"] - c["forces"])) <= 1e-8 * max(
                c["total_force"], scale)


def test_first_scene_of_each_line_is_a_cold_solve(swept):
    *_, runs, _ = swept
    first = {(json.dumps(_rest(r["scene"])), r["settings"]): r for r in runs
             if r["method"] == "globalised" and r["theta"] == THETAS[0]}
    assert len(first) == 4
    for r in runs:
        if r["method"] == LABEL and r["theta"] == THETAS[0]:
            c = first[(json.dumps(_rest(r["scene"])), r["settings"])]
            # no neighbour before it: the same computation as the cold run, bit for bit
            assert r["outer_iterations"] == c["outer_iterations"]
            np.testing.assert_array_equal(r["forces"], c["forces"])


def test_secant_continuation_takes_fewer_outer_iterations_at_1e_3(swept):
    # Checked beforehand as a property of the secant predictor: on lines of 4-7
    # angles (60-180 deg) at h = 2-5 mm, N = 20 and 30, warm totals were 8-15
    # against cold 19-31 at 1e-3 rad.
    *_, runs, _ = swept
    totals = {}
    for r in runs:
        if r["settings"] == "default":
            t = totals.setdefault(r["height"], {"globalised": 0, LABEL: 0})
            t[r["method"]] += r["outer_iterations"]
    assert set(totals) == {3.0, 5.0}
    for t in totals.values():
        assert t[LABEL] <= t["globalised"]


# -- resume -----------------------------------------------------------------------------------
def test_resume_skips_complete_lines_and_reruns_a_partial_one_in_full(swept, tmp_path):
    path, *_, runs, _ = swept
    copy = tmp_path / "copy.sqlite"
    shutil.copy(path, copy)
    jobs = _plan("secant")
    with Store(copy) as st:
        assert sweep(st, jobs).todo == []
    # one line (h = 3 mm, default): drop its last row and spoil its first
    line = [r for r in runs if r["method"] == LABEL and r["height"] == 3.0
            and r["settings"] == "default"]
    first, last = min(line, key=lambda r: r["theta"]), max(line, key=lambda r: r["theta"])
    with sqlite3.connect(copy) as db:
        db.execute("DELETE FROM runs WHERE scene = ? AND method = ? AND settings = 'default'",
                   (last["scene"], LABEL))
        db.execute("UPDATE runs SET total_force = -1, outer_iterations = -1 WHERE scene = ? "
                   "AND method = ? AND settings = 'default'", (first["scene"], LABEL))
    rows = []
    with Store(copy) as st:
        plan = sweep(st, jobs, progress=lambda d, t, j, r: rows.append(j.scene))
        again = {(r["scene"], r["settings"], r["method"]): r for r in st.runs()}
    assert len(plan.todo) == 1 and plan.todo[0].kind == "line"
    assert sorted(rows) == sorted(r["scene"] for r in line)  # the whole line, once each
    assert len(again) == len(runs)
    for r in line:  # rewritten, the spoilt row included, with the first run's numbers
        new = again[(r["scene"], "default", LABEL)]
        assert new["outer_iterations"] == r["outer_iterations"]
        np.testing.assert_array_equal(new["forces"], r["forces"])


def test_a_line_that_crashes_or_hangs_costs_a_row_per_unstored_scene(
        tmp_path, misbehaving_backends):
    scenes = [ActuatorScene(theta=t, height=3.0, links=20) for t in (120.0, 150.0)]
    keys = [scene_key(s) for s in scenes]
    jobs = [j for j in plan_sweep(scenes, ["test-crash", "test-hang"], ["default"],
                                  baselines=(), continuation="secant") if j.kind == "line"]
    with Store(tmp_path / "f.sqlite") as st:
        # the crash line's first scene is already stored: a failure must not overwrite it
        kept = {"scene": keys[0], "backend": "test-crash", "settings": "default",
                "tol": 1e-3, "method": LABEL, "status": "solved", "converged": True,
                "reason": "stored before", "total_force": 1.0, "outer_iterations": 1}
        st.put_run(kept)
        plan = sweep(st, jobs, workers=2, time_limit=5.0)  # room for worker start-up under load
        rows = {(r["backend"], json.loads(r["scene"])["theta"]): r
                for r in st.runs(arrays=False)}
    assert len(plan.todo) == 2  # the partly stored line runs again
    assert len(rows) == 4
    assert rows[("test-crash", 120.0)]["reason"] == "stored before"
    assert rows[("test-crash", 150.0)]["status"] == "crashed"
    for t in (120.0, 150.0):
        hang = rows[("test-hang", t)]
        # the time limit of a line of 2 scenes is 2 x 5 s
        assert hang["status"] == "timeout" and "10 s" in hang["reason"]
        assert not hang["converged"]


# -- the command line ---------------------------------------------------------------------------
def _one_line_error(capsys, args, *words):
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    for w in words:
        assert w in err
    return err


def test_cli_refuses_bad_continuation_input(capsys, tmp_path):
    store = tmp_path / "never.sqlite"
    base = ["sweep", "--theta", "120,150", "--height", "3", "--links", "20", "--solvers",
            "active-set", "--baseline", "none", "--store", str(store), "--quiet"]
    _one_line_error(capsys, [*base, "--continuation", "bogus"], "--continuation", "bogus")
    _one_line_error(capsys, [*base, "--continuation", "--method", "undamped"],
                    "--continuation", "undamped")
    _one_line_error(capsys, [*base, "--method", "globalised,undamped", "--continuation"],
                    "--continuation")
    assert not store.exists()  # refused before anything ran


def test_cli_continuation_sweep(capsys, tmp_path):
    store = tmp_path / "cli.sqlite"
    args = ["sweep", "--theta", "120:180:30", "--height", "3", "--links", "20", "--solvers",
            "active-set", "--settings", "default", "--baseline", "none", "--jobs", "1",
            "--store", str(store), "--quiet", "--no-report"]
    assert main([*args, "--continuation", "previous"]) == 0
    assert "continuation" in capsys.readouterr().out
    with Store(store) as st:
        runs = st.runs(arrays=False)
    assert sorted(r["theta"] for r in runs) == [120.0, 150.0, 180.0]
    assert {r["method"] for r in runs} == {"globalised+previous"}
    # given without a value: the adaptive predictor (solve_many's), stored apart from the first run
    assert main([*args, "--continuation"]) == 0
    with Store(store) as st:
        methods = sorted(r["method"] for r in st.runs(arrays=False))
    assert methods == ["globalised+adaptive"] * 3 + ["globalised+previous"] * 3


# -- the report -----------------------------------------------------------------------------------
def test_report_compares_continuation_with_cold(swept, tmp_path):
    path, *_, runs, _ = swept
    with Store(path) as st:
        info = build_report(st, tmp_path / "r", plots=False)
    md = (tmp_path / "r" / "report.md").read_text()
    assert "## Continuation against cold starts" in md
    assert "## Back-ends compared" in md and "## Unsuccessful runs" in md
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    by_settings = {r["settings"]: r for r in summary if r["method"] == LABEL}
    assert not any("continuation" in r for r in summary if r["method"] == "globalised")
    for settings, r in by_settings.items():
        cold = sum(x["outer_iterations"] for x in runs
                   if x["settings"] == settings and x["method"] == "globalised")
        warm = sum(x["outer_iterations"] for x in runs
                   if x["settings"] == settings and x["method"] == LABEL)
        c = r["continuation"]
        assert (c["outer_cold"], c["outer_continuation"]) == (cold, warm)
        assert c["ratio"] == pytest.approx(cold / warm) and c["scenes"] == len(GRID)
        assert f"| {cold} | {warm} | {cold / warm:.2f} |" in md
    assert len(info["continuation"]) == 2
    tight = by_settings["high"]["continuation"]
    assert tight["force_difference_max"] <= 1e-8


def test_no_section_without_cold_runs_and_table_two_shows_cold_runs_only(swept, tmp_path):
    path, *_ = swept
    copy = tmp_path / "warm-only.sqlite"
    shutil.copy(path, copy)
    with sqlite3.connect(copy) as db:
        db.execute("DELETE FROM runs WHERE method = 'globalised'")
    with Store(copy) as st:
        build_report(st, tmp_path / "r", plots=False)
        evaluated = evaluate(st.runs(), st.refs())
    assert "Continuation against cold" not in (tmp_path / "r" / "report.md").read_text()
    # Table II is the cold globalised driver's: continuation rows do not land in it
    _, cells, _ = time_table(evaluated, 3.0)
    assert "active-set" not in cells
