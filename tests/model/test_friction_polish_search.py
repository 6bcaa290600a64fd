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


def test_the_edge_picks_keep_every_changed_set_where_an_edge_node_is_off():
    """An edge node whose own state is none of its choices (an off pair, its row coming
    into contact: its choices stick, forward, backward) makes every pick differ from the
    answer's own set; by enumeration of the 2 · 3 · 3 states of a row in contact, that
    off pair and a sticking pair, the picks are all 18 (none equal to the own states),
    the fewest changes first (1: the off pair sticking, or forward, or backward, the
    rest as they are — 3 of them; then 2, then 3), in the product's order within a tie;
    with a budget of 4, the 3 of one change and the first of two. Where the own states
    are among the choices the picks are the 17 others (the own one left out)."""
    k = polish_kernels()
    choices = [(1, 0), (k.STICK, k.FORWARD, k.BACKWARD), (k.STICK, k.FORWARD, k.BACKWARD)]
    for now in ([1, k.OFF, k.STICK], [1, k.STICK, k.STICK]):

        def changes(p, now=now):
            return sum(a != b for a, b in zip(p, now))

        every = [p for p in itertools.product(*choices) if changes(p) > 0]
        expect = sorted(every, key=changes)  # (a stable sort: the product's order in a tie)
        assert len(expect) == (18 if now[1] == k.OFF else 17)
        assert tuple(now) not in expect
        for most in (4, 100):
            picks, ok = edge_order(choices, now, [c for c in choices], most)
            assert [tuple(int(v) for v in p) for p in picks] == expect[:most]
            assert ok.all()  # (every state likely)
        if now[1] == k.OFF:
            assert [changes(p) for p in expect[:4]] == [1, 1, 1, 2]


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
    had nothing to keep. (The pull-out as it was before ASSUME_SLIP, a gross slip solved
    at its second state, and before an attempt after a gross slip was warm-started from
    the last held state's support (StepLemke.rewind): its third state then starts from
    the sliding answer's support and takes the outer steps that repeat a refusal.)"""
    import lcpbench.studies.pull_out as study

    monkeypatch.setattr(study, "ASSUME_SLIP", False)
    monkeypatch.setattr(friction_lemke.StepLemke, "rewind", lambda self, warm: None)
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


#: benchmarks/friction_agreement.py's path 12 (seed 39): N = 80, μ 0.99, slider–pinned
PATH_12 = ActuatorScene(theta=140.1888023115021, height=2.5552526829615783, links=80,
                        friction=0.9904804925320116, left_end="slider", right_end="pinned")


def test_sticking_runs_sum_their_T_across_level_links():
    """A run of sticking pairs joined neighbour by neighbour by links with |tan α| at
    most POLISH_LIKELY_LEVEL shares its T's sum (by hand: pairs at nodes 3, 4, 5 on
    links of 0 and 5e-10, then a link of 1e-6 to node 6; a sliding pair at node 7 and a
    sticking one at 8 across a level link: not joined to a slide)."""
    k = polish_kernels()
    tan = np.array([1e-3, 1e-3, 1e-3, 0.0, 5e-10, 1e-6, 1e-3, 0.0, 1e-3])
    node = np.array([8, 3, 4, 5, 6, 7])  # (unsorted: the runs are by node)
    state = np.array([k.STICK, k.STICK, k.STICK, k.STICK, k.STICK, k.FORWARD])
    T = np.array([0.5, -0.25, 0.0, 0.5, -0.375, -0.125])  # (sums exact in binary)
    runs = friction_lemke.run_sums(k, tan, node, state, T)
    np.testing.assert_array_equal(runs, [0.5, 0.25, 0.25, 0.25, -0.375, -0.125])


def test_path_12_state_1_is_polished_onto_its_exact_answer(monkeypatch):
    """The agreement's state 12.1 (its last step): Lemke's answer sticks at two runs of
    two pressed nodes (35–36 and 42–43), each run on a link level to 1e-14, the chain
    between them sloped ~1e-6, and the answer's T of each run sits on one node of it
    (0 on the other). The exact oracle (Fractions: flips, then every state of its edge
    nodes) puts the exact answer three pair changes away: 36, 42 and 43 sliding
    forward, against their run's T (the sum; node 42's own T is 0), and the answer
    is 6.8e-6 of the largest force from it in N. The polish keeps that answer (after the
    first flip, by the likely picks: the search's 6 failing nodes put it at the 106th
    pick of the fewest changes, past the 64 sets): it is the oracle's exact solution of
    its set, every sign holding exactly, within 1e-12 in N and in the move.

    Which of the three pairs Lemke's answer already slides is its round-off's: on one
    host it slides 36 forward already and sticks 42–43 (two changes). So the test holds
    what the oracle fixes — the exact set slides 36, 42, 43 forward — and that Lemke's
    answer differs from it at sticking pairs among those three only."""
    calls = spied(monkeypatch)
    res = lcpbench.solve_path(PATH_12, [{}, {"theta": 150.1888023115021}])
    assert all(r.converged for r in res)
    fs, z0, out = calls[-1]
    assert out.extra["polish"] == "kept"
    step = ef.chain_step(fs)
    first, d0, _ = ef.nearest_exact(step, ef.answer_values(fs, step, z0))
    assert first.solution and 1e-6 < d0[0] < 1e-5  # Lemke's answer: off
    ex, dist, _ = ef.nearest_exact(step, ef.answer_values(fs, step, out.z), search=False)
    assert ex.solution and max(dist[0], dist[2]) <= 1e-12
    k = polish_kernels()
    mn, mt = fs.normal_node.size, fs.friction_node.size
    contact, state = k.index_set(z0, fs.M @ z0 + fs.q, mn, mt, fs.pair, fs.mu)
    exact = [k.OFF if p is None else p for p in first.pairs]
    assert list(contact) == [bool(r) for r in first.rows]
    changed = {int(fs.friction_node[c]): exact[c] for c in range(mt) if exact[c] != state[c]}
    slides = {int(fs.friction_node[c]): exact[c] for c in range(mt)
              if fs.friction_node[c] in (36, 42, 43)}
    assert slides == {36: k.FORWARD, 42: k.FORWARD, 43: k.FORWARD}
    assert changed and set(changed) <= set(slides)
    assert all(v == k.FORWARD for v in changed.values())
    assert all(state[c] == k.STICK for c in range(mt) if fs.friction_node[c] in changed)
