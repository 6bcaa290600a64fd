"""Tight tolerances below LARGE_N (issue 19, item 3): where node heights cannot be certified, increments.

In node heights the round-off of a step grows with cond H ~ N⁴: at N = 3000 the
paper scene's answer stops 1.6·10⁻⁷ F₀ from the force, so at tol 1e-11 (τ = 10⁻⁹)
the judge rejects it however long the driver runs. (At tol 1e-9 it is rejected too,
but 1.6·10⁻⁷ against τ = 10⁻⁷ is too close a margin for a test: the error moves
with the scene's last digits and the machine.) :func:`lcpbench.solve` then
solves it again in increments on the tridiagonal factor (cond ~ N², the
formulation used from ``LARGE_N`` links), from the rejected answer, and judges
that in increments. These tests check when that happens, that the retried answer
is right against an independent exact step, and that nothing else changes.
"""

from __future__ import annotations

import numpy as np
import pytest

from lcpbench import ActuatorScene, solve, solve_many
from lcpbench.escalations import Context, escalate
from lcpbench.model import large_n
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.judge import force_tol
from lcpbench.plan import make_plan
from lcpbench.solvers.registry import DEFAULT

N = 3000
TOL = 1e-11


@pytest.fixture(scope="module")
def heights_answer():
    """The answer in node heights alone (the retry switched off)."""
    mp = pytest.MonkeyPatch()
    mp.setattr(large_n, "roundoff_limited", lambda chain, judgement, method: False)
    try:
        return solve(ActuatorScene(150, 3.0, links=N), tol=TOL)
    finally:
        mp.undo()


@pytest.fixture(scope="module")
def retried():
    return solve(ActuatorScene(150, 3.0, links=N), tol=TOL)


def test_the_height_answer_at_n_3000_is_rejected_on_its_force(heights_answer):
    assert not heights_answer.converged
    assert heights_answer.judgement.failed == ["force error bound"]
    assert heights_answer.retried("in_increments") is None


def test_the_rejected_answer_is_solved_again_in_increments_and_accepted(retried):
    assert retried.converged, retried.reason
    assert retried.judgement.force_error_bound <= force_tol(TOL)
    assert retried.judge == "increments"  # judged in increments, as from LARGE_N
    assert "increments" in retried.engine
    assert "did not certify" in retried.retried("in_increments")


def test_the_retried_force_is_the_independent_exact_step_of_the_rejected_answer(
        heights_answer, retried):
    # the judge's own step at the rejected answer's angles: block principal pivoting in
    # node heights, no code shared with the increments walk (on this scene it lands
    # ~4e-11 F₀ from the retried force; it is the driver's height answer that is
    # 1.6e-7 off)
    F0 = retried.judgement.force_unit
    step_force = heights_answer.judgement.judge_total_force
    assert abs(retried.total_force - step_force) / F0 <= force_tol(TOL)
    # and the rejection was right: the height answer itself is more than τ off
    assert abs(heights_answer.total_force - retried.total_force) / F0 > force_tol(TOL)


def test_a_retried_channel_answer_is_the_cold_increment_solves(monkeypatch):
    """Route against route: the two forces must agree to τ = 1e-8 F₀ at N = 3000, finer
    than central differences of the energy resolve and where SLSQP is out of reach; the
    two starts are independent paths to one equilibrium."""
    # a channel at N = 3000, tol 1e-10 (τ = 1e-8): retried from the rejected height
    # answer, and solved in increments from the rest shape (LARGE_N lowered): two
    # starts, one force
    scene = ActuatorScene(66, 2.99, links=N, channel=True)
    res = solve(scene, tol=1e-10)
    assert res.converged and res.retried("in_increments") is not None, res.reason
    monkeypatch.setattr(large_n, "LARGE_N", 10)
    cold = solve(scene, tol=1e-10)
    assert cold.converged and cold.retried("in_increments") is None
    assert "increments" in cold.engine
    assert abs(res.total_force - cold.total_force) / res.judgement.force_unit \
        <= force_tol(1e-10)


def test_a_batch_retries_as_solve_does(retried):
    """Route against route: a batch must retry as solve does, to τ at N = 3000, where the
    energy oracles cannot resolve τ; the retried answer itself is checked against the
    independent exact step in test_the_retried_force_is_the_independent_exact_step_of_the_rejected_answer."""
    scenes = [ActuatorScene(150, 3.0, links=N), ActuatorScene(150, 3.2, links=N)]
    got = solve_many(scenes, tol=TOL)
    assert all(r.converged for r in got), [r.reason for r in got]
    assert all(r.retried("in_increments") is not None and "continuation" in r.extra for r in got)
    F0 = retried.judgement.force_unit
    assert abs(got[0].total_force - retried.total_force) / F0 <= force_tol(TOL)


