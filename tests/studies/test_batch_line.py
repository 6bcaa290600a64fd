"""A continuation line in one kernel call (lcpbench.model.batch_kernel, studies.batch_line).

Each scene of the batch must be what one ``lcpbench.solve`` gives from the same start
(the start chosen by Solved from the batch's own answers before it: the one compiled
predictor, model/predictor_kernel.py, which the line kernel calls too); the results,
built when read, must carry what a single solve's carry.
"""

import dataclasses
import pickle
import random

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import ActuatorScene, CantileverScene, ProblemError
from lcpbench.bench.grid import PAPER_GRID
from lcpbench.model.chain import node_positions
from lcpbench.studies.batch import continuation_order
from lcpbench.studies.batch_line import takes_line
from lcpbench.studies.batch_result import LineResult
from lcpbench.studies.continuation import new_solved, warm_or_cold


def paper_scenes(links=140):
    return [ActuatorScene(theta=t, height=h, links=links) for h in PAPER_GRID.height
            for t in PAPER_GRID.theta]


def _from_line(res) -> bool:
    return isinstance(res, LineResult)


@pytest.mark.parametrize("tol", [1e-3, 1e-8])
def test_each_scene_is_one_solve_from_the_same_start(tol):
    """Replay the line in Python: Solved predicts each scene from the batch's answers
    before it, lcpbench.solve runs from that start (a failed warm start redone cold):
    the same verdict, path and label, and the same answer to round-off."""
    scenes = paper_scenes(links=60 if tol < 1e-6 else 140)
    batch = lcpbench.solve_many(scenes, tol=tol)
    assert all(_from_line(r) for r in batch)
    order = continuation_order(scenes)
    assert len(order) == 1
    solved = new_solved("adaptive")
    for i in order[0]:
        scene, got = scenes[i], batch[i]
        p = solved.predict(scene)
        start = None if p is None else dataclasses.replace(p[1], alpha=p[0])
        one = warm_or_cold(lambda s, sc=scene: lcpbench.solve(sc, tol=tol, start=s), start,
                           "adaptive")
        assert got.converged == one.converged and got.converged, (got.reason, one.reason)
        assert got.extra["continuation"] == one.extra["continuation"]
        assert got.outer_iterations == one.outer_iterations
        assert [s.iterations for s in got.steps] == [s.iterations for s in one.steps]
        F0 = max(one.total_force, scene.EI / scene.length**2)
        assert abs(got.total_force - one.total_force) <= 1e-9 * F0
        assert np.max(np.abs(got.alpha - one.alpha)) <= 1e-9
        assert got.reason == one.reason
        assert_solved(got)  # the equilibrium (tests/energy_oracle.py)
        solved.add(scene, got)


def test_results_are_built_when_read_and_carry_what_a_solve_carries():
    scenes = [ActuatorScene(theta=t, height=3.0, links=40) for t in (120, 140, 160)]
    batch = lcpbench.solve_many(scenes, tol=1e-6)
    r = batch[1]
    assert "_build" in r.__dict__ and "steps" not in r.__dict__  # nothing built yet
    assert r.converged and r.outer_iterations == len(r.steps)  # (builds it)
    assert "_build" not in r.__dict__
    assert r.judgement.converged and r.judgement.failed == []
    assert r.total_force == pytest.approx(float(np.sum(r.forces)), rel=0, abs=0)
    x, y = node_positions(scenes[1].chain(), r.alpha)  # forward kinematics of α
    assert np.array_equal(r.x, x) and np.array_equal(r.y, y)
    assert np.allclose(r.gaps, 3.0 - y[r.free_nodes])
    assert r.engine == "compiled" and r.judge == "heights"
    assert r.extra["last_step"].u.shape == r.forces.shape
    # a field set before it is read keeps its value; pickling and replace build the rest
    s = batch[2]
    s.reason = "mine"
    assert s.reason == "mine" and s.certificate.min_force >= -1e-12
    back = pickle.loads(pickle.dumps(batch[0]))
    assert back.total_force == batch[0].total_force and back.reason == batch[0].reason
    assert np.array_equal(back.x, batch[0].x)
    moved = dataclasses.replace(batch[0], alpha=batch[0].alpha + 0.0)
    assert moved.steps == batch[0].steps
    assert "converged" in repr(batch[0]) and batch[0].to_dict()["converged"]


