"""lcpbench.solve_many: one result per scene, in the caller's order."""

import random

import pytest

import lcpbench
from lcpbench import ActuatorScene, CantileverScene, ProblemError
from lcpbench.studies.continuation import total_outer


def grid():
    scenes = [ActuatorScene(theta=th, height=h, links=60) for h in (2.0, 3.0)
              for th in range(120, 181, 10)]
    scenes.append(CantileverScene(links=60))
    random.Random(7).shuffle(scenes)
    return scenes


def test_results_in_the_callers_order_and_equal_to_cold_solves():
    scenes = grid()
    batch = lcpbench.solve_many(scenes, tol=1e-10)
    cold = [lcpbench.solve(s, tol=1e-10) for s in scenes]
    assert [r.scene for r in batch] == scenes
    for b, c in zip(batch, cold):
        assert b.converged and c.converged
        scale = max(c.total_force, c.scene.EI / c.scene.length**2)
        assert abs(b.total_force - c.total_force) <= 1e-8 * scale
    # continuation along θ starts next to the answer: fewer contact steps in total
    assert total_outer(batch) < total_outer(cold)


def test_without_continuation_each_scene_is_a_cold_solve():
    scenes = grid()[:4]
    batch = lcpbench.solve_many(scenes, tol=1e-3, continuation=False)
    for b, s in zip(batch, scenes):
        c = lcpbench.solve(s, tol=1e-3)
        assert b.scene == s and b.outer_iterations == c.outer_iterations
        assert b.total_force == pytest.approx(c.total_force, rel=1e-12)


def test_bad_input():
    with pytest.raises(ProblemError, match="scenes must be"):
        lcpbench.solve_many("scenes")
    with pytest.raises(ProblemError, match="continuation must be"):
        lcpbench.solve_many([], continuation="yes")
    assert lcpbench.solve_many([]) == []
