"""lcpbench.solve_many: one result per scene, in the caller's order."""

import random

import pytest
from energy_oracle import assert_solved

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
        assert_solved(b)  # the equilibrium (tests/energy_oracle.py)
    # continuation along θ starts next to the answer: fewer contact steps in total
    assert total_outer(batch) < total_outer(cold)


def test_without_continuation_each_scene_is_a_cold_solve():
    scenes = grid()[:4]
    batch = lcpbench.solve_many(scenes, tol=1e-3, continuation=False)
    for b, s in zip(batch, scenes):
        c = lcpbench.solve(s, tol=1e-3)
        assert b.scene == s and b.outer_iterations == c.outer_iterations
        assert b.total_force == pytest.approx(c.total_force, rel=1e-12)
        assert_solved(b)  # the equilibrium (tests/energy_oracle.py)


def test_bad_input():
    with pytest.raises(ProblemError, match="scenes must be"):
        lcpbench.solve_many("scenes")
    with pytest.raises(ProblemError, match="continuation must be"):
        lcpbench.solve_many([], continuation="yes")
    assert lcpbench.solve_many([]) == []


# -- the compiled batch loop (issue 19, item 4) --------------------------------------------

def paper_like_grid():
    """θ 10-180 at two heights (no-contact scenes at small θ), a channel line, a heavy line."""
    scenes = [ActuatorScene(theta=th, height=h, links=60) for h in (2.0, 5.0)
              for th in range(10, 181, 20)]
    scenes += [ActuatorScene(theta=th, height=1.0, links=60, channel=True, weight=0.002)
               for th in (60, 90, 120)]
    scenes += [ActuatorScene(theta=th, height=3.0, links=40, weight=0.01) for th in (100, 140)]
    random.Random(19).shuffle(scenes)
    return scenes


@pytest.mark.parametrize("tol", [1e-3, 1e-9])
def test_the_compiled_batch_gives_the_equilibria(tol):
    """The kernels' loop solves every scene of the grid, in order, each answer the
    scene's equilibrium."""
    scenes = paper_like_grid()
    fast = lcpbench.solve_many(scenes, tol=tol)
    assert [r.scene for r in fast] == scenes
    for f in fast:
        assert f.judge == "heights" and f.engine == "compiled"
        assert f.converged, f.reason
        assert_solved(f)  # the equilibrium (tests/energy_oracle.py)


def test_every_batch_result_has_the_verdict_of_the_judges_rules():
    """The batch decides each verdict in its kernel (model.batch_verdict.accepted, on the
    judge kernel's numbers); it must be the judge's rules' (model.judge.failed_checks) on
    the same answers, whose equilibrium is the oracle's in the tests above."""
    from lcpbench.model.judge import judge
    from lcpbench.model.result import certify

    for res in lcpbench.solve_many(paper_like_grid(), tol=1e-6):
        chain = res.scene.chain()
        lower = res.forces_lower if res.forces_lower is not None else 0 * res.forces
        v = judge(chain, res.alpha, res.forces, lower, tol=res.tol, driver_converged=True,
                  driver_reason=res.reason, step_statuses=[s.status for s in res.steps],
                  step_sizes=[s.max_dalpha for s in res.steps],
                  certificate=lambda up, lo, c=chain, a=res.alpha: certify(c, a, up, lo))
        assert v.converged == res.converged, (v.reason, res.reason)
        assert v.failed == res.judgement.failed


def test_batch_bad_settings_and_limits_name_the_parameter():
    scenes = [ActuatorScene(theta=150, height=3.0, links=20)]
    with pytest.raises(ProblemError, match="settings"):
        lcpbench.solve_many(scenes, settings="fast")
    with pytest.raises(ProblemError, match="max_outer"):
        lcpbench.solve_many(scenes, max_outer=0)
    with pytest.raises(ProblemError, match="tol"):
        lcpbench.solve_many(scenes, tol=2.0)


def test_large_n_scenes_take_solves_large_n_path_in_a_batch():
    """From LARGE_N links solve() drives in increments (model.large_driver); solve_many's
    compiled loop must not run such a chain through the heights kernel instead.

    Route against route: a cold batch is promised to be the single solve, bit for bit
    (the same computation), at N = LARGE_N where the energy oracle costs ~25 s."""
    from lcpbench.model.large_n import LARGE_N

    scenes = [lcpbench.ActuatorScene(theta=t, height=3.0, links=LARGE_N) for t in (160.0, 165.0)]
    ones = [lcpbench.solve(scene, tol=1e-3) for scene in scenes]
    cold = lcpbench.solve_many(scenes, tol=1e-3, continuation=False)
    warm = lcpbench.solve_many(scenes, tol=1e-3)
    for one, c, w in zip(ones, cold, warm):
        assert "large N" in one.engine
        assert c.engine == w.engine == one.engine
        assert c.total_force == one.total_force and c.converged == one.converged
        # a warm start ends elsewhere within the tolerance: both answers are judged
        F0 = max(one.total_force, one.scene.EI / one.scene.length**2)
        if w.converged and one.converged:
            assert abs(w.total_force - one.total_force) / F0 <= (
                w.force_error_bound + one.force_error_bound)
