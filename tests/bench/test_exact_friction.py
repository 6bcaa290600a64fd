"""The exact oracle of the frictional step (benchmarks/exact_friction.py) and its
classifier, on steps whose answers are known by construction."""

from __future__ import annotations

import sys
from fractions import Fraction as Q
from pathlib import Path

import numpy as np
import pytest
from friction_oracle import recorded

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import exact_friction as ef  # noqa: E402


def one_contact(mu):
    """One contact, unknowns (δ1, δ2, N, T): K = I, G_n = (1, 0), G_t = (9/10, 3/10),
    f = 0, so g = 4/5 + N + (9/10) T and s = 2 + (9/10) N + (9/10) T (W = GᵀG, positive
    definite). With μ = 2 it has two answers: separate (N = T = 0, g = 4/5) and sliding
    forward (g = 0: 4/5 + N − (9/5) N = 0, N = 1, T = −2, s = 2 + 9/10 − 9/5 = 11/10 >=
    0). With μ = 1/10 only the first: in contact, sliding forward needs
    N = −(4/5)/(1 − 9/100) < 0, backward N = −(4/5)/(1 + 9/100) < 0, and sticking
    (W (N, T) = −(4/5, 2)) gives N = 12, T = −128/9, outside its cone μN = 6/5."""
    mech = [({0: Q(1), 2: Q(-1), 3: Q(-9, 10)}, Q(0)), ({1: Q(1), 3: Q(-3, 10)}, Q(0))]
    return ef.PrimalStep(4, mech, [2], [(Q(4, 5), {0: Q(1)})], [3],
                         [(Q(2), {0: Q(9, 10), 1: Q(3, 10)})], [Q(mu)], [0], [0, 1])


SEPARATE = np.array([0.0, 0.0, 0.0, 0.0])
SLIDING = np.array([1 - 1.8, -0.6, 1.0, -2.0])  # δ = G_n N + G_t T


def test_both_answers_of_a_two_answer_step_are_exact_and_classified_as_two():
    step = one_contact(Q(2))
    for v, rows, pairs in ((SEPARATE, [False], [ef.OFF]), (SLIDING, [True], [ef.FORWARD])):
        assert ef.read_states(step, v) == (rows, pairs)
        ex = ef.solve(step, rows, pairs, v)
        assert ex.solution and not ex.ray
        assert max(ef.distance(step, ex, v)) < 1e-15
    assert [float(x) for x in ef.solve(step, [True], [ef.FORWARD]).x] == [-0.8, -0.6, 1, -2]
    kind, info = ef.classify(step, SEPARATE, SLIDING)
    # ΔN = 1 against the largest force |T| = 2
    assert kind == ef.MULTIPLE and info["apart"][0] == pytest.approx(0.5)


def test_a_unique_answer_step_has_no_second_exact_answer_and_a_wrong_one_is_caught():
    step = one_contact(Q(1, 10))
    assert ef.solve(step, [False], [ef.OFF]).solution
    for pairs in ([ef.FORWARD], [ef.BACKWARD], [ef.STICK]):
        ex = ef.solve(step, [True], pairs)
        assert not ex.solution, pairs  # N < 0 when sliding, outside the cone sticking
    stick = ef.solve(step, [True], [ef.STICK])
    assert (stick.x[2], stick.x[3]) == (Q(12), Q(-128, 9))
    # an answer pressing on the wall by 1e-3 (separated in fact): not an answer
    wrong = np.array([1e-3, 0.0, 1e-3, 0.0])
    kind, info = ef.classify(step, SEPARATE, wrong)
    assert kind == ef.INACCURATE and info["which"] == "b"
    # two roundings of one answer: the same exact answer
    two = one_contact(Q(2))
    assert ef.classify(two, SLIDING, SLIDING * (1 + 1e-15))[0] == ef.SAME


