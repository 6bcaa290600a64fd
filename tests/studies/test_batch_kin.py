"""Scattered scenes of one kin in solve_many: a scene that no answer of its own plane
predicts (no answer on its line in θ or at its θ) starts from the nearest answer of
its kin (the same scene but for θ, h and the walls' stiffness; studies.batch._kin,
rule 5 of the predictor, model.predictor_kernel.predict_start); each scene is
solved on its own walls, a failed warm start is redone cold, and a channel bent past
180° (several stable states) starts cold.

Oracles: the exact energy's stationarity with the scene's own Winkler springs
(tests/energy_oracle.py ``assert_solved``), the direct minimisation of the energy on
rigid walls (``energy_minimum``), enumeration of the nearest answer.
"""

import random

import numpy as np
import pytest
from energy_oracle import assert_solved, energy_minimum, force_unit

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.studies.batch import KIN_THETA_MAX
from lcpbench.studies.batch_result import LineResult


def _label(res) -> str:
    return res.extra["continuation"]


def test_scattered_elastic_walls_start_from_their_kin_each_on_its_own_walls():
    """Scattered θ, h and k (1e-2 to 1e4 N/mm², where the oracle's differences of the
    springs' energy are accurate; and rigid walls, a kin of their own kernel
    call): every scene but the first of each call starts warm, and every answer is the
    equilibrium of its own walls: stationary with its own springs, or on rigid walls the
    force of the direct minimisation."""
    rng = random.Random(11)
    soft = [ActuatorScene(theta=rng.uniform(100, 175), height=rng.uniform(2, 4), links=40,
                          wall_stiffness=10 ** rng.uniform(-2, 4)) for _ in range(10)]
    rigid = [ActuatorScene(theta=rng.uniform(100, 175), height=rng.uniform(2, 4), links=40)
             for _ in range(4)]
    scenes = soft + rigid
    rng.shuffle(scenes)
    got = lcpbench.solve_many(scenes, tol=1e-8)
    for group in (soft, rigid):
        rs = [r for r in got if r.scene in group]
        assert all(isinstance(r, LineResult) and r.converged for r in rs)
        assert [_label(r) for r in rs].count("cold") == 1
    for r in got:
        assert_solved(r)
        if r.scene in rigid:
            ref = energy_minimum(r.scene)
            assert abs(r.total_force - ref.total_force) <= 1e-6 * force_unit(
                r.scene, ref.total_force)


def test_scattered_channel_scenes_start_warm_up_to_180_degrees_and_cold_past_it():
    """A channel at scattered (θ, h): the scenes up to KIN_THETA_MAX start from their
    nearest answer and give the direct minimisation's forces on both walls; those past
    it (a folded chain in a channel may have several stable states) start cold."""
    rng = random.Random(3)
    low = [ActuatorScene(theta=rng.uniform(90, 175), height=rng.uniform(0.8, 3), links=40,
                         channel=True) for _ in range(8)]
    past = [ActuatorScene(theta=200.0, height=1.2, links=40, channel=True)]
    assert all(s.theta > KIN_THETA_MAX for s in past)
    got = lcpbench.solve_many(low + past, tol=1e-8)
    assert all(isinstance(r, LineResult) and r.converged for r in got)
    assert [_label(r) for r in got[:8]].count("cold") == 1
    for r in got[8:]:
        assert _label(r) == "cold"
        assert_solved(r)
    for r in got[:8]:
        ref = energy_minimum(r.scene)
        F0 = force_unit(r.scene, ref.total_force)
        assert abs(r.total_force - ref.total_force) <= 1e-6 * F0
        assert abs(np.sum(r.forces_lower) - np.sum(ref.forces_lower)) <= 1e-6 * F0


