"""Performance and data profiles: by hand, from their definitions' properties, and in a report."""

import csv
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lcpbench.bench.grid import Grid
from lcpbench.bench.metrics import evaluate
from lcpbench.bench.profiles import (
    cost_matrix,
    data_profile,
    performance_profile,
    performance_ratios,
    read_csv,
    write_csv,
)
from lcpbench.bench.report import build_report
from lcpbench.bench.store import Store
from lcpbench.bench.sweep import plan_sweep, sweep

INF = math.inf
# Four problems, three solvers, worked out by hand below.
COST = np.array([[1.0, 2.0, 4.0],
                 [3.0, 1.0, INF],
                 [INF, INF, 2.0],
                 [INF, INF, INF]])


def test_three_solvers_by_hand():
    r = performance_ratios(COST)
    assert r[0].tolist() == [1.0, 2.0, 4.0]
    assert r[1].tolist() == [3.0, 1.0, INF]
    assert r[2].tolist() == [INF, INF, 1.0]
    assert np.all(np.isinf(r[3]))  # nobody solved it
    p = performance_profile(COST, ["A", "B", "C"])
    assert p.problems == 4
    # rho_A: p1 at tau 1, p2 at tau 3
    assert [p.at("A", t) for t in (1, 2, 2.99, 3, 100)] == [0.25, 0.25, 0.25, 0.5, 0.5]
    assert [p.at("B", t) for t in (1, 1.99, 2, 100)] == [0.25, 0.25, 0.5, 0.5]
    assert [p.at("C", t) for t in (1, 3.99, 4, 100)] == [0.25, 0.25, 0.5, 0.5]
    assert p.at("A", 0.999) == 0.0
    assert p.solved.tolist() == [0.5, 0.5, 0.5]


def test_data_profile_by_hand():
    d = data_profile(COST, ["A", "B", "C"])
    assert [d.at("A", k) for k in (0.5, 1, 2.9, 3)] == [0.0, 0.25, 0.25, 0.5]
    assert [d.at("C", k) for k in (1.9, 2, 4)] == [0.0, 0.25, 0.5]
    # budgets per unit: problem 1 has n_p = 2, so A solves it within kappa = 0.5
    d2 = data_profile(COST, ["A", "B", "C"], units=[2.0, 1.0, 1.0, 1.0])
    assert d2.at("A", 0.5) == 0.25 and d2.at("B", 1.0) == 0.5


def test_ties_count_for_each_tied_solver():
    p = performance_profile(np.array([[5.0, 5.0, 7.0]]), ["A", "B", "C"])
    assert p.at("A", 1.0) == 1.0 and p.at("B", 1.0) == 1.0 and p.at("C", 1.0) == 0.0
    assert p.at("C", 7 / 5) == 1.0


def test_identical_curves_share_one_legend_entry():
    # A and C are the same column, so the same curve; B differs on problem 2
    cost = np.array([[1.0, 1.0, 1.0], [2.0, 3.0, 2.0], [INF, INF, INF]])
    p = performance_profile(cost, ["A", "B", "C"])
    assert p.same_curves() == [[0, 2], [1]]
    d = data_profile(cost, ["A", "B", "C"])
    assert d.same_curves() == [[0, 2], [1]]
    from lcpbench.bench.profile_plot import legend_label

    assert legend_label(["A", "C"]) == "same curve: A, C" and legend_label(["B"]) == "B"
    # the common settings and driver said once, three names a line
    assert legend_label(["pgs/high (globalised)", "psor/high (globalised)", "a/high (globalised)",
                         "b/high (globalised)"]) == ("same curve: pgs, psor, a,\nb "
                                                     "/high (globalised)")


def _run(backend, scene, success, ms, outer, inner, ref):
    from lcpbench.bench.metrics import Evaluated

    row = {"backend": backend, "settings": "default", "method": "globalised",
           "scene": scene, "links": 10, "tol": 1e-3, "converged": success,
           "wall_time": ms / 1e3, "outer_iterations": outer, "inner_iterations": inner}
    return Evaluated(row, 0.0 if success else INF, success, ref)


def test_back_ends_without_an_inner_count_are_left_out_of_inner_profiles():
    from lcpbench.bench.profiles import profiles_of

    ev = [_run("pivots", "free", True, 1.0, 2, 0, 0.0),
          _run("pivots", "wall", True, 4.0, 3, 30, 0.4),
          _run("highs", "free", True, 2.0, 2, 0, 0.0),
          _run("highs", "wall", True, 2.0, 3, 0, 0.4)]  # 0 on a contact scene: no count
    by = {(p.kind, p.measure): p for p in profiles_of(ev)}
    for kind in ("performance", "data"):
        inner = by[kind, "inner"]
        assert inner.solvers == ["pivots/default"] and inner.left_out == ("highs",)
        # time and outer iterations keep both
        assert by[kind, "time"].solvers == ["highs/default", "pivots/default"]
        assert by[kind, "time"].left_out == () and by[kind, "outer"].left_out == ()
    # with highs left out, pivots is the cheapest on both scenes: rho(1) = 1
    assert by["performance", "inner"].at("pivots/default", 1.0) == 1.0
    # the outer counts are equal (2, 3 each): one curve, one legend entry
    assert by["performance", "outer"].same_curves() == [[0, 1]]
    # time: highs is 2x cheaper on the contact scene, 2x dearer on the free one
    t = by["performance", "time"]
    assert t.at("highs/default", 1.0) == 0.5 and t.at("highs/default", 2.0) == 1.0


