"""Friction on rows of sections (issue 39, item 1): SectionedScene and the paper's
anchoring actuator take friction=, left_end=, right_end= and pull= as ActuatorScene.

Expectations independent of the frictional code: today's frictionless sectioned solve
(the μ = 0 limit), the single-section row being ActuatorScene's chain array for array,
force balance at gross slip (the pull-out force equals μ ΣN on flat walls) and
Coulomb's law read off each node (tests/friction_oracle.py).
"""

from dataclasses import replace

import numpy as np
import pytest
from friction_oracle import coulomb_holds

import lcpbench
from lcpbench import ActuatorScene, ProblemError
from lcpbench.problems.sections import Section, SectionedScene, anchoring_actuator

TIGHT = 1e-12
ROW = SectionedScene(sections=[(120, 15.0), (-40, 15.0, 20.0)], height=2.0, links=30)
ANCHOR = anchoring_actuator(150, 5.5, links=30)


def _bent(scene, theta):
    """``scene`` with its sharpest section at ``theta`` and the others scaled with it."""
    k = theta / scene.theta
    return replace(scene, sections=[Section(s.theta * k, s.length, s.EI, s.weight)
                                    for s in scene.sections])


@pytest.mark.parametrize("base", [ROW, ANCHOR, replace(ROW, channel=True, height=1.5)],
                         ids=["row", "anchoring", "row-channel"])
def test_mu_zero_reproduces_the_frictionless_sectioned_solve(base):
    """μ = 0 through the frictional route (a pin and a slider) along a bend ramp of
    5°, its second state iterated from the first, against lcpbench.solve of the bent
    row at tight tolerance: 1e-10 relative per node."""
    ref = lcpbench.solve(_bent(base, base.theta + 5), tol=TIGHT)
    assert ref.converged, ref.reason
    scene = replace(base, right_end="slider")
    first, res = lcpbench.solve_path(scene, [{}, {"theta": base.theta + 5}], tol=TIGHT)
    assert res.converged and res.route == "frictional", res.reason
    assert res.outer_iterations > 1  # an iteration of its own, not the start
    scale = max(np.max(ref.forces), 1e-300)
    if base.channel:
        scale = max(scale, np.max(ref.forces_lower))
        np.testing.assert_allclose(res.forces_lower, ref.forces_lower, rtol=0,
                                   atol=1e-10 * scale)
    np.testing.assert_allclose(res.forces, ref.forces, rtol=0, atol=1e-10 * scale)
    both = ref.total_force + (ref.total_force_lower or 0.0)  # ΣN over every wall
    assert abs(res.total_force - both) <= 1e-10 * both
    np.testing.assert_allclose(res.alpha, ref.alpha, rtol=0, atol=1e-10)
    assert np.max(np.abs(res.tangential_forces)) <= 1e-14 * scale


def test_one_section_is_the_actuator_scene():
    """A row of one section is ActuatorScene's chain, so its path is the same."""
    kw = dict(height=3.0, links=30, friction=0.3, left_end="slider", right_end="slider")
    states = [{}, {"pull": 0.03}, {"theta": 160}]
    one = lcpbench.solve_path(SectionedScene(sections=[Section(150.0)], **kw), states,
                              tol=1e-10)
    ref = lcpbench.solve_path(ActuatorScene(theta=150.0, **kw), states, tol=1e-10)
    for a, b in zip(one, ref, strict=True):
        assert a.converged and b.converged, (a.reason, b.reason)
        np.testing.assert_allclose(a.forces, b.forces, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a.tangential_forces, b.tangential_forces, rtol=0,
                                   atol=1e-12)


@pytest.mark.parametrize("scene", [replace(ROW, friction=0.3, left_end="slider",
                                           right_end="slider"),
                                   anchoring_actuator(150, 5.5, links=30, friction=0.3,
                                                      left_end="slider", right_end="slider")],
                         ids=["row", "anchoring"])
def test_paths_on_sections_obey_coulomb_and_balance(scene):
    """A bend ramp (every section's θ scaled), a pull and a release."""
    top = scene.theta
    path = lcpbench.solve_path(scene, [{}, {"theta": top + 10}, {"pull": 0.03},
                                       {"pull": 0.0}], tol=1e-10)
    for res in path:
        assert res.converged, res.reason
        assert res.route == "frictional"
        coulomb_holds(res)
        assert abs(np.sum(res.tangential_forces) + res.pull) <= 1e-9 * max(
            res.total_force, res.pull)
    assert path[1].scene.theta == top + 10
    signs = [np.sign(s.theta) for s in scene.sections]
    assert [np.sign(s.theta) for s in path[1].scene.sections] == signs


def test_anchoring_pull_out_is_mu_times_the_normal_forces():
    """Sliders at both ends in the flat channel: the largest pull held, by an
    independent bisection on whether one state holds, equals μ ΣN (both walls) there,
    and pull_out finds it; a little more is not held (gross slip)."""
    scene = anchoring_actuator(150, 5.5, links=30, friction=0.3, left_end="slider",
                               right_end="slider")

    def held(pull):
        (res,) = lcpbench.solve_path(replace(scene, pull=pull), [{}], tol=1e-10)
        return res

    lo, hi = 0.0, 0.3
    assert not held(hi).converged
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if held(mid).converged else (lo, mid)
    res = held(lo)
    # Lemke turns INACCURATE within ~1e-6 of gross slip (the step is degenerate: every
    # node on its cone), so the bisection stops short by that much (seen 2.6e-6)
    assert abs(lo - 0.3 * res.total_force) <= 1e-5 * lo
    pressed = res.forces + res.forces_lower > 0
    N = (res.forces + res.forces_lower)[pressed]
    np.testing.assert_allclose(-res.tangential_forces[pressed], 0.3 * N, rtol=1e-5)
    po = lcpbench.pull_out(scene)
    assert po.converged, po.reason
    assert po.solves <= 20
    assert abs(po.force - lo) <= 1e-5 * lo  # (seen 1.2e-6: the bisection's shortfall)
    (over,) = lcpbench.solve_path(replace(scene, pull=1.001 * po.force), [{}], tol=1e-10)
    assert not over.converged and "gross slip" in over.reason


@pytest.mark.parametrize("kw,words", [
    (dict(pull=0.01), "pull acts on the right end"),
    (dict(right_end="free"), "a free end needs channel=True"),
    (dict(friction=-0.1), "friction"),
    (dict(left_end="slider", right_end="slider"), "nothing holds the chain along x"),
    (dict(left_end="roller"), "left_end"),
])
def test_sectioned_bad_options_give_one_clear_error(kw, words):
    with pytest.raises(ProblemError, match=words):
        replace(ROW, **kw)


def test_sectioned_scenes_go_along_a_path_only():
    scene = replace(ROW, friction=0.3, right_end="slider")
    with pytest.raises(ProblemError, match="solve_path"):
        lcpbench.solve(scene)
    with pytest.raises(ProblemError, match="may change"):
        lcpbench.solve_path(scene, [{"gravity": "+y"}])
    with pytest.raises(ProblemError, match="anchoring_actuator takes friction"):
        anchoring_actuator(150, 5.5, links=30, mu=0.3)
