"""Following the load from zero (model.ramp; solve(start="ramp") and the escalation in
escalations.ramped), against independent checks: the answer is a KKT point of the exact energy
(central differences of the energy and kinematics, tests/energy_oracle.py) with its
reactions feasible, and a strict local minimum on its contact set (the same oracle's
second-order test). Scenes whose cold start fails: past 180° in a channel (the
issue's grid) and rows of sections with large signed angles (the issue's kind), some
of whose links pass the vertical along the path."""

import dataclasses

import numpy as np
import pytest
from energy_oracle import energy_minimum, fd_kkt_residual, fd_unstable_directions

import lcpbench
from lcpbench.errors import ProblemError
from lcpbench.model import ramp
from lcpbench.model.compiled import drive
from lcpbench.model.ramp import STEP_DEG, fractions, near_vertical
from lcpbench.model.step_solver import make_step_solver
from lcpbench.problems.sections import SectionedScene
from lcpbench.solvers.registry import DEFAULT
from lcpbench.thresholds import NEAR_VERTICAL_DEG


def _cold_driver_converges(scene) -> bool:
    out, _ = drive(scene.chain(), make_step_solver(DEFAULT, "default", True),
                   backend=DEFAULT, settings="default", tol=1e-3, max_outer=200,
                   method="globalised", start=None)
    return out.converged


def _assert_stable_kkt_point(scene, res):
    """Feasible, complementary, stationary and stable, by the oracle."""
    chain = scene.chain()
    fu = res.forces
    fl = res.forces_lower if res.forces_lower is not None else np.zeros_like(fu)
    y = res.y[chain.free_nodes]
    h = chain.wall
    assert np.all(fu >= -1e-9) and np.all(fl >= -1e-9)
    assert np.all(y <= h + 1e-6)
    if chain.channel:
        assert np.all(y >= -h - 1e-6)
    assert np.all(fu * (h - y) <= 1e-6 * max(1.0, fu.max(initial=0)))
    assert fd_kkt_residual(chain, res.alpha, fu, fl) < 1e-3  # tol 1e-3 rad answers
    threshold = res.judgement.contact_threshold
    assert fd_unstable_directions(chain, res.alpha, fu, fl, threshold) == 0


def test_the_path_ends_at_the_scene_in_steps_of_at_most_ten_degrees():
    for scene in (lcpbench.ActuatorScene(theta=350, height=1.0),
                  SectionedScene(sections=[(-80, 30.0), (154, 30.0), (81, 30.0)])):
        path = fractions(scene)
        assert path[-1] == 1.0 and all(0 < s <= 1 for s in path)
        thetas = [[abs(s * t) for t in ([scene.theta] if hasattr(scene, "theta")
                                         else [x.theta for x in scene.sections])]
                  for s in [0.0, *path]]
        steps = np.diff(np.array(thetas), axis=0)
        assert np.all(steps <= STEP_DEG + 1e-9)



def test_a_step_of_the_path_is_the_chain_of_the_row_at_the_scaled_bend_angles():
    # property: the row's chain at s = 1/2 is the chain of the row built with θ/2
    scaled = SectionedScene(sections=[(-80, 30.0), (154, 30.0)]).chain_at(0.5)
    built = SectionedScene(sections=[(-40, 30.0), (77, 30.0)]).chain()
    for f in dataclasses.fields(built):
        got, want = getattr(scaled, f.name), getattr(built, f.name)
        if isinstance(want, np.ndarray):
            np.testing.assert_allclose(got, want, rtol=1e-15, atol=1e-15, err_msg=f.name)
        else:
            assert got == want, f.name
    whole = SectionedScene(sections=[(-80, 30.0), (154, 30.0)])
    assert whole.chain_at(1.0) is whole.chain()


@pytest.mark.parametrize("scene", [
    lcpbench.ActuatorScene(theta=190, height=0.3, channel=True, links=70),
    SectionedScene(sections=[(-80, 30.0), (154, 30.0), (81, 30.0)], height=5.07, links=45),
])
def test_a_refused_cold_start_is_solved_along_the_loading_path(scene):
    assert not _cold_driver_converges(scene)  # the premise: cold, the driver fails
    res = lcpbench.solve(scene)
    assert res.converged and "followed the load from zero" in res.retried("ramped")
    _assert_stable_kkt_point(scene, res)


def test_start_ramp_gives_the_stable_state_of_the_paper_scene():
    scene = lcpbench.ActuatorScene(theta=150, height=3.0, links=40)
    ramp = lcpbench.solve(scene, start="ramp", tol=1e-9)
    assert ramp.converged and ramp.route == "load path" and ramp.retries == ()
    _assert_stable_kkt_point(scene, ramp)
    # one stable state here: the energy minimum's (tests/energy_oracle.py), to the
    # success rule at tol 1e-9 (100 tol = 1e-7; 1e-6 leaves room for the oracle's 1e-11)
    assert ramp.total_force == pytest.approx(energy_minimum(scene).total_force, rel=1e-6)


def test_start_must_be_a_result_or_ramp():
    with pytest.raises(ProblemError, match="'ramp'"):
        lcpbench.solve(lcpbench.ActuatorScene(), start="rmp")
    with pytest.raises(ProblemError, match="globalised"):
        lcpbench.solve(lcpbench.ActuatorScene(), start="ramp", method="undamped")


