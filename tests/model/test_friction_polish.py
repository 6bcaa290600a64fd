"""The frictional step's primal polish (issue 39, target 2; model/friction_polish.py).

Expectations are independent of the polish: the exact solution of the answer's index
set in rational arithmetic (benchmarks/exact_friction.py, from the step's doubles, not
from its Delassus matrix), the sign conditions read off the polished forces and slips,
and today's frictionless solve (the μ = 0 limit).
"""

import sys
from pathlib import Path

import numpy as np
import pytest
from friction_oracle import frictionless_by_the_frictional_path, recorded

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.model import friction_lemke
from lcpbench.model.friction_driver import StepLemke
from lcpbench.model.friction_lemke import (
    POLISH_VERDICTS,
    polish_args,
    polish_kernels,
    polish_step,
)
from lcpbench.solvers.base import LCPSolution, Status
from lcpbench.thresholds import POLISH_MOST_FAILING, POLISH_STICK_COMPLIANCE, POLISH_SWEEPS

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import exact_friction as ef  # noqa: E402
from friction_agreement import scenes  # noqa: E402


def exact_gap(fs, z):
    """(the exact solution of z's index set found, its distance to z in N and the move)."""
    step = ef.chain_step(fs)
    v = ef.answer_values(fs, step, z)
    ex, dist, _ = ef.nearest_exact(step, v)
    return ex, max(dist[0], dist[2])


def test_polish_lands_on_the_exact_answer_of_the_index_set():
    """Path 3 of benchmarks/friction_agreement.py's set (N = 12): Lemke's warm-started
    answers of three steps sit 1.2e-6 (in N, of the largest force) from the exact
    solution of their own index set, solved in Fractions; polished, every answer is an
    exact answer to 1e-9 and none is farther from it than before."""
    scene, states = list(scenes(4, 39))[3]
    res, steps = recorded(scene, states)
    assert all(r.converged for r in res)
    worst_before, kept = 0.0, 0
    for fs, sol in steps:
        assert sol.extra["polish"] in POLISH_VERDICTS
        if sol.extra["polish"] != "kept":
            continue
        kept += 1
        ex, after = exact_gap(fs, sol.z)
        ex0, before = exact_gap(fs, sol.extra["unpolished"])
        assert ex.solution and not ex.ray and after <= 1e-9
        assert after <= max(before, 1e-12)
        worst_before = max(worst_before, before)
    assert kept >= len(steps) // 2
    assert worst_before > 1e-7  # the polish had something to do


def first_step(scene):
    """The first frictional step of a one-state path of ``scene``, and its answer."""
    res, steps = recorded(scene, [{}])
    assert res[0].converged
    return steps[-1]


def test_polish_refuses_an_index_set_whose_signs_fail():
    """Every pressed node's answer made to slide the wrong way (T = +μN: then Σ T has the
    pull's sign, so the exact solution of that set cannot hold the chain without a
    forward slip). One node alone would not do: a run of sticking nodes shares its T in
    any way (statically indeterminate), and one of them sliding backward at zero slip is
    an answer too. Without a flip the polish refuses it and returns z unchanged;
    whatever polish_step keeps (POLISH_FLIPS) meets every sign: N >= 0, |T| <= μN, a
    sliding node's slip against its T; what it refuses keeps its status and z."""
    fs, sol = first_step(ActuatorScene(theta=150, height=3.0, links=20, friction=0.3,
                                       left_end="pinned", right_end="slider", pull=0.05))
    z = sol.z.copy()
    mn, mt = fs.normal_node.size, fs.friction_node.size
    N = z[:mn]
    pressed = [c for c in range(mt) if np.any((fs.pair == c) & (N > 0))]
    assert pressed
    for c in pressed:  # the index set: each pressed pair slides backward (β⁺ = μN, λ > 0)
        r = int(np.flatnonzero(fs.pair == c)[0])
        z[mn + c], z[mn + mt + c], z[mn + 2 * mt + c] = fs.mu[r] * N[r], 0.0, 1e-3
    w = fs.M @ z + fs.q
    P = fs.parts
    Nf, T, dy, tau = fs.forces(z)
    args = (P["bands"], P["f"], P["tan"], float(P["k_tau"]), int(P["first"]),
            bool(P["right_datum"]), P["gap"], P["slip"], P["compliance"], fs.normal_node,
            fs.normal_xy, fs.friction_node, fs.tangent_xy, fs.mu, fs.pair, P["rot"],
            float(P["rot_k"]), z, w, dy,
            float(tau), Nf, T, float(fs.force), float(fs.length),
            float(fs.length) / P["tan"].size, POLISH_STICK_COMPLIANCE, POLISH_SWEEPS)
    k = polish_kernels()
    code, z_new, _, _ = k.polish(*args, 0)
    assert code == k.SIGNS
    np.testing.assert_array_equal(z_new, z)
    bad = LCPSolution(z, w, Status.SOLVED, extra={})
    refused = polish_step(fs, LCPSolution(z, w, Status.SOLVED, extra={}), 0)
    assert refused.status is Status.SOLVED and refused.extra["polish"] == "a sign fails"
    np.testing.assert_array_equal(refused.z, z)
    out = polish_step(fs, bad)
    assert out.status is Status.SOLVED  # never changed by the polish
    if out.extra["polish"] == "kept":  # its flipped set: every sign holds
        N2, T2, _, _ = fs.forces(out.z)
        assert np.all(N2 >= -1e-12 * np.max(N2))
        cone = np.zeros(mt)
        np.add.at(cone, fs.pair[fs.pair >= 0], (fs.mu * N2)[fs.pair >= 0])
        assert np.all(np.abs(T2) <= cone + 1e-12 * np.max(N2))
        s = (out.w[mn:mn + mt] - out.w[mn + mt:mn + 2 * mt]) / 2  # the slips (β± rows)
        sliding = np.abs(T2) >= cone - 1e-12 * np.max(N2)
        assert np.all(s[sliding & (T2 > 0)] <= 1e-12) and np.all(s[sliding & (T2 < 0)] >= -1e-12)
        # and it is an exact answer of the step: the Fraction solution of its index set
        step = ef.chain_step(fs)
        ex, dist, _ = ef.nearest_exact(step, ef.answer_values(fs, step, out.z), search=False)
        assert ef.confirmed(ex, dist), dist
    else:
        np.testing.assert_array_equal(out.z, z)