def test_mixed_batches_fall_back_per_plane_in_the_callers_order():
    """Rigid and elastic walls in one group (two planes), a channel, a heavy chain and a
    cantilever: the rigid and the elastic plane and the channel run in the line kernel,
    the others as before, and every answer is the scene's equilibrium."""
    rigid = [ActuatorScene(theta=t, height=3.0, links=40) for t in (110, 130, 150, 170)]
    soft = [ActuatorScene(theta=t, height=3.0, links=40, wall_stiffness=50.0)
            for t in (120, 150)]
    channel = [ActuatorScene(theta=t, height=1.0, links=40, channel=True) for t in (90, 120)]
    heavy = [ActuatorScene(theta=t, height=3.0, links=30, weight=0.05) for t in (100, 140)]
    scenes = rigid + soft + channel + heavy + [CantileverScene(links=30)]
    random.Random(3).shuffle(scenes)
    fast = lcpbench.solve_many(scenes, tol=1e-8)
    assert [r.scene for r in fast] == scenes
    for f in fast:
        assert _from_line(f) == (f.scene in rigid or f.scene in soft or f.scene in channel)
        assert f.converged, f.reason
        assert_solved(f)  # the equilibrium, rigid or Winkler (tests/energy_oracle.py)


def test_which_lines_the_kernel_takes():
    assert takes_line(ActuatorScene(theta=150, height=3.0, links=40).chain())
    assert takes_line(ActuatorScene(theta=150, height=3.0, links=40, wall_stiffness=50.0).chain())
    assert takes_line(ActuatorScene(theta=150, height=1.0, links=40, channel=True).chain())
    assert not takes_line(ActuatorScene(theta=150, height=3.0, links=30, weight=0.05).chain())


@pytest.mark.parametrize("tol", [1e-3, 1e-8])
def test_a_channel_line_is_one_solve_per_scene_from_the_same_start(tol):
    """A line in a channel, sagging onto the lower wall at the small heights: one call of
    the line kernel, each scene what lcpbench.solve gives from the start Solved predicts
    (replayed in Python), both walls' reactions to round-off; every answer the
    equilibrium by the energy oracle (both walls)."""
    scenes = [ActuatorScene(theta=t, height=h, links=60, channel=True, weight=0.009)
              for h in (0.3, 1.0) for t in (20.0, 50.0, 80.0, 110.0)]
    batch = lcpbench.solve_many(scenes, tol=tol)
    assert all(_from_line(r) for r in batch)
    assert any(np.sum(r.forces_lower) > 0 for r in batch)  # the lower wall is pressed
    solved = new_solved("adaptive")
    for i in continuation_order(scenes)[0]:
        scene, got = scenes[i], batch[i]
        p = solved.predict(scene)
        start = None if p is None else dataclasses.replace(p[1], alpha=p[0])
        one = warm_or_cold(lambda s, sc=scene: lcpbench.solve(sc, tol=tol, start=s), start,
                           "adaptive")
        assert got.converged and one.converged, (got.reason, one.reason)
        assert got.extra["continuation"] == one.extra["continuation"]
        F0 = max(one.total_force, scene.EI / scene.length**2)
        np.testing.assert_allclose(got.forces, one.forces, rtol=0, atol=1e-9 * F0)
        np.testing.assert_allclose(got.forces_lower, one.forces_lower, rtol=0, atol=1e-9 * F0)
        assert got.total_force_lower == pytest.approx(one.total_force_lower, abs=1e-9 * F0)
        assert_solved(got)
        solved.add(scene, got)


def test_bad_scenes_in_a_batch_name_the_problem_as_solve_does():
    good = ActuatorScene(theta=150, height=3.0, links=20)
    with pytest.raises(ProblemError, match="scene must be") as batch:
        lcpbench.solve_many([good, {"theta": 150}])
    with pytest.raises(ProblemError, match="scene must be") as one:
        lcpbench.solve({"theta": 150})
    assert str(batch.value) == str(one.value)
    auto = ActuatorScene(theta=150, height=3.0, links="auto")
    with pytest.raises(ProblemError, match="links"):
        lcpbench.solve_many([good, auto])


