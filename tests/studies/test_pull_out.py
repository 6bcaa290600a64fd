"""Pull-out (issue 39, item 5): the largest pull held by wall friction."""

from dataclasses import replace

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene, ProblemError

SCENE = ActuatorScene(theta=150, height=3.0, links=30, friction=0.3, left_end="slider",
                      right_end="slider")


def _held(scene, pull):
    (res,) = lcpbench.solve_path(replace(scene, pull=pull), [{}], tol=1e-10)
    return res.converged


@pytest.mark.parametrize("scene", [SCENE, replace(SCENE, channel=True, theta=200,
                                                  friction=(0.3, 0.1))],
                         ids=["flat", "channel"])
def test_pull_out_is_the_largest_pull_held(scene):
    """Against an independent bisection on whether one state from the placement holds:
    the same force to 1e-6; at it, the capacity Σ μ N equals the pull (gross slip)."""
    po = lcpbench.pull_out(scene)
    assert po.converged, po.reason
    assert po.solves <= 20  # issue 39, target 5
    lo, hi = 0.0, 2.0 * po.force
    assert not _held(scene, hi)
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _held(scene, mid) else (lo, mid)
    assert abs(po.force - lo) <= 1e-6 * po.force
    assert abs(po.capacity - po.force) <= 1e-6 * po.force
    assert abs(np.sum(po.tangential_forces) + po.path[-1].pull) <= 1e-9 * po.force
    pulls = [r.pull for r in po.path]
    assert pulls == sorted(pulls) and pulls[0] == 0.0  # a loading path, from the start
    assert all(r.converged for r in po.path)


@pytest.mark.parametrize("kw,words", [
    (dict(left_end="pinned"), "left_end='slider'"),
    (dict(right_end="pinned", pull=0.0), "right_end='slider'"),
    (dict(pull=-0.01), "pull >= 0"),
])
def test_pull_out_bad_input(kw, words):
    with pytest.raises(ProblemError, match=words):
        lcpbench.pull_out(replace(SCENE, **kw))
    with pytest.raises(ProblemError, match="rtol"):
        lcpbench.pull_out(SCENE, rtol=-1)


def test_a_state_that_fails_for_another_reason_is_not_a_pull_out(monkeypatch):
    """A state that fails for another reason than gross slip (here: every state above
    a cut-off, as if Lemke stopped on a ray) says nothing of P*: pull_out does not call
    a secant extrapolation from below the cut-off converged."""
    import lcpbench.studies.pull_out as study

    real = study.advance
    cut = 0.5 * lcpbench.pull_out(SCENE).force

    def failing(scene, state, *args, **kw):
        res, end = real(scene, state, *args, **kw)
        if scene.pull > cut:
            res = replace(res, converged=False, reason="contact step 1: RAY (a test)")
        return res, end

    monkeypatch.setattr(study, "advance", failing)
    po = lcpbench.pull_out(SCENE)
    assert not po.converged
    assert "did not converge (contact step 1: RAY (a test))" in po.reason
    assert all(r.pull <= cut for r in po.path)


def test_a_cycling_outer_loop_is_not_a_gross_slip():
    """Actuator 1 at 25 psi in its channel, h 4.5 mm, μ 0.5, N 140: a state pulled far
    beyond the last held one cycled between contact sets and ran along x, and was called
    a gross slip, so that pull-out bracketed P* at 68.5 mN while friction held μΣN =
    144 mN there. At pull-out every contact node slides (Coulomb, flat walls):
    P* = μ ΣN(P*), the identity checked here."""
    scene = ActuatorScene(theta=0.81 * 172.37 + 9.78, height=4.5, links=140, channel=True,
                          friction=0.5, left_end="slider", right_end="slider")
    po = lcpbench.pull_out(scene)
    assert po.converged, po.reason
    assert po.force == pytest.approx(0.5 * po.normal_force_total, rel=1e-5)