def test_a_pull_at_mu_N_on_a_chain_nothing_holds_in_x_is_a_ray():
    """Unknowns (δy, δx, N, T): δy = N − 1 (pressed on the wall, g = δy), nothing holds
    δx (k = 0: −T = P = 1/2), μ = 1/2: in contact N = 1 and T = −μN = −P, sliding
    forward by any δx >= 0."""
    mech = [({0: Q(1), 2: Q(-1)}, Q(-1)), ({3: Q(-1)}, Q(1, 2))]
    step = ef.PrimalStep(4, mech, [2], [(Q(0), {0: Q(1)})], [3], [(Q(0), {1: Q(1)})],
                         [Q(1, 2)], [0], [0, 1])
    a, b = np.array([0.0, 0.0, 1.0, -0.5]), np.array([0.0, 1.0, 1.0, -0.5])
    ex = ef.solve(step, [True], [ef.FORWARD], b)
    assert ex.solution and ex.ray and ex.free == 1
    assert ef.classify(step, a, b)[0] == ef.RAY


def test_lemke_answer_of_a_chain_step_is_exact_on_its_index_set():
    """The primal equations rebuilt from the step's doubles (recurrences for D and Dᵀ,
    no Delassus matrix) confirm Lemke's answer, solved on W = GᵀK⁻¹G in floats."""
    import lcpbench
    from lcpbench import ActuatorScene
    from lcpbench.model.friction_solvers import step_runner

    steps = []
    run = step_runner("lemke")

    def keep(fs):
        sol = run(fs)
        steps.append((fs, sol))
        return sol

    keep.takes_step, keep.newton = True, True
    scene = ActuatorScene(theta=150.0, height=3.0, links=20, left_end="pinned",
                          right_end="slider", friction=0.3)
    res = lcpbench.solve_path(scene, [{}, {"pull": 0.05}], lcp=keep)
    assert all(r.converged for r in res)
    fs, sol = steps[-1]
    step = ef.chain_step(fs)
    v = ef.answer_values(fs, step, sol.z)
    ex, dist, _ = ef.nearest_exact(step, v)
    assert ex.solution and not ex.ray and ef.confirmed(ex, dist)
    assert sum(v[step.normal]) > 0  # it presses on the wall


def two_edge_contacts():
    """Two copies of one contact (unknowns δ1, δ2, N, T each; K = I, G_n = (1, 0),
    G_t = (9/10, 3/10), μ = 1/2), each built to sit at the edge of stick and slide:
    g = −11/20 + N + (9/10) T and s = −9/20 + ε + (9/10)(N + T), ε = 1e-9. Sliding
    forward (T = −N/2, g = 0): N = (11/20)/(1 − 9/20) = 1, T = −1/2, s = ε >= 0, the
    answer. Sticking (g = s = 0): N = 1 + 10ε, T = −1/2 − 100ε/9, outside its cone
    (|T| − μN = 50ε/9 > 0); sliding backward: N = 11/29, s = −9/20 + ε + (27/20)(11/29)
    > 0, the wrong way; separate: g = −11/20 < 0. So each contact's only answer slides
    forward, ε from sticking."""
    eps = Q(1, 10**9)
    mech, gap, slip, normal, tang = [], [], [], [], []
    for o in (0, 4):
        mech += [({o: Q(1), o + 2: Q(-1), o + 3: Q(-9, 10)}, Q(0)),
                 ({o + 1: Q(1), o + 3: Q(-3, 10)}, Q(0))]
        gap.append((Q(-11, 20), {o: Q(1)}))
        slip.append((Q(-9, 20) + eps, {o: Q(9, 10), o + 1: Q(3, 10)}))
        normal.append(o + 2)
        tang.append(o + 3)
    return ef.PrimalStep(8, mech, normal, gap, tang, slip, [Q(1, 2)] * 2, [0, 1],
                         [0, 1, 4, 5])