def test_failed_warm_starts_are_redone_cold_as_scene_by_scene():
    """With max_outer = 4 at tol 1e-10 many warm starts fail (more than the rows spared
    for retries at first): each is redone cold, labelled and counted as the per-scene
    loop (studies.batch_compiled) does it.

    Route against route: at max_outer = 4 most answers are unconverged, with no
    equilibrium to check; what is promised is the per-scene loop's labels, counts and
    verdicts, which only that loop defines. (Converged answers are checked below.)"""
    from lcpbench.studies.batch_compiled import solve_line
    from lcpbench.studies.batch_line import run_line

    scenes = [ActuatorScene(theta=t, height=h, links=40) for h in (2.0, 3.0)
              for t in range(10, 181, 10)]
    line = [scenes[i] for i in continuation_order(scenes)[0]]
    got = run_line(line, tol=1e-10, max_outer=4)
    want = solve_line(line, tol=1e-10, max_outer=4)
    assert got is not None
    failed = [w for w in want if "failed" in w.extra["continuation"]]
    assert len(failed) > 8 and any(w.converged for w in want)
    for g, w in zip(got, want):
        assert (g.converged, g.extra["continuation"], g.outer_iterations) == (
            w.converged, w.extra["continuation"], w.outer_iterations)
        assert g.reason == w.reason
        assert g.extra.get("discarded", {}).get("outer_iterations") == \
            w.extra.get("discarded", {}).get("outer_iterations")
        F0 = max(abs(w.total_force), w.scene.EI / w.scene.length**2)
        assert abs(g.total_force - w.total_force) <= 1e-9 * F0
        if g.converged:
            assert_solved(g, stationarity=1e-5)  # (tests/energy_oracle.py)


def test_planes_of_elastic_walls_run_in_one_call_each_on_its_own_walls(monkeypatch):
    """Two lines in θ at each of two wall stiffnesses (two planes of one kin): one call
    of the line kernel for both, each answer an equilibrium on its own elastic walls
    (tests/energy_oracle.py: the Winkler springs of its own k; only a start is shared),
    and only the batch's first scene starts cold: the first scene of the other plane,
    which no answer of its own plane predicts, starts from the nearest answer of its
    kin (studies.batch._kin, the kernel's rule 5)."""
    from lcpbench.studies import batch_line

    planes = [[ActuatorScene(theta=t, height=h, links=40, wall_stiffness=k)
               for t in (110, 130, 150, 170)] for k in (5.0, 500.0) for h in (2.5, 3.0)]
    scenes = [s for p in planes for s in p]
    random.Random(5).shuffle(scenes)
    calls = []
    real = batch_line.run_line
    monkeypatch.setattr(lcpbench.studies.batch, "run_line",
                        lambda *a, **kw: calls.append(kw.get("plane")) or real(*a, **kw))
    got = lcpbench.solve_many(scenes, tol=1e-6)
    assert len(calls) == 1 and sorted(set(calls[0])) == [0, 1]  # the planes: k
    for res in got:
        assert _from_line(res) and res.converged
        assert_solved(res)
    assert [r.extra["continuation"] for r in got].count("cold") == 1


def test_rows_of_sections_run_in_one_call_and_a_row_it_stops_on_as_solve_runs_it():
    """Rows of two sections (θ, −θ), each cold and alone in its plane: one call of the line
    kernel for all; the rows past ~157° on which the solve kernel stops (its own step
    refused at the free arc) go on from that stop as lcpbench.solve goes on from it,
    without a second cold solve: the first along the loading path, the same answer bit
    for bit; the second, which has the first as its neighbour (5° and 0.7 mm away), by SQP
    steps from the first's answer (tests/studies/test_batch_neighbour.py). Every answer
    is an equilibrium (tests/energy_oracle.py: stationary, feasible, complementary)."""
    from lcpbench import SectionedScene

    rows = [SectionedScene(sections=[(t, 15.0), (-t, 15.0)], height=h, links=40)
            for t, h in ((100, 2.5), (140, 3.0), (170, 2.0), (175, 2.7), (120, 4.0))]
    got = lcpbench.solve_many(rows, tol=1e-3)
    assert [r.scene for r in got] == rows
    assert [_from_line(r) for r in got] == [True, True, False, False, True]
    for res in got:
        assert res.converged
        assert_solved(res)
    assert [r.name for r in got[3].retries] == ["from_neighbour"]
    for res in got[2:3]:  # the kernel stopped cold: the plan's escalation, as in solve()
        assert "followed the load from zero" in res.retried("ramped")
        assert res.route == "line kernel"
        one = lcpbench.solve(res.scene, tol=1e-3)
        assert [r.name for r in res.retries] == [r.name for r in one.retries]
        assert res.total_force == one.total_force
        np.testing.assert_array_equal(res.alpha, one.alpha)