@pytest.mark.parametrize("slope", [-1.0 / 12.0, 1.0 / 6.0], ids=["falls", "rises"])
def test_the_assumed_slip_against_a_capacity_of_known_root(monkeypatch, slope):
    """pull_out's stepping on a model of known root: a state at pull P holds iff
    P <= P*, where the capacity C(P) = 1 + slope · P (N) meets P: P* = 1 / (1 − slope)
    (12/13 N where C falls, 1.2 N where it rises). Where C falls, the pull 0.999 C(0) is
    past P* and ASSUME_SLIP takes it as a gross slip unsolved: no state is solved there,
    one solve fewer than without it. Where C rises, P* lies beyond 0.999 C(0) and the
    secant's root passes the assumed slip, which is then dropped: P* is still found.
    Either way P* to rtol."""
    import types

    import lcpbench.studies.pull_out as study

    star = 1.0 / (1.0 - slope)
    solved = []

    def advance(scene, state, current, *args, **kw):
        P = scene.pull
        solved.append(P)
        held = P <= star
        z = np.zeros(3)
        res = types.SimpleNamespace(
            converged=held, reason="held" if held else "gross slip: (a model)",
            outer_iterations=3, stick=np.zeros(3, bool), x=z, y=z, forces=z,
            forces_lower=None, tangential_forces=z, total_force=0.0, pull=P)
        return res, current

    monkeypatch.setattr(study, "advance", advance)
    monkeypatch.setattr(study, "capacity", lambda res: 1.0 + slope * res.pull)
    counts = {}
    for assume in (True, False):
        monkeypatch.setattr(study, "ASSUME_SLIP", assume)
        solved.clear()
        po = lcpbench.pull_out(SCENE)
        assert po.converged, po.reason
        assert abs(po.force - star) <= 1e-6 * star
        counts[assume] = (po.solves, list(solved))
    if slope < 0:
        assert all(P < star for P in counts[True][1])  # no gross slip solved
        assert any(P > star for P in counts[False][1])
        assert counts[True][0] == counts[False][0] - 1
    else:
        assert any(P > 0.999 for P in counts[True][1])  # past the assumed slip


def _held_on_a_ramp(scene, pull, step=0.01):
    """Whether ``scene`` holds ``pull`` reached by solve_path on a ramp from 0 in steps of
    at most ``step`` N (every state of the ramp held)."""
    k = max(1, int(np.ceil(pull / step)))
    states = [{"pull": float(p)} for p in np.linspace(0.0, pull, k + 1)]
    return all(r.converged for r in lcpbench.solve_path(scene, states, tol=1e-10))


@pytest.mark.parametrize("theta,height,links", [(150, 5.5, 330), (150, 5.5, 420),
                                                (180, 6.5, 420)])
def test_the_anchoring_actuator_pulls_out_where_its_first_steps_have_two_answers(
        theta, height, links):
    """The anchoring actuator (μ 0.3, sliders; 420 links is its default). After a held
    state the first outer step of the next has two answers, one with every contact node
    sliding; lead-1204's pull_out warm-started every attempt after a real gross slip
    from that sliding answer, read "gross slip" off its first step 17 times and ran out
    of solves claiming P* between 119.515 and 119.516 mN (150°, 5.5 mm, N = 420; at 330,
    126.33 mN) while P* is ~153.9 mN; at 180°, 6.5 mm it claimed P* below 151.977 mN
    (P* ~176.2 mN; there the retry from the last held state's own end state is needed,
    not from the predicted start). The pull-out must agree with an independent
    bisection on whether the pull held, each pull reached by solve_path on a ramp of
    0.01 N steps (at gross slip every node slides, T = −μN: the state there does not
    depend on the path that reached it). The channel's walls are flat: at gross slip
    the pull is μΣN (the flat-wall identity; here to 1e-5, the last held state being
    within rtol of P*)."""
    scene = lcpbench.anchoring_actuator(theta, height, links=links, friction=0.3,
                                        left_end="slider", right_end="slider")
    po = lcpbench.pull_out(scene)
    assert po.converged, po.reason
    assert po.solves <= 20
    lo, hi = 0.0, 2.0 * po.force
    assert not _held_on_a_ramp(scene, hi)
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _held_on_a_ramp(scene, mid) else (lo, mid)
    assert abs(po.force - lo) <= 1e-6 * lo
    assert abs(po.capacity - po.force) <= 1e-5 * po.force
    assert abs(0.3 * po.normal_force_total - po.force) <= 1e-5 * po.force
    assert all(r.converged for r in po.path)


