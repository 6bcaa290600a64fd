"""The polish's sign test on level links (issue 39, target 2; docs/friction.md, "What
limits target 2"): a sticking pair joined to an earlier sticking pair by a level link
has its T held at the answer's split instead of its (dependent) slip equation; its slip
must still be zero, else the set is not an answer. The expectation is the exact
(Fraction) solution of the step, by enumeration of the two pairs' states, not the
polish's own output."""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import numpy as np
from friction_oracle import recorded

from lcpbench import ActuatorScene
from lcpbench.model.friction_lemke import polish_args, polish_kernels
from lcpbench.thresholds import POLISH_FLIPS, POLISH_LEVEL

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import exact_friction as ef  # noqa: E402


def channel_step():
    """The frictional step of a channel (θ 180°: the chain lies on the upper wall, its
    two end links of each contact run exactly level), and Lemke's answer."""
    scene = ActuatorScene(theta=180, height=2.0, links=40, channel=True, friction=0.3,
                          left_end="slider", right_end="slider", pull=0.0)
    res, steps = recorded(scene, [{}], tol=None)
    assert res[0].converged
    return steps[-1]


def test_a_held_sticking_pair_whose_slip_breaks_the_level_link_is_refused_and_flipped():
    """Two sticking pairs joined by a level link: their x move together, so the second's
    slip equation is dependent and the polish holds its T instead. Its slip from the last
    state moved by 1e-6 mm, the two stick equations contradict each other: exactly, the
    answer's set has no solution (the oracle: the slip equation fails), and of the nine
    states of the two pairs (the rest as the answer reads them) only the second sliding
    forward is an exact answer. The polish of the answer's set must refuse it (a sign
    fails), flip that pair forward, and what it keeps there is the exact solution."""
    fs, sol = channel_step()
    k = polish_kernels()
    mn, mt = fs.normal_node.size, fs.friction_node.size
    z = sol.z
    contact, state = k.index_set(z, fs.M @ z + fs.q, mn, mt, fs.pair, fs.mu)
    tan = fs.parts["tan"]
    # the first two pairs stick, at adjacent nodes joined by a level link
    a, b = np.argsort(fs.friction_node, kind="mergesort")[:2]
    i = int(fs.friction_node[a])
    assert int(fs.friction_node[b]) == i + 1 and abs(tan[i]) <= POLISH_LEVEL
    assert state[a] == state[b] == k.STICK and fs.tangent_xy[b, 1] == 0.0
    fs.parts["slip"] = fs.parts["slip"].copy()
    fs.parts["slip"][b] += 1e-6  # mm
    step = ef.chain_step(fs)
    v = ef.answer_values(fs, step, z)
    rows, pairs = ef.read_states(step, v)
    assert pairs[a] == pairs[b] == ef.STICK
    exact = []
    for sa, sb in itertools.product((ef.STICK, ef.FORWARD, ef.BACKWARD), repeat=2):
        p = list(pairs)
        p[a], p[b] = sa, sb
        if ef.solve(step, rows, p, v).solution:
            exact.append((sa, sb))
    assert ef.solve(step, rows, pairs, v).failed == [("slip", int(b))]
    assert exact == [(ef.STICK, ef.FORWARD)]
    head, answer = polish_args(fs, z)
    own = k.polish_on(*head, *answer, 0, contact, state)
    assert own[0] == k.SIGNS
    np.testing.assert_array_equal(own[1], z)  # a refused polish returns z as it was
    assert own[5][b] == k.FORWARD and own[5][a] == k.STICK
    out = k.polish_on(*head, *answer, POLISH_FLIPS, contact, state)
    assert out[0] == k.KEPT
    ex, dist, _ = ef.nearest_exact(step, ef.answer_values(fs, step, out[1]), search=False)
    assert ef.confirmed(ex, dist), dist
    assert (ex.pairs[a], ex.pairs[b]) == (ef.STICK, ef.FORWARD)
