"""The continuation predictor over the plane of θ and h (studies.continuation.Solved).

Hand-made answers (a real result with its angles and reactions replaced) show
which neighbours the predictor uses; a small grid shows that warm answers are
the cold ones to 1e-8, whatever the predictor chose.
"""

import random
from dataclasses import replace

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.numba_cache import kernel_module
from lcpbench.studies.continuation import Solved, largest_difference, new_solved, predict

N = 30


@pytest.fixture(scope="module")
def base():
    return lcpbench.solve(ActuatorScene(theta=150.0, height=3.0, links=N))


def fake(base, theta, height, alpha, touching):
    """(scene, result): ``alpha`` as the answer at (θ, h), pressing on the wall or not."""
    forces = np.zeros_like(base.forces)
    if touching:
        forces[len(forces) // 2] = 0.01
    scene = ActuatorScene(theta=theta, height=height, links=N)
    return scene, replace(base, scene=scene, alpha=np.asarray(alpha, float), forces=forces,
                          forces_lower=None, converged=True)


def field(theta, height, n=N):
    """Smooth made-up link angles: quadratic in θ, bilinear in θ and h."""
    k = np.arange(n) / n
    t = theta / 100
    return 0.3 + 0.2 * k + 0.05 * t**2 * (1 + k) + 0.01 * height + 0.02 * t * height * k


def solved_from(pairs, predictor="quadratic"):
    s = new_solved(predictor)
    for scene, res in pairs:
        s.add(scene, res)
    return s


def test_a_neighbour_that_touches_no_wall_is_taken_as_it_is(base):
    """No wall enters the equilibrium of a chain that touches none: the answer at the same
    θ on another line is this scene's answer if it touches nothing either."""
    free = field(60, 2.0) + 0.123  # not what any polynomial in θ would give
    pairs = [fake(base, t, 3.0, field(t, 3.0), False) for t in (30, 40, 50)]
    pairs.append(fake(base, 60, 2.0, free, False))
    alpha, _ = solved_from(pairs).predict(ActuatorScene(theta=60, height=3.0, links=N))
    assert np.array_equal(alpha, free)
    # a line that already touches is extrapolated along θ instead (the free shape is not it)
    touching = [fake(base, t, 3.0, field(t, 3.0), True) for t in (30, 40, 50)]
    alpha, _ = solved_from(touching + pairs[3:]).predict(ActuatorScene(theta=60, height=3.0,
                                                                       links=N))
    assert np.allclose(alpha, field(60, 3.0), atol=1e-12)  # quadratic in θ: exact


def test_just_after_the_line_touches_the_neighbouring_lines_difference_is_extrapolated(base):
    """Two answers on the line touch (the third does not): the start is the other line's
    answer at θ plus the secant in θ of the difference between the lines, which is exact
    for angles whose difference between lines is linear in θ (the field is quadratic
    in θ, so the line's own secant is not)."""
    pairs = [fake(base, 90, 3.0, field(90, 3.0), False)]
    pairs += [fake(base, t, 3.0, field(t, 3.0), True) for t in (100, 110)]
    pairs += [fake(base, t, 2.0, field(t, 2.0), True) for t in (90, 100, 110, 120)]
    target = ActuatorScene(theta=120, height=3.0, links=N)
    alpha, warm_from = solved_from(pairs).predict(target)
    assert np.allclose(alpha, field(120, 3.0), atol=1e-12)
    assert warm_from.scene.theta == 110 and warm_from.scene.height == 3.0  # nearest on the line
    secant = 2 * field(110, 3.0) - field(100, 3.0)
    assert not np.allclose(secant, field(120, 3.0), atol=1e-6)


def test_no_polynomial_through_a_change_of_contact(base):
    """The line's nearest answer touches, the ones before it do not: the start is the
    nearest answer alone (no neighbouring line to help)."""
    pairs = [fake(base, t, 3.0, field(t, 3.0) + (0.5 if t < 110 else 0.0), t >= 110)
             for t in (80, 90, 100, 110)]
    alpha, _ = solved_from(pairs).predict(ActuatorScene(theta=120, height=3.0, links=N))
    assert np.array_equal(alpha, field(110, 3.0))


def test_the_nearest_answers_whatever_the_order_they_were_solved_in(base):
    """A line solved downwards in θ (and with a far answer first): the start comes from the
    nearest three answers, a parabola through them, exact for a quadratic field."""
    thetas = [170, 100, 160, 150, 140]
    pairs = [fake(base, t, 3.0, field(t, 3.0), True) for t in thetas]
    alpha, warm_from = solved_from(pairs).predict(ActuatorScene(theta=130, height=3.0,
                                                                links=N))
    assert warm_from.scene.theta == 140
    assert np.allclose(alpha, field(130, 3.0), atol=1e-12)
    # the history form answers the same
    guess = predict(pairs, ActuatorScene(theta=130, height=3.0, links=N), "quadratic")
    assert np.array_equal(guess.alpha, alpha)


def test_another_plane_is_no_neighbour(base):
    pairs = [fake(base, t, 3.0, field(t, 3.0), True) for t in (100, 110, 120)]
    s = solved_from(pairs)
    assert s.predict(ActuatorScene(theta=130, height=3.0, links=N, weight=0.001)) is None
    assert s.predict(ActuatorScene(theta=130, height=3.0, links=N + 1)) is None
    assert Solved(0).predict(pairs[0][0]) is None  # "none": every scene cold


def test_extrapolations_and_the_adaptive_degree():
    """Row j is the polynomial through j + 1 points (exact for degree ≤ j); the adaptive
    choice returns the extrapolation after the smallest change between degrees."""
    rng = np.random.default_rng(3)
    c = rng.standard_normal((3, 4))
    f = lambda t: c[0] + c[1] * (t / 100) + c[2] * (t / 100) ** 2  # noqa: E731
    ts = [150.0, 140.0, 125.0, 110.0, 90.0, 85.0]  # unequal steps
    k = kernel_module("lcpbench.model.predictor_kernel")
    m = len(ts)

    def extrapolations(t, values):
        return k.extrapolations(t, np.array(ts), np.array(values), m)

    rows = extrapolations(160.0, [f(t) for t in ts])
    assert np.array_equal(rows[0], f(150.0))
    assert np.allclose(rows[2:], f(160.0), rtol=0, atol=1e-12)
    assert not np.allclose(rows[1], f(160.0), atol=1e-6)
    assert np.allclose(k.best_degree(rows, m), f(160.0), atol=1e-12)
    # the farther answers off the parabola (a change of regime, or their own truncation):
    # the degrees that use them change the extrapolation more than the parabola's own
    # correction does, so the choice stops at the parabola
    off = [f(t) + (1.0 if i >= 3 else 0.0) for i, t in enumerate(ts)]
    assert np.allclose(k.best_degree(extrapolations(160.0, off), m), f(160.0), atol=1e-12)


def plane():
    """θ 20…180 by 20 at h 2, 3, 4 (N = 30): no contact at small θ, the line's first
    contact at a θ growing with h, contact after it."""
    scenes = [ActuatorScene(theta=float(t), height=h, links=N) for h in (2.0, 3.0, 4.0)
              for t in range(20, 181, 20)]
    random.Random(4).shuffle(scenes)
    return scenes


@pytest.mark.parametrize("method", ["globalised", "newton"])
def test_warm_answers_are_the_cold_ones_on_a_small_grid(method):
    scenes = plane()
    cold = [lcpbench.solve(s, tol=1e-10, method=method) for s in scenes]
    warm = lcpbench.solve_many(scenes, tol=1e-10, method=method)
    assert [r.scene for r in warm] == scenes  # the caller's order
    assert all(r.converged for r in cold + warm)
    assert largest_difference(cold, warm) <= 1e-8
    for c, w in zip(cold, warm):
        assert np.abs(c.alpha - w.alpha).max() < 1e-8  # rad
        assert_solved(w)  # the equilibrium (tests/energy_oracle.py)
    labels = {r.extra["continuation"] for r in warm}
    assert labels <= {"cold", "adaptive"} and "adaptive" in labels
    # both kinds of scene occur: some touch a wall and some do not
    assert any(r.total_force > 0 for r in warm) and any(r.total_force == 0 for r in warm)


def test_planes_whose_fields_do_not_hash_are_found_by_equality(base, monkeypatch):
    import lcpbench.studies.continuation as cont

    pairs = [fake(base, t, 3.0, field(t, 3.0), True) for t in (100, 110, 120)]
    target = ActuatorScene(theta=130, height=3.0, links=N)
    hashed, _ = solved_from(pairs).predict(target)
    monkeypatch.setattr(cont, "_hashable", lambda key: False)
    s = solved_from(pairs)
    alpha, _ = s.predict(target)
    assert np.array_equal(alpha, hashed)
    assert s.predict(ActuatorScene(theta=130, height=3.0, links=N + 1)) is None