def test_the_anchoring_actuator_at_friction_half_pulls_out():
    """The anchoring actuator at μ 0.5 (N = 420, sliders): lead-1204 ran out of its 20
    solves, most spent on pulls whose first outer step slid everywhere (the secant's
    root overshoots P* again and again where the capacity falls steeply before it).
    The pull-out must agree with an independent bisection on whether the pull held,
    each pull reached by solve_path on a ramp of 0.002 N steps from 0 (a coarser ramp
    can itself slide on a first step), within the bisection's width; and the channel's
    walls are flat: at gross slip the pull is μΣN (to 5e-5: the last held pull is
    within SECANT_REACH = 1e-5 of P*, and g = μΣN − P falls ~4× as fast as P rises
    there)."""
    scene = lcpbench.anchoring_actuator(150, 5.5, friction=0.5, left_end="slider",
                                        right_end="slider")
    po = lcpbench.pull_out(scene)
    assert po.converged, po.reason
    assert po.solves <= 20
    assert all(r.converged for r in po.path)
    assert abs(po.capacity - po.force) <= 5e-5 * po.force
    assert abs(0.5 * po.normal_force_total - po.force) <= 5e-5 * po.force
    lo, hi = 0.9 * po.force, 1.05 * po.force
    assert _held_on_a_ramp(scene, lo, step=0.002)
    assert not _held_on_a_ramp(scene, hi, step=0.002)
    for _ in range(14):  # to ~1e-5 of P*
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _held_on_a_ramp(scene, mid, step=0.002) else (lo, mid)
    assert lo - 1e-5 * po.force <= po.force <= hi + 1e-5 * po.force


def test_a_step_that_slides_as_a_whole_is_solved_again_by_lemkes_pivots(monkeypatch):
    """The anchoring actuator at 150°, 4.5 mm, μ 0.5 (N = 420) on the path of pulls
    pull_out took (0, 122.036, 189.255, 252.871 mN): the first outer step of the last
    state has two answers; the warm start's guess "every pair sliding" carries the chain
    ~4 m along x, Lemke's pivots on the same step slide 4 of 6 pairs and move it 3 µm.
    The state's outer loop solves such a step again and holds; without the re-solve the
    state ends in a gross slip after one outer step. Independent checks: friction holds
    the pull (μΣN > P), and a solve_path ramp of 0.002 N steps holds it too."""
    import lcpbench.model.friction_driver as driver

    scene = lcpbench.anchoring_actuator(150, 4.5, friction=0.5, left_end="slider",
                                        right_end="slider")
    states = [{}] + [{"pull": p} for p in (0.122036, 0.189255, 0.252871)]
    res = lcpbench.solve_path(scene, states, tol=1e-10)
    assert all(r.converged for r in res), res[-1].reason
    assert 0.5 * res[-1].total_force > 0.252871
    assert _held_on_a_ramp(scene, 0.252871, step=0.002)
    monkeypatch.setattr(driver, "_stick_preferred", lambda lcp, sol, out, *a: (sol, out))
    last = lcpbench.solve_path(scene, states, tol=1e-10)[-1]
    assert not last.converged and last.reason.startswith("gross slip")
    assert last.outer_iterations == 1


