"""The warm-started frictional step (StepLemke: block principal pivoting from the last
answer's support, Lemke where it fails) and pull-out at N = 140 (issue 39, target 5).

Expectations are independent of the step's code: today's frictionless solve (the μ = 0
limit), the gross-slip identity P* = Σ μ N on flat walls, Coulomb's law read off each
node, and Siconos' fc2d solvers on the same steps the warm start answered.
"""


import numpy as np
import pytest
from friction_oracle import coulomb_holds, frictionless_by_the_frictional_path

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.model.friction_driver import FrictionState, StepLemke, solve_state
from lcpbench.model.friction_result import build_result
from lcpbench.model.friction_solvers import fc2d_contacts
from lcpbench.solvers import siconos_bridge
from lcpbench.studies.pull_out import pull_out

TIGHT = 1e-12


class Recording(StepLemke):
    """StepLemke, keeping each step it answered from the last support."""

    def __init__(self):
        super().__init__()
        self.warm = []

    def last_support(self, M, q, keys):
        sol = super().last_support(M, q, keys)
        if sol is not None:
            self.warm.append((M, q, sol))
        return sol

    def __call__(self, fs, q=None, polish=True):
        self.step = fs
        before = len(self.warm)
        sol = super().__call__(fs, q, polish)
        if len(self.warm) > before:
            self.warm[-1] = (fs, sol)
        return sol


@pytest.mark.parametrize("kw", [dict(theta=150, height=3.0),
                                dict(theta=170, height=2.5, channel=True)],
                         ids=["flat", "channel"])
def test_mu_zero_with_warm_steps_is_the_frictionless_answer(kw):
    """μ = 0 (pin and slider) from the rest arc, its later outer steps answered by the
    warm start, against today's solve: 1e-10 relative per node."""
    base = ActuatorScene(links=30, **kw)
    lcp = Recording()
    frictionless_by_the_frictional_path(base, lcp, TIGHT)
    assert lcp.warm  # the warm start answered steps (else this tests Lemke alone)


@pytest.mark.parametrize("kw", [dict(theta=150, height=3.0, friction=0.3),
                                dict(theta=180, height=2.0, channel=True,
                                     friction=(0.3, 0.1))],
                         ids=["flat", "channel"])
def test_pull_out_at_n140_is_mu_times_the_normal_forces(kw):
    """The scenes of benchmarks/friction_speed.py (N = 140, sliders): the pull-out
    converges within its 20 frictional solves, and at gross slip on flat walls the pull
    is Σ μ N over both walls (the capacity at the last state held) to 1e-5; every state
    held obeys Coulomb node by node and ΣT + P = 0. (The channel's did not converge in
    20 solves with Lemke alone: its steps stopped on rays.)"""
    scene = ActuatorScene(links=140, left_end="slider", right_end="slider", **kw)
    po = pull_out(scene)
    assert po.converged, po.reason
    assert po.solves <= 20
    assert abs(po.force - po.capacity) <= 1e-5 * po.force
    for res in po.path:
        coulomb_holds(res)
        assert abs(np.sum(res.tangential_forces) + res.pull) <= 1e-9 * max(res.pull, 1e-3)


@pytest.mark.skipif(not siconos_bridge.available(), reason="siconos not installed for the "
                    "system python (apt-get install python3-siconos)")
def test_warm_steps_agree_with_siconos_fc2d():
    """Each step of a pull path that the warm start answered, handed to Siconos'
    fc2d Lemke (and enumeration, up to 6 contacts) in its own form: where the peer is
    SOLVED its normal forces agree to 1e-6 of the largest force, and the sum of T over
    the step too (T per node is indeterminate in a run of sticking nodes)."""
    from lcpbench.solvers.siconos_fc2d import coulomb_residual, solve_fc2d

    scene = ActuatorScene(theta=150, height=3.0, links=20, friction=0.3,
                          left_end="slider", right_end="slider")
    lcp = Recording()
    path = lcpbench.solve_path(scene, [{}, {"pull": 0.02}, {"pull": 0.04}, {"pull": 0.0}],
                               tol=1e-10, lcp=lcp)
    assert all(r.converged for r in path)
    assert len(lcp.warm) >= 3
    answered = 0
    for fs, sol in lcp.warm:
        W, q, mu = fc2d_contacts(fs)
        mn = fs.normal_node.size
        ours = np.zeros(2 * mn)
        ours[0::2] = sol.z[:mn]
        T = sol.z[mn:mn + fs.friction_node.size] - sol.z[mn + fs.friction_node.size:
                                                         mn + 2 * fs.friction_node.size]
        has = fs.pair >= 0
        ours[1::2][has] = T[fs.pair[has]]
        assert coulomb_residual(W, q, mu, ours) <= 1e-8
        scale = np.abs(ours).max()
        for method in ("lemke", "enum"):
            if method == "enum" and mn > 6:
                continue
            peer = solve_fc2d(W, q, mu, method=method)
            if peer.solved:
                answered += 1
                np.testing.assert_allclose(peer.r[0::2], ours[0::2], rtol=0, atol=1e-6 * scale)
                assert abs(peer.r[1::2].sum() - ours[1::2].sum()) <= 1e-6 * scale
    assert answered >= 1


