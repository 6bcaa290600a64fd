"""The polish's search (issue 39, target 5; model/friction_lemke.py): the edge search's
order (:func:`edge_order`, the likely states first) and a state's repeated refusal
(:func:`polish_step`'s ``refused``).

Expectations are independent of the polish: the exact solution of an index set in
rational arithmetic (benchmarks/exact_friction.py, from the step's doubles), the
enumeration of the picks, and the answers returned bit for bit.
"""

import itertools
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.model import friction_lemke
from lcpbench.model.friction_lemke import edge_order, likely_states, polish_kernels

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import exact_friction as ef  # noqa: E402

#: benchmarks/friction_speed.py's channel (N = 140, μ 0.3 above, 0.1 below)
CHANNEL = ActuatorScene(theta=180, height=2.0, links=140, channel=True, friction=(0.3, 0.1),
                        left_end="slider", right_end="slider")


def spied(monkeypatch):
    """Every polish the driver asks for: (step, answer's z, what it returned)."""
    calls, polish = [], friction_lemke.polish_step

    def spy(fs, sol, *more):
        z = sol.z.copy()
        out = polish(fs, sol, *more)
        calls.append((fs, z, out))
        return out

    monkeypatch.setattr(friction_lemke, "polish_step", spy)
    return calls


def test_the_edge_picks_are_the_fewest_changes_and_the_likely_ones_marked():
    """Three edge nodes (a wall row, a sticking pair with T < 0, a pair sliding backward):
    by enumeration of every state of the three (3 · 3 · 2), the picks are those with the
    fewest changes from the answer's own states but the own one, in the product's order
    within a tie (with a budget of 11: the 5 of one change and 6 of the 8 of two); a
    pick is marked likely where each of its states is (the row either way; the sticking
    pair sticking or sliding forward, T = −μN having T's sign; the sliding pair as it
    is or sticking)."""
    k = polish_kernels()
    mn = 1
    nodes = [0, mn + 0, mn + 1]  # row 0, pairs 0 and 1
    now = [1, k.STICK, k.BACKWARD]
    T = np.array([-0.2, 0.1])
    likely = likely_states(k, nodes, now, mn, T)
    assert [set(s) for s in likely] == [{0, 1}, {k.STICK, k.FORWARD},
                                        {k.BACKWARD, k.STICK}]
    choices = [(1, 0), (k.STICK, k.FORWARD, k.BACKWARD), (k.STICK, k.FORWARD, k.BACKWARD)]

    def changes(p):
        return sum(a != b for a, b in zip(p, now))

    before = sorted(itertools.product(*choices), key=changes)[1:12]  # (a stable sort)
    assert [changes(p) for p in before] == [1] * 5 + [2] * 6
    picks, ok = edge_order(choices, now, likely, 11)
    assert [tuple(int(v) for v in p) for p in picks] == before
    expect = [p[1] in (k.STICK, k.FORWARD) and p[2] in (k.BACKWARD, k.STICK) for p in before]
    assert list(ok) == expect and 0 < sum(expect) < 11


def test_the_channel_solve_keeps_an_exact_answer_three_changes_away(monkeypatch):
    """The channel's frictional solve (benchmarks/friction_speed.py, pull 0.05 N): its
    answer sticks at four pressed nodes, two pairs of them on links level to round-off,
    and the signs of that set fail (T per node along the nearly straight chain between
    them is all but indeterminate). The polish keeps a set whose exact solution
    (Fractions) meets every sign and is within 1e-9 of the kept answer in N and the move;
    the set the oracle reads from it differs from the answer's at three sticking pairs
    only, which slide there (at their cone, with no slip: the edge of two states). It is
    kept after the first flip (the flips went 4, 4, 4, 5, 41 before the edge search
    kept it), by the edge search's likely picks: the links between the two pairs of
    each run are nearly level, 1.2e-12 and 1.4e-12 (POLISH_LIKELY_LEVEL)."""
    calls = spied(monkeypatch)
    res = lcpbench.solve_path(replace(CHANNEL, pull=0.05), [{}])
    assert res[0].converged
    fs, z0, out = calls[-1]
    assert out.extra["polish"] == "kept" and len(out.extra["polish_failing"]) == 2
    step = ef.chain_step(fs)
    ex, dist, _ = ef.nearest_exact(step, ef.answer_values(fs, step, out.z), search=False)
    assert ex.solution and not ex.ray and max(dist[0], dist[2]) <= 1e-9
    k = polish_kernels()
    mn, mt = fs.normal_node.size, fs.friction_node.size
    contact, state = k.index_set(z0, fs.M @ z0 + fs.q, mn, mt, fs.pair, fs.mu)
    assert list(contact) == [bool(r) for r in ex.rows]
    exact = [k.OFF if p is None else p for p in ex.pairs]
    changed = [c for c in range(mt) if exact[c] != state[c]]
    assert changed and all(state[c] == k.STICK for c in changed)
    assert len(changed) == 3


def test_a_repeated_refusal_is_not_searched_and_returns_the_answer(monkeypatch):
    """The channel's pull-out: where an outer step's answer has the own index set and
    failing nodes of the state's last refused polish, it is refused after its own set
    (one set solved, no flip, no edge search), bit for bit the answer it was given, its
    status SOLVED; and the exact oracle (Fractions: flips, then every state of its edge
    nodes) finds no exact answer within 1e-6 of it either, so the search it was spared
    had nothing to keep."""
    calls = spied(monkeypatch)
    res = lcpbench.pull_out(CHANNEL)
    assert res.converged
    repeats = [(fs, z, out) for fs, z, out in calls if out.extra.get("polish_repeat")]
    assert repeats
    for _, z, out in repeats:
        assert out.extra["polish"] == "a sign fails"
        assert len(out.extra["polish_failing"]) == 1
        np.testing.assert_array_equal(out.z, z)
        assert out.solved
    fs, z, _ = repeats[0]
    step = ef.chain_step(fs)
    ex, dist, _ = ef.nearest_exact(step, ef.answer_values(fs, step, z))
    assert not ef.confirmed(ex, dist)