def test_the_edge_search_finds_the_exact_answer_on_a_neighbouring_index_set(monkeypatch):
    """An answer 1e-7 inside the cone at both contacts of :func:`two_edge_contacts` reads
    as sticking at both (its cone's margin 1e-7 above its slip 9.1e-8); that set's
    exact solution breaks both cones, and without flips the answer is not confirmed. The
    edge search, alone (no flips), tries every state of the two edge nodes and finds the
    set where both slide forward, whose exact solution is the one derived by hand."""
    step = two_edge_contacts()
    T = -0.5 + 1e-7
    one = [1.0 + 0.9 * T, 0.3 * T, 1.0, T]
    v = np.array(one + one)
    rows, pairs = ef.read_states(step, v)
    assert rows == [True, True] and pairs == [ef.STICK, ef.STICK]
    first = ef.solve(step, rows, pairs, v)
    assert sorted(first.failed) == [("pair", 0), ("pair", 1)]
    er, ep = ef.edge_nodes(step, v, rows, pairs, first.failed)
    assert er == [] and sorted(ep) == [0, 1]
    monkeypatch.setattr(ef, "FLIP_ROUNDS", 0)
    ex, dist, _ = ef.nearest_exact(step, v, search=False)
    assert not ef.confirmed(ex, dist)
    found, tried = ef.edge_search(step, v, rows, pairs, first.failed)
    assert found.pairs == [ef.FORWARD, ef.FORWARD] and found.solution
    assert 2 < tried <= 9  # the sets changing one node alone fail
    assert [found.x[k] for k in (2, 3, 6, 7)] == [Q(1), Q(-1, 2), Q(1), Q(-1, 2)]
    ex, dist, _ = ef.nearest_exact(step, v)
    assert ef.confirmed(ex, dist) and ex.pairs == [ef.FORWARD, ef.FORWARD]
    assert dist[1] == pytest.approx(1e-7 / (1.0), rel=1e-6)


def test_t_per_node_along_a_sticking_run_on_level_links_is_indeterminate():
    """Theory: two nodes pressed on a rigid wall and sticking are held in x and y; when
    the link between them is level, a horizontal force moved from one to the other
    changes that link's axial force only (no moment arm, no move): T per node along
    such a run is statically indeterminate, and only its sum is an answer. Across a
    stretch of chain off the wall it is not: there the links' slopes carry the axial
    force into the heights, and the exact step fixes each run's sum.

    A pulled chain (θ = 170°, h = 2.5 mm, N = 30, pin and slider, μ = 0.3) sticks on
    the wall at two runs, nodes 12–13 and 17–18, each on a link level to round-off,
    the stretch between sloped ~1e-5. The exact solution nearest Lemke's answer, and the
    one nearest the same answer with T moved between the nodes of either run (half the
    room their cones leave), are exact solutions of the step on one index set (every
    condition checked in fractions), the second taking the moved split exactly, with N
    and the move the same Fractions and each run's ΣT the same: two different splits,
    both exact. Moved from run to run, the exact solution nearest it keeps each run's
    ΣT: that split is not an answer (the step's near-null direction of state 41.2 of
    benchmarks/friction_agreement.py, docs/friction.md)."""
    from lcpbench import ActuatorScene

    scene = ActuatorScene(theta=170, height=2.5, links=30, left_end="pinned",
                          right_end="slider", friction=0.3)
    res, steps = recorded(scene, [{}, {"pull": 0.05}], tol=None)
    assert all(r.converged for r in res)
    fs, sol = steps[-1]
    step = ef.chain_step(fs)
    v = ef.answer_values(fs, step, sol.z)
    ex, dist, _ = ef.nearest_exact(step, v)
    assert ef.confirmed(ex, dist) and not ex.ray
    pair = {int(fs.friction_node[c]): c for c, p in enumerate(ex.pairs) if p == ef.STICK}
    runs = ((12, 13), (17, 18))
    assert sorted(pair) == [12, 13, 17, 18]
    assert all(fs.parts["tan"][i] == pytest.approx(0, abs=ef.LEVEL) for i, _ in runs)
    assert ex.free == len(runs)  # one free split per run, nothing else
    T = [step.tangential[pair[i]] for i in sorted(pair)]

    def limit(c):
        return sum(ex.x[step.normal[r]] * step.mu[r] for r in range(len(ex.rows))
                   if step.pair[r] == c)

    def moved(i, j):  # T moved from node j to node i, within both cones
        ci, cj = pair[i], pair[j]
        Ti, Tj = step.tangential[ci], step.tangential[cj]
        d = 0.5 * min(float(limit(ci)) - v[Ti], v[Tj] + float(limit(cj)))
        assert d > 1e-3 * step.force
        v2 = v.copy()
        v2[Ti] += d
        v2[Tj] -= d
        return d, ef.solve(step, ex.rows, ex.pairs, v2)

    def run_sums(x):
        return [x[T[0]] + x[T[1]], x[T[2]] + x[T[3]]]

    for i, j in runs:
        d, other = moved(i, j)
        assert other.solution and not other.ray
        assert all(other.x[k] == ex.x[k] for k in step.normal + step.moves)
        assert run_sums(other.x) == run_sums(ex.x)
        shift = float(other.x[step.tangential[pair[i]]] - ex.x[step.tangential[pair[i]]])
        assert shift == pytest.approx(d, rel=1e-9)  # the exact solution takes the split
    d, other = moved(12, 18)
    assert other.solution and run_sums(other.x) == run_sums(ex.x)
    shift = float(other.x[step.tangential[pair[12]]] - ex.x[step.tangential[pair[12]]])
    assert abs(shift - d) >= 0.4 * d  # the fit spreads d within each run: not this split