@pytest.mark.parametrize("kw", [dict(theta=150, height=3.0, links=140, friction=0.3,
                                     right_end="slider"),
                                dict(theta=200, height=3.0, links=30, friction=(0.3, 0.1),
                                     channel=True, left_end="slider", right_end="slider",
                                     pull=0.02)],
                         ids=["pin-slider-N140", "channel-N30-pulled"])
def test_elastic_steps_lemke_stopped_on_are_solved(kw):
    """Elastic walls (k = 0.1 N/mm²) where Lemke's ratio test at ties of 1e-9 stopped
    with a basic w at −1.5e-3 on every covering (the state was not converged; the first
    still is without the retry at ties of 1e-12, STRICT_TIES; the second converges with
    the warm start alone): each converges, Coulomb node by node, and the normal forces
    follow the Winkler law N = k a (y − h)₊ read off the link angles."""
    scene = ActuatorScene(wall_stiffness=0.1, **kw)
    path = lcpbench.solve_path(scene, [{}] if "pull" not in kw else
                               [{"pull": 0.0}, {"pull": kw["pull"]}])
    for res in path:
        assert res.converged, res.reason
        coulomb_holds(res)
    res = path[-1]
    a = scene.length / scene.links
    y = np.concatenate([[0.0], np.cumsum(a * np.sin(res.alpha))])[1:scene.links]
    depth = np.maximum(y - scene.height, 0.0)
    np.testing.assert_allclose(res.forces / (0.1 * a), depth, rtol=0,
                               atol=1e-6 * scene.length + 1e-6 * depth.max())


class GaussNewton(StepLemke):
    """StepLemke on the paper's Gauss–Newton steps (the springs' curvature left out)."""

    newton = False


@pytest.mark.parametrize("kw", [dict(theta=150, height=3.0, friction=0.3),
                                dict(theta=180, height=2.0, channel=True,
                                     friction=(0.3, 0.1))],
                         ids=["flat", "channel"])
def test_newton_steps_reach_the_same_state_faster(kw):
    """A pulled state from the rest arc: its fixed point does not depend on the step's
    Hessian (δ = 0 there), so Newton's steps (H + T near the answer) and Gauss–Newton's
    end on the same forces (1e-9 of the largest), and the state obeys Coulomb node by
    node. Gauss–Newton's steps shrink by a constant factor (~0.02–0.03 here: the springs'
    curvature it leaves out); Newton's last step is below 1e-2 of the one before, and it
    takes fewer steps."""
    scene = ActuatorScene(links=30, left_end="slider", right_end="slider", pull=0.01, **kw)
    chain = scene.chain()
    rest = FrictionState(chain.rest_alpha.copy())
    x_prev = rest.positions(chain)[0]
    got = {}
    for lcp in (StepLemke(), GaussNewton()):
        ans = solve_state(scene, rest, x_prev, tol=1e-10, max_outer=30, lcp=lcp)
        assert ans.converged, ans.reason
        res = build_result(scene, {}, ans, x_prev, 1e-10)
        coulomb_holds(res)
        got[lcp.newton] = ans, res
    (new, new_res), (old, old_res) = got[True], got[False]
    scale = max(np.max(old_res.forces), old_res.pull)
    np.testing.assert_allclose(new_res.forces, old_res.forces, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(new_res.tangential_forces, old_res.tangential_forces,
                               rtol=0, atol=1e-9 * scale)
    assert new.step_sizes[-1] < 1e-2 * new.step_sizes[-2]
    assert old.step_sizes[-1] > 1e-2 * old.step_sizes[-2]  # (the contrast)
    assert len(new.step_sizes) < len(old.step_sizes)