def test_the_quadratic_root_of_a_capacity_that_bends_down():
    """After a first-step slide pull_out steps no further than the root of the quadratic
    through the last three held (P, g): on g(P) = 1 − P − P² (concave; root (√5 − 1)/2)
    that root is exact, below the secant's; a g that does not bend down keeps the
    secant's root."""
    from lcpbench.studies.pull_out import _quadratic_root, _secant_root

    held = [(P, 1.0 - P - P * P) for P in (0.1, 0.2, 0.3)]
    secant = _secant_root(held)
    assert _quadratic_root(held, secant) == pytest.approx((np.sqrt(5.0) - 1.0) / 2.0,
                                                          rel=1e-12)
    assert _quadratic_root(held, secant) < secant
    straight = [(P, 1.0 - P) for P in (0.1, 0.2, 0.3)]
    assert _quadratic_root(straight, 1.0) == 1.0


def _stepping_model(monkeypatch, star, jump, unproven_above):
    """pull_out on a model of known root P* = ``star`` (capacity C(P) = 1 − P / 12): a
    state held iff P <= P*, except that one attempted more than ``jump`` N past the last
    held pull with the step's guesses on ends "gross slip" on its first outer step (the
    anchoring actuator's step that slides everywhere; its retry, Lemke after the held
    support, holds); a state past P* ends in gross slip after 3 outer steps, or after 1
    where ``unproven_above``. Returns the pulls solved."""
    import types

    import lcpbench.studies.pull_out as study

    solved, last = [], [0.0]

    def advance(scene, state, current, *args, lcp, **kw):
        P = scene.pull
        solved.append(P)
        spurious = lcp.guesses and P - last[0] > jump and len(solved) > 1
        held = P <= star and not spurious
        steps = 1 if spurious or unproven_above else 3
        if held:
            last[0] = P
        z = np.zeros(3)
        res = types.SimpleNamespace(
            converged=held, reason="held" if held else "gross slip: (a model)",
            outer_iterations=steps, stick=np.zeros(3, bool), x=z, y=z, forces=z,
            forces_lower=None, tangential_forces=z, total_force=0.0, pull=P)
        return res, current

    monkeypatch.setattr(study, "advance", advance)
    monkeypatch.setattr(study, "capacity", lambda res: 1.0 - res.pull / 12.0)
    return solved


def test_a_gross_slip_on_a_first_step_is_retried_before_it_bounds_p_star(monkeypatch):
    """A gross slip read off one outer step, where the step has a sliding answer beside
    the held one, is retried (Lemke after the last held state's support) and holds: P*
    is found to rtol, and no pull below it is ever claimed as a gross slip."""
    star = 12.0 / 13.0
    solved = _stepping_model(monkeypatch, star, jump=0.05, unproven_above=False)
    po = lcpbench.pull_out(SCENE)
    assert po.converged, po.reason
    assert abs(po.force - star) <= 1e-6 * star
    assert po.solves == len(solved) <= 20


def test_a_gross_slip_on_a_first_step_never_brackets_p_star(monkeypatch):
    """Where every state past P* ends its gross slip on its first outer step (retried
    too), none of them is a bound on P*: the reason never claims a bracket; P* is the
    secant's root (the model's capacity is linear) and is right."""
    star = 12.0 / 13.0
    _stepping_model(monkeypatch, star, jump=np.inf, unproven_above=True)
    po = lcpbench.pull_out(SCENE)
    assert "lies between" not in po.reason and "bracketed" not in po.reason
    if po.converged:
        assert abs(po.force - star) <= 1e-6 * star


def test_an_actuator_clear_of_the_walls_holds_no_pull():
    """θ = 60° at h = 4.5 mm clears the wall: with no normal force friction holds
    nothing, so P* = 0 (theory), said so in one solve; and a small pull is not held
    (independently, by one state of solve_path)."""
    scene = replace(SCENE, theta=60.0, height=4.5)
    po = lcpbench.pull_out(scene)
    assert po.converged and po.force == 0.0 and po.solves == 1
    assert "no wall contact" in po.reason
    assert po.normal_force_total == 0.0 and po.capacity == 0.0
    assert not _held(scene, 1e-3)