def _level_pair(mismatch):
    """Two nodes joined by a rigid level link (δx2 = δx1), held along x by a unit spring
    under a unit load (δx1 = 1 + T1 + T2), each pressed (g = −1 + N: N = 1) with μ = 1,
    ℓ = 30 mm. Both sticking: s1 + δx1 = 0 and s2 + δx2 = 0 are one equation when
    s2 = s1 (T1 + T2 = −1 − s1, split free); s2 = s1 + ``mismatch`` leaves the second
    a dependent equation off by ``mismatch`` mm. s1 = −2.13e-14 mm: a slip that is
    round-off of the positions (state 37.2 of friction_agreement.py has this one)."""
    s1 = -2.1316282072803006e-14
    mech = [({1: Q(1), 0: Q(-1)}, Q(0)), ({0: Q(1), 4: Q(-1), 5: Q(-1)}, Q(1))]
    return ef.PrimalStep(6, mech, [2, 3], [(Q(-1), {2: Q(1)}), (Q(-1), {3: Q(1)})],
                         [4, 5], [(Q(s1), {0: Q(1)}), (Q(s1 + mismatch), {1: Q(1)})],
                         [Q(1), Q(1)], [0, 1], [0, 1], 1.0, 30.0, 0.75)


def test_a_dependent_slip_met_to_the_positions_round_off_is_consistent():
    """A dependent slip equation whose terms are themselves round-off (2e-14 mm) and
    which the data meet to 1.8e-15 mm — 4 % of its terms, far beyond CONSISTENT_RTOL —
    is consistent: the positions it is differenced from carry ~ε ℓ = 7e-15 mm. Off by
    1e-11 mm (a real mismatch: one of the two must slide) it is not."""
    ok = ef.solve(_level_pair(1.8e-15), [True, True], [ef.STICK, ef.STICK])
    assert ok.inconsistency > 1e-3 and ok.solution and ok.free == 1 and not ok.ray
    assert ok.x[4] + ok.x[5] == -1 - Q(-2.1316282072803006e-14)
    off = ef.solve(_level_pair(1e-11), [True, True], [ef.STICK, ef.STICK])
    assert [kind for kind, _ in off.failed] == ["slip"]


def test_a_dependent_force_equation_gets_no_position_round_off():
    """The round-off floor is for equations in mm (a contact row's gap, a sticking pair's
    slip), never for a force equation: a pressed node sliding forward (T + μN = 0, μ = 1)
    whose mechanics fix N = 1e-3 N and T = -1e-3 N - δ leaves that slide equation off by
    δ; at δ = 5e-14 N (2.5e-11 of its terms, below 16 ε ℓ in mm at ℓ = 30 mm) the set
    has no exact solution."""
    for delta in (5e-14, 1e-13):
        mech = [({0: Q(1)}, Q(0.001)), ({1: Q(1)}, Q(-0.001) - Q(delta))]
        step = ef.PrimalStep(3, mech, [0], [(Q(-1), {2: Q(1)})], [1], [(Q(0), {2: Q(0)})],
                             [Q(1)], [0], [2], 1.0, 30.0, 0.75)
        ex = ef.solve(step, [True], [ef.FORWARD])
        assert ex.x[1] + ex.x[0] == -Q(delta)  # the slide equation's own residual
        assert not ex.solution and len(ex.failed) == 1