def test_an_accepted_answer_is_never_solved_again():
    # N = 3000 at tol 1e-3: cond H · ε = 3e-3 reaches τ = 1e-3, so a rejection would be
    # retried; the answer in heights is accepted and kept
    res = solve(ActuatorScene(150, 3.0, links=N), tol=1e-3)
    assert res.converged, res.reason
    assert res.retried("in_increments") is None


def test_where_increments_cannot_do_better_the_rejection_stands():
    # N = 140 at tol 1e-14 (τ = 1e-12): both formulations stop ~1e-11 F₀ off
    res = solve(ActuatorScene(150, 3.0, links=140), tol=1e-14)
    assert not res.converged
    assert "increments" not in res.engine  # the first answer is kept
    assert "solved again in increments: not accepted" in res.retried("in_increments")


def test_the_retry_takes_only_the_outer_steps_left(heights_answer):
    # max_outer bounds the contact steps of both solves: none left, no retry; one left,
    # a retry of one step, which cannot stop, and the first answer is kept
    scene = ActuatorScene(150, 3.0, links=N)
    used = heights_answer.outer_iterations
    none_left = solve(scene, tol=TOL, max_outer=used)
    assert not none_left.converged and none_left.retried("in_increments") is None
    one_left = solve(scene, tol=TOL, max_outer=used + 1)
    assert not one_left.converged and "1 outer iterations" in one_left.retried("in_increments")
    assert one_left.outer_iterations == used


@pytest.mark.parametrize("method", ["newton", "undamped"])
def test_only_the_globalised_scheme_is_retried(method):
    chain = ActuatorScene(150, 3.0, links=N).chain()

    class Rejected:
        converged, failed, force_tol = False, ["force error bound"], 1e-7

    assert large_n.roundoff_limited(chain, Rejected, "globalised")
    assert not large_n.roundoff_limited(chain, Rejected, method)
    Rejected.failed = ["driver"]  # the driver did not stop: nothing for a retry to fix
    assert not large_n.roundoff_limited(chain, Rejected, "globalised")


def test_the_retry_needs_cond_h_eps_to_reach_tau():
    class Rejected:
        converged, failed = False, ["force error bound"]

    chain = ActuatorScene(150, 3.0, links=140).chain()  # cond H · ε ≈ 1.4e-8
    Rejected.force_tol = force_tol(1e-9)  # 1e-7: round-off cannot be the reason
    assert not large_n.roundoff_limited(chain, Rejected, "globalised")
    Rejected.force_tol = force_tol(1e-11)  # 1e-9
    assert large_n.roundoff_limited(chain, Rejected, "globalised")
    # the cantilever (clamped end): the increments' layout does not take it
    from lcpbench import CantileverScene
    assert not large_n.roundoff_limited(CantileverScene(links=3000).chain(), Rejected,
                                        "globalised")


@pytest.mark.parametrize("theta", [60.0, 150.0])
def test_heights_condition_against_the_computed_condition_number(theta):
    # numpy's cond of the assembled H at the rest shape: N⁴ growth, and the uniform
    # chain's (2N/π)⁴ to within the 1/cos α of steep links (θ = 150°: ends at 75°)
    cond = {}
    for n in (80, 160, 320):
        chain = ActuatorScene(theta, 3.0, links=n).chain()
        cond[n] = np.linalg.cond(assemble_step(chain, chain.rest_alpha).dense_hessian())
        assert 0.5 <= cond[n] / large_n.heights_condition(n) <= 5.0
    assert cond[320] / cond[160] == pytest.approx(16.0, rel=0.2)


def test_another_back_ends_rejection_stays_its_own(heights_answer):
    # a benchmark compares back-ends in node heights: a second solve in increments
    # would hide the rejection it measures
    def no_second_solve():
        raise AssertionError("a second solve was started")

    chain = heights_answer.scene.chain()
    plan = make_plan(chain, "osqp", "globalised", "auto", TOL)
    assert "in_increments" not in plan.escalations  # nor tightened, nor ramped
    assert make_plan(chain, DEFAULT, "globalised", "auto", TOL).escalations[0] == \
        "in_increments"  # (the built-in back-end's plan has it)
    ctx = Context(chain, no_second_solve, "osqp", "default", "auto", TOL, 200, "globalised")
    got = escalate(heights_answer, ctx, plan.escalations)
    assert got is heights_answer and got.retried("in_increments") is None