def test_the_edge_search_kernel_skips_a_failing_set_and_keeps_an_exact_one():
    """``polish_sets`` (the edge search's sets in one compiled call) on the index sets
    that differ at the pressed pairs only: first every pressed pair sliding backward (the
    set of the test above: no exact answer holds its signs), then their states as the
    answer reads them. It must pass over the first and keep the second, and what it keeps
    is the exact (Fraction) solution of that set with every sign holding (the oracle,
    not the polish, decides); with the first set alone it keeps nothing and returns z."""
    fs, sol = first_step(ActuatorScene(theta=150, height=3.0, links=20, friction=0.3,
                                       left_end="pinned", right_end="slider", pull=0.05))
    k = polish_kernels()
    z = sol.z
    mn, mt = fs.normal_node.size, fs.friction_node.size
    w = fs.M @ z + fs.q
    contact, state = k.index_set(z, w, mn, mt, fs.pair, fs.mu)
    pressed = [c for c in range(mt) if state[c] != k.OFF]
    assert pressed
    head, answer = polish_args(fs, z)
    args = (*head, *answer)
    nodes = np.array([mn + c for c in pressed], np.int64)
    wrong = [k.BACKWARD] * len(pressed)
    own = [int(state[c]) for c in pressed]
    assert own != wrong
    none_c, none_s = np.zeros((0, mn), bool), np.zeros((0, mt), np.int64)
    code, z_new, _, _ = k.polish_sets(*args, contact, state, nodes,
                                      np.array([wrong], np.int64), 64, none_c, none_s)
    assert code == k.SIGNS
    np.testing.assert_array_equal(z_new, z)
    code, z_new, r0, r1 = k.polish_sets(*args, contact, state, nodes,
                                        np.array([wrong, own], np.int64), 64, none_c, none_s)
    assert code == k.KEPT and r1 < r0
    N2, T2, _, _ = fs.forces(z_new)
    assert np.all(N2 >= -1e-12 * np.max(N2))
    cone = np.zeros(mt)
    np.add.at(cone, fs.pair[fs.pair >= 0], (fs.mu * N2)[fs.pair >= 0])
    assert np.all(np.abs(T2) <= cone + 1e-12 * np.max(N2))
    step = ef.chain_step(fs)
    ex, dist, _ = ef.nearest_exact(step, ef.answer_values(fs, step, z_new), search=False)
    assert ef.confirmed(ex, dist), dist
    assert [ex.pairs[c] for c in pressed] == own  # the set it kept is the second
    # a set listed as solved (its signs failed) is passed over, here the one it kept
    c2, s2 = contact.copy(), state.copy()
    s2[pressed] = own
    code, z_new, _, _ = k.polish_sets(*args, contact, state, nodes,
                                      np.array([wrong, own], np.int64), 64, c2[None],
                                      s2[None])
    assert code == k.SIGNS
    np.testing.assert_array_equal(z_new, z)