def test_bad_costs_are_refused():
    with pytest.raises(ValueError):
        performance_ratios(np.array([[0.0, 1.0]]))
    with pytest.raises(ValueError):
        performance_ratios(np.array([[math.nan, 1.0]]))
    with pytest.raises(ValueError):
        data_profile(np.array([[1.0]]), ["A"], units=[0.0])


costs = st.integers(1, 6).flatmap(lambda s: st.lists(
    st.lists(st.one_of(st.floats(1e-3, 1e3), st.just(INF)), min_size=s, max_size=s),
    min_size=1, max_size=12))


@settings(max_examples=150, deadline=None)
@given(costs)
def test_profile_properties(rows):
    cost = np.array(rows, float)
    P, S = cost.shape
    names = [f"s{i}" for i in range(S)]
    p = performance_profile(cost, names)
    best = cost.min(axis=1)
    for j, name in enumerate(names):
        curve = p.values[j]
        assert np.all(np.diff(curve) >= 0)  # non-decreasing
        assert np.all((curve >= 0) & (curve <= 1))
        # rho_s(1) = share of problems where s is the cheapest (ties included)
        fastest = np.mean(np.isfinite(best) & (cost[:, j] == best))
        assert p.at(name, 1.0) == pytest.approx(fastest)
        # the limit is the share s solved
        assert curve[-1] == pytest.approx(np.mean(np.isfinite(cost[:, j])))
        assert p.solved[j] == pytest.approx(np.mean(np.isfinite(cost[:, j])))
    # every problem someone solved has a fastest solver
    assert sum(p.at(n, 1.0) for n in names) >= np.mean(np.isfinite(best)) - 1e-12
    # scale invariance: multiplying a problem's costs by a constant changes no ratio
    scaled = cost * np.linspace(0.5, 7.0, P)[:, None]
    q = performance_profile(scaled, names)
    for name in names:
        for tau in (1.0, 1.5, 4.0, 1e6):
            assert q.at(name, tau) == pytest.approx(p.at(name, tau))
    d = data_profile(cost, names)
    for j in range(S):
        assert np.all(np.diff(d.values[j]) >= 0)
        assert d.values[j][-1] == pytest.approx(np.mean(np.isfinite(cost[:, j])))
    # a data profile is absolute: dropping a solver changes no other curve
    if S > 1:
        d1 = data_profile(cost[:, 1:], names[1:])
        for name in names[1:]:
            for k in np.unique(cost[np.isfinite(cost)]):
                assert d1.at(name, k) == d.at(name, k)


def test_csv_round_trip(tmp_path):
    ps = [performance_profile(COST, ["A", "B", "C"], measure="time", group="default"),
          data_profile(COST, ["A", "B", "C"], measure="outer", group="high")]
    n = write_csv(ps, tmp_path / "p.csv")
    assert n == sum(p.x.size * len(p.solvers) for p in ps)
    back = {(p.kind, p.measure, p.group): p for p in read_csv(tmp_path / "p.csv")}
    for p in ps:
        b = back[p.kind, p.measure, p.group]
        assert b.solvers == p.solvers and b.problems == p.problems
        assert np.array_equal(b.x, p.x) and np.array_equal(b.values, p.values)


@pytest.fixture(scope="module")
def small_store(tmp_path_factory):
    path = tmp_path_factory.mktemp("prof") / "s.sqlite"
    grid = Grid(theta=(90.0, 150.0, 180.0), height=(3.0,), links=(20,))
    jobs = plan_sweep(grid, ["active-set", "lemke", "pgs"], ["default"], baselines=())
    with Store(path) as st:
        sweep(st, jobs, workers=1)
    return path


def test_report_writes_profiles_that_match_the_runs(small_store, tmp_path):
    with Store(small_store) as st:
        build_report(st, tmp_path, plots=True)
        ev = evaluate(st.runs(), st.refs())
    assert (tmp_path / "perf-profile-time.png").stat().st_size > 0
    assert (tmp_path / "data-profile-inner.png").stat().st_size > 0
    text = (tmp_path / "report.md").read_text()
    assert "Performance and data profiles" in text and "profiles.csv" in text
    got = {(p.kind, p.measure, p.group): p for p in read_csv(tmp_path / "profiles.csv")}
    perf = got["performance", "outer", "default"]
    # rho_s(1) from the stored rows directly: the share of scenes where s succeeded
    # with the fewest outer iterations (floored at 1) among the successes
    scenes = sorted({e.row["scene"] for e in ev})
    for s in ("active-set", "lemke", "pgs"):
        wins = 0
        for sc in scenes:
            ok = {e.backend: max(1, e.row["outer_iterations"]) for e in ev
                  if e.row["scene"] == sc and e.success}
            wins += s in ok and ok[s] == min(ok.values())
        assert perf.at(f"{s}/default", 1.0) == pytest.approx(wins / len(scenes))
    # the limit of each curve is that back-end's success share in the summary table
    with open(tmp_path / "runs.csv") as fh:
        assert len(list(csv.DictReader(fh))) == 9
    problems, solvers, cost, links = cost_matrix(ev, "time", settings="default")
    assert len(problems) == 3 and links.tolist() == [20.0] * 3
    for j, s in enumerate(solvers):
        share = np.mean([e.success for e in ev if f"{e.backend}/{e.settings}" == s])
        assert perf.solved[perf.solvers.index(s)] == pytest.approx(share)
        assert np.isfinite(cost[:, j]).mean() == pytest.approx(share)