# Rows of sections whose loading path stalled in the node heights (issue 36's audit,
# results/stability/saddle-grid.md, at N = 10 per section): a step of the path starts
# with links at 82-90 degrees and ends with them past the vertical, where the height
# step divides by a cos(alpha) ~ 0.
PAST_THE_VERTICAL = [
    SectionedScene(sections=[(159.2, 30.0), (-70.9, 30.0), (-80.5, 30.0)], height=3.44,
                   links=30),
    SectionedScene(sections=[(64.6, 30.0), (-112.0, 30.0), (-75.0, 30.0)], height=6.93,
                   links=30),
    SectionedScene(sections=[(-166.5, 30.0), (146.8, 30.0), (167.8, 30.0)], height=5.05,
                   links=30),
]


@pytest.mark.parametrize("scene", PAST_THE_VERTICAL)
def test_a_path_whose_links_pass_the_vertical_takes_steps_in_the_link_angles(scene,
                                                                             monkeypatch):
    res = lcpbench.solve(scene)
    assert res.converged and "in the link angles" in res.retried("ramped")
    assert np.max(np.abs(res.alpha)) > np.pi / 2  # the answer has links past the vertical
    _assert_stable_kkt_point(scene, res)
    # the premise: in the node heights alone the path stops (or its answer is refused)
    monkeypatch.setattr(ramp, "in_reach", lambda chain: False)
    assert not lcpbench.solve(scene).converged


def test_near_vertical_is_measured_from_the_vertical():
    limit = np.radians(90.0 - NEAR_VERTICAL_DEG)
    assert not near_vertical([0.0, limit - 1e-3, -limit + 1e-3])
    assert near_vertical([0.0, limit + 1e-3])
    assert near_vertical([np.pi - limit - 1e-3])  # past it, folded back


def test_the_first_sqp_of_the_path_starts_from_the_height_steps_walls_in_contact(
        monkeypatch):
    # a row of two sections (the mixed batch's kind, results/mixed-batch.md) whose path
    # turns from height steps to SQP steps near the vertical: the first SQP is handed the
    # height answer's walls in contact (lambda unknown: 0), and the path's answer is a
    # stable KKT point by the oracle
    scene = SectionedScene(sections=[(156.0, 15.0), (-154.5, 15.0)], height=2.27, links=40)
    handed = []
    real = ramp.run_heavy

    def spy(chain, start, tol, max_outer, why=""):
        handed.append(start.multipliers)
        return real(chain, start, tol, max_outer, why=why)

    monkeypatch.setattr(ramp, "run_heavy", spy)
    res = lcpbench.solve(scene)
    assert res.converged and "in the link angles" in res.retried("ramped")
    lam, up, lo = handed[0]
    assert lam == 0.0 and 1 <= np.count_nonzero(up) + np.count_nonzero(lo) < up.size
    _assert_stable_kkt_point(scene, res)
    # A route comparison, kept because the oracle checks the answer to the driver's
    # tolerance only: the SQP converges to 1e-9 rad whatever its first active set, so
    # the answer is the one of a first QP built from an empty set to round-off.
    monkeypatch.setattr(ramp, "_multipliers", lambda out, tol, force_scale: None)
    empty = lcpbench.solve(scene)
    assert empty.total_force == pytest.approx(res.total_force, rel=1e-9)


def test_the_chains_of_a_path_are_the_rows_built_at_the_scaled_bend_angles():
    # property: chains_at (one pass for the whole path) gives, at each fraction s, the
    # chain of the row built with s·theta
    row = SectionedScene(sections=[(-80, 30.0), (154, 30.0), (81, 30.0)])
    path = [0.25, 0.5, 1.0]
    for s, got in zip(path, row.chains_at(path), strict=True):
        built = SectionedScene(sections=[(s * -80, 30.0), (s * 154, 30.0),
                                         (s * 81, 30.0)]).chain()
        np.testing.assert_allclose(got.rest_alpha, built.rest_alpha, rtol=0, atol=1e-15)
        np.testing.assert_allclose(got.rest_joint, built.rest_joint, rtol=0, atol=1e-15)
    assert row.chains_at(path)[-1] is row.chain()


@pytest.mark.parametrize("scene", [
    # in a channel, the path all in height steps (one kernel call)
    SectionedScene(sections=[(137.0, 15.0), (125.0, 15.0)], height=3.17, links=40,
                   channel=True),
    # one wall, height steps then SQP steps near the vertical
    SectionedScene(sections=[(156.0, 15.0), (-154.5, 15.0)], height=2.27, links=40),
])
def test_the_height_steps_of_the_path_run_in_one_kernel_call(scene, monkeypatch):
    walked = []
    real = ramp._walked

    def spy(*args, **kw):
        got = real(*args, **kw)
        walked.append(got[0])
        return got

    monkeypatch.setattr(ramp, "_walked", spy)
    res = lcpbench.solve(scene)
    assert res.converged and "followed the load from zero" in res.retried("ramped")
    assert walked and walked[0] >= 10  # the steps far from the vertical, in one call
    _assert_stable_kkt_point(scene, res)
    # A route comparison, kept because the oracle checks the answer to the driver's
    # tolerance only: the walk is the same solve kernel step after step, so the path
    # step by step (lcpbench.model.compiled.drive each step) gives its answer to
    # round-off.
    monkeypatch.setattr(ramp, "_walk_args", lambda *a: None)
    one_by_one = lcpbench.solve(scene)
    assert one_by_one.total_force == pytest.approx(res.total_force, rel=1e-12)
    np.testing.assert_allclose(one_by_one.alpha, res.alpha, rtol=0, atol=1e-12)