def test_a_failed_warm_start_from_the_kin_is_redone_cold():
    """A scene started from a far kin (θ 120° → 175°, k 1e3 → 1e-2 N/mm²) with too few outer
    iterations for the warm start (max_outer 5): the warm attempt is discarded and the
    scene solved again cold; with room to converge, the scene's answer is its
    equilibrium (the exact energy's oracle).

    Route against route: the kept answer is the scene's alone (a batch of one, cold by
    construction), kept because the promise is exactly that answer: a failed warm start
    leaves no trace in it; unconverged at max_outer 5, it has no equilibrium to check."""
    near = ActuatorScene(theta=120.0, height=2.5, links=40, wall_stiffness=1e3)
    far = ActuatorScene(theta=175.0, height=4.0, links=40, wall_stiffness=1e-2)
    got = lcpbench.solve_many([near, far], tol=1e-6, max_outer=5)
    assert got[0].converged
    assert _label(got[1]) == "adaptive, failed; cold"
    assert got[1].extra["discarded"]["outer_iterations"] == 5
    alone = lcpbench.solve_many([far], tol=1e-6, max_outer=5)[0]
    assert _label(alone) == "cold"
    assert (got[1].converged, got[1].outer_iterations, got[1].reason) == (
        alone.converged, alone.outer_iterations, alone.reason)
    np.testing.assert_array_equal(got[1].forces, alone.forces)
    for r in lcpbench.solve_many([near, far], tol=1e-6):
        assert_solved(r)


@pytest.mark.parametrize("seed", range(4))
def test_the_kernels_rule_5_takes_the_nearest_answer_of_the_kin(seed):
    """Random histories on four planes in two kins (and scenes of no kin): where the
    scene's own plane predicts nothing (Solved's rules 1-4 find no answer on its line or
    at its θ), the kernel starts it from the accepted answer of its kin before it
    nearest in ``where`` (found here by enumeration; the first of equals), as it is;
    with no kin, or none solved, cold. Where its plane predicts, the kernel's start is
    Solved's: the planes interleaved in one call are kept apart as Solved's dict of
    planes keeps them (route against route for that part: both run predict_start, and
    what is compared is the separation of the planes, not the prediction)."""
    from lcpbench.numba_cache import kernel_module
    from lcpbench.studies.continuation import POINTS, Solved

    k = kernel_module("lcpbench.model.predictor_kernel")
    rng = random.Random(seed)
    m, links = 40, 5
    stiffness = [np.inf, 50.0, 5.0, 0.5]
    plane = np.array([rng.randrange(4) for _ in range(m)], np.int64)
    kin = np.array([-1 if rng.random() < 0.1 else int(p >= 2) for p in plane], np.int64)
    scenes = [ActuatorScene(theta=rng.choice([100.0, 120.0, rng.uniform(90, 180)]),
                            height=rng.choice([2.0, 3.0, rng.uniform(2, 5)]), links=links,
                            wall_stiffness=stiffness[p]) for p in plane]
    where = np.array([[rng.random(), rng.random(), rng.random()] for _ in range(m)])
    ok = np.array([rng.random() < 0.8 for _ in range(m)])
    touch = np.array([rng.random() < 0.6 for _ in range(m)])
    alphas = np.array([rng.random() * np.arange(links) for _ in range(m)])
    theta = np.array([s.theta for s in scenes])
    height = np.array([s.height for s in scenes])
    solved = Solved(POINTS["adaptive"], True)
    fakes = [_fake(bool(o), bool(t), a) for o, t, a in zip(ok, touch, alphas)]
    fired = 0
    for s in range(m):
        start, base = k.predict_start(s, theta, height, plane, kin, where, ok, touch, alphas,
                                      POINTS["adaptive"], True)
        own = solved.predict(scenes[s])
        if own is not None:  # rules 1-4, from the scene's own plane alone, as Solved keeps it
            assert fakes[base] is own[1] and np.array_equal(start, own[0])
        else:
            cand = [i for i in range(s) if ok[i] and kin[s] >= 0 and kin[i] == kin[s]]
            if not cand:
                assert base == -1 and start.size == 0
            else:
                d = [float(np.sum((where[i] - where[s]) ** 2)) for i in cand]
                want = cand[int(np.argmin(d))]
                assert base == want
                np.testing.assert_array_equal(start, alphas[want])
                fired += 1
        solved.add(scenes[s], fakes[s])
    assert fired


def _fake(converged, touches, alpha):
    from types import SimpleNamespace

    return SimpleNamespace(converged=converged, alpha=alpha, forces_lower=None,
                           forces=np.array([1.0 if touches else 0.0]))