def test_polish_never_raises_a_status():
    """An answer that is not SOLVED is not polished and keeps its status and z."""
    fs, sol = first_step(ActuatorScene(theta=150, height=3.0, links=12, friction=0.3,
                                       left_end="pinned", right_end="slider"))
    bad = LCPSolution(sol.z.copy(), sol.w.copy(), Status.INACCURATE, extra={})
    out = polish_step(fs, bad)
    assert out.status is Status.INACCURATE and out.extra["polish"] == "not SOLVED"
    np.testing.assert_array_equal(out.z, sol.z)


class Recording(StepLemke):
    def __init__(self):
        super().__init__()
        self.verdicts = []

    def __call__(self, fs, q=None, polish=True):
        sol = super().__call__(fs, q, polish)
        self.verdicts.append(sol.extra.get("polish"))
        return sol

    def polish(self, fs, sol, *flips):  # (the driver's: the answer that would end a state)
        out = super().polish(fs, sol, *flips)
        self.verdicts.append(out.extra.get("polish"))
        return out


@pytest.mark.parametrize("kw", [dict(theta=150, height=3.0),
                                dict(theta=170, height=2.5, channel=True)],
                         ids=["flat", "channel"])
def test_mu_zero_polished_step_is_the_frictionless_answer(kw):
    """μ = 0 (pin and slider), the answer that ends each state through the polish,
    against today's solve: 1e-10 relative per node, and the polish kept at least one
    step's answer."""
    base = ActuatorScene(links=30, **kw)
    lcp = Recording()
    res = frictionless_by_the_frictional_path(base, lcp, 1e-12)
    assert "kept" in lcp.verdicts
    assert np.all(res.tangential_forces == 0.0)


class Steps(StepLemke):
    """The default step solver, keeping every step and its answer as the driver took it
    (the answer that would end a state replaced by its polish)."""

    def __init__(self):
        super().__init__()
        self.steps = []

    def __call__(self, fs, q=None, polish=True):
        sol = super().__call__(fs, q, polish)
        self.steps.append((fs, sol))
        return sol

    def polish(self, fs, sol, *flips):
        out = super().polish(fs, sol, *flips)
        if self.steps and self.steps[-1][1] is sol:
            self.steps[-1] = (fs, out)
        return out


def test_a_state_reports_its_polished_answer_and_the_judge_passes_it():
    """Path 3 of benchmarks/friction_agreement.py's set (N = 12) by the default path: the
    polish runs on the answers that end a state, not on the steps before them (fewer
    polished steps than steps). Each converged state's last step went through the polish;
    where it was kept, the state's reported normal and tangential forces are that polished
    answer's (bit for bit), which is the exact solution of its index set (in Fractions,
    benchmarks/exact_friction.py) to 1e-9, and the judge passes the state."""
    scene, states = list(scenes(4, 39))[3]
    lcp = Steps()
    res = lcpbench.solve_path(scene, states, tol=1e-8, lcp=lcp)
    assert all(r.converged and r.route == "frictional" for r in res)
    assert len(lcp.steps) == sum(r.outer_iterations for r in res)
    polished = [sol for _, sol in lcp.steps if "polish" in sol.extra]
    assert len(res) <= len(polished) < len(lcp.steps)
    end, kept = 0, 0
    for r in res:
        end += r.outer_iterations
        fs, sol = lcp.steps[end - 1]
        assert sol.extra["polish"] in POLISH_VERDICTS and sol.solved
        assert r.judgement["fails"] == []  # the judge, on the state as reported
        if sol.extra["polish"] != "kept":
            continue
        kept += 1
        N, T, _, _ = fs.forces(sol.z)
        forces = r.forces + (r.forces_lower if r.forces_lower is not None else 0.0)
        np.testing.assert_array_equal(forces[fs.normal_node], N)
        np.testing.assert_array_equal(
            r.tangential_forces[fs.friction_node - fs.parts["first"]], T)
        ex, gap = exact_gap(fs, sol.z)
        assert ex.solution and not ex.ray and gap <= 1e-9
    assert kept >= 1


@pytest.mark.parametrize("kw", [dict(theta=150, height=3.0, links=20, friction=0.3),
                                dict(theta=180, height=2.0, links=40, channel=True,
                                     friction=(0.3, 0.1))], ids=["flat", "channel"])
def test_the_flips_end_where_they_would_go_round(kw):
    """``polish_on`` with flips against its own steps replayed one by one (``polish_on``
    without flips on the set the step before flipped to), from an index set made to
    slide the wrong way: the sets it reports solved are the replay's, in order, each a
    set whose signs fail, none twice; it stops early only where the replay's next set is
    one of them (from there the replay goes round: each step is a function of its set),
    and its verdict and z are the replay's after the whole budget."""
    scene = ActuatorScene(left_end="slider", right_end="slider", pull=0.05, **kw)
    fs, sol = first_step(scene)
    k = polish_kernels()
    z = sol.z.copy()
    mn, mt = fs.normal_node.size, fs.friction_node.size
    pressed = [c for c in range(mt) if np.any((fs.pair == c) & (z[:mn] > 0))]
    for c in pressed:
        r = int(np.flatnonzero(fs.pair == c)[0])
        z[mn + c], z[mn + mt + c], z[mn + 2 * mt + c] = fs.mu[r] * z[r], 0.0, 1e-3
    w = fs.M @ z + fs.q
    head, answer = polish_args(fs, z)
    args = (*head, *answer)
    contact, state = k.index_set(z, w, mn, mt, fs.pair, fs.mu)
    flips = 8
    out = k.polish_on(*args, flips, contact, state)
    replay, c, s = [], contact, state
    for _ in range(flips + 1):
        step = k.polish_on(*args, 0, c, s)
        replay.append((c, s, step))
        if step[0] != k.SIGNS:
            break
        c, s = step[4], step[5]
    assert out[0] == replay[-1][2][0]
    np.testing.assert_array_equal(out[1], replay[-1][2][1])
    if out[0] != k.SIGNS:
        return
    seen_c, seen_s = out[6], out[7]
    assert 1 <= len(seen_c) <= flips + 1
    keys = [(a.tobytes(), b.tobytes()) for a, b in zip(seen_c, seen_s)]
    assert len(set(keys)) == len(keys)
    for i in range(len(seen_c)):
        np.testing.assert_array_equal(seen_c[i], replay[i][0])
        np.testing.assert_array_equal(seen_s[i], replay[i][1])
    if len(seen_c) < flips + 1:  # stopped early: its next set is one solved already
        nxt = replay[len(seen_c) - 1][2]
        assert (nxt[4].tobytes(), nxt[5].tobytes()) in keys


def test_the_polish_gives_up_on_an_answer_far_from_its_index_set(monkeypatch):
    """An answer that reads every wall row in contact (its N raised above its gaps, N = 80
    against a flat wall, 41 rows): the exact solution of that index set (Fractions,
    benchmarks/exact_friction.py) breaks far more sign conditions than round-off at a few
    nodes could (more than POLISH_MOST_FAILING: most rows would pull on the wall). The
    polish then solves that one set and gives up: no flip, no edge search; the answer is
    returned bit for bit with the status it came with (its LCP residual's)."""
    fs, sol = first_step(ActuatorScene(theta=150, height=3.0, links=80, friction=0.3,
                                       left_end="pinned", right_end="slider", pull=0.05))
    z = sol.z.copy()
    mn = fs.normal_node.size
    for _ in range(50):  # every row's N at least its gap: the index set reads contact
        w = fs.M @ z + fs.q
        if np.all(z[:mn] >= w[:mn]):
            break
        z[:mn] = np.maximum(z[:mn], 1.01 * w[:mn] + 1e-12)
    w = fs.M @ z + fs.q
    step = ef.chain_step(fs)
    v = ef.answer_values(fs, step, z)
    rows, pairs = ef.read_states(step, v)
    assert all(rows)
    ex = ef.solve(step, rows, pairs, v)
    assert len(ex.failed) > POLISH_MOST_FAILING  # the oracle's count, not the polish's

    def no_search(*args):
        raise AssertionError("the edge search ran")

    monkeypatch.setattr(friction_lemke, "edge_polish", no_search)
    out = polish_step(fs, LCPSolution(z.copy(), w.copy(), Status.SOLVED, extra={}))
    assert out.status is Status.SOLVED
    np.testing.assert_array_equal(out.z, z)
    assert out.extra["polish"] == "a sign fails"
    assert len(out.extra["polish_failing"]) == 1  # the answer's own set only: no flip


def test_the_polish_still_repairs_one_failing_node():
    """Path 3 of benchmarks/friction_agreement.py's set (N = 12): the answers whose own
    index set breaks exactly one sign condition in exact arithmetic (Fractions, the
    oracle's count) are still polished (one flip) onto the exact solution of a set whose
    signs all hold, to 1e-9."""
    scene, states = list(scenes(4, 39))[3]
    res, steps = recorded(scene, states)
    one = 0
    for fs, sol in steps:
        if "polish" not in sol.extra:
            continue
        step = ef.chain_step(fs)
        v = ef.answer_values(fs, step, sol.extra.get("unpolished", sol.z))
        if len(ef.solve(step, *ef.read_states(step, v), v).failed) != 1:
            continue
        one += 1
        assert sol.extra["polish"] == "kept"
        ex, gap = exact_gap(fs, sol.z)
        assert ex.solution and not ex.ray and not ex.failed and gap <= 1e-9
    assert one >= 1
