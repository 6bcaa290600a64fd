"""Continuation: a neighbour's answer as the start gives the same equilibrium, in fewer steps."""

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench.errors import ProblemError
from lcpbench.studies.continuation import (
    largest_difference,
    predict,
    solve_sequence,
    total_outer,
)

LINE = [lcpbench.ActuatorScene(theta=t, height=3.0, links=40) for t in range(100, 181, 10)]


@pytest.fixture(scope="module")
def tight():
    kw = {"solver": "active-set", "tol": 1e-10}
    return {p: solve_sequence(LINE, predictor=p, **kw) for p in ("none", "previous", "secant", "quadratic")}


def test_same_equilibrium_to_1e_8(tight):
    cold = tight["none"]
    assert all(r.converged for rs in tight.values() for r in rs)
    for p in ("previous", "secant", "quadratic"):
        assert largest_difference(cold, tight[p]) < 1e-8
        for a, b in zip(cold, tight[p]):
            assert abs(a.alpha - b.alpha).max() < 1e-8  # rad
    for r in tight["quadratic"]:  # and each the equilibrium (tests/energy_oracle.py)
        assert_solved(r)


def test_every_scene_but_the_first_is_warm(tight):
    # how many steps this saves is a measurement (benchmarks/warm_sweep.py), not a test
    labels = [r.extra["continuation"] for r in tight["secant"]]
    assert labels[0] == "cold" and set(labels[1:]) == {"secant"}


def test_predict_starts_cold_across_a_change_of_kind(tight):
    history = [(LINE[0], tight["none"][0]), (LINE[1], tight["none"][1])]
    assert predict(history, LINE[2].with_links(41)) is None  # another N
    assert predict(history, lcpbench.ActuatorScene(theta=120, height=4.0, links=40)) is None
    guess = predict(history, LINE[2])
    # secant: alpha_1 + (alpha_1 - alpha_0) at equal steps in theta
    expected = 2 * tight["none"][1].alpha - tight["none"][0].alpha
    assert abs(guess.alpha - expected).max() == 0.0


def test_bad_starts_are_refused():
    res = lcpbench.solve(LINE[0])
    with pytest.raises(ProblemError, match="same links"):
        lcpbench.solve(LINE[1].with_links(50), start=res)
    with pytest.raises(ProblemError, match="globalised"):
        lcpbench.solve(LINE[1], start=res, method="undamped")
    with pytest.raises(ProblemError, match="ContactResult"):
        lcpbench.solve(LINE[1], start=res.alpha)
    with pytest.raises(ProblemError, match="predictor"):
        solve_sequence(LINE, predictor="magic")


def test_quadratic_predictor_reproduces_a_parabola_exactly(tight):
    """Lagrange extrapolation through three answers at unequal steps in θ is exact for
    angles that are quadratic in θ (and the secant for linear ones)."""
    from dataclasses import replace

    base = tight["none"][0]
    rng = np.random.default_rng(0)
    a, b, c = (rng.standard_normal(base.alpha.size) for _ in range(3))
    thetas = [100.0, 110.0, 130.0]  # unequal steps
    history = [(lcpbench.ActuatorScene(theta=t, height=3.0, links=40),
                replace(base, alpha=a + b * t + c * t**2)) for t in thetas]
    target = lcpbench.ActuatorScene(theta=145.0, height=3.0, links=40)
    guess = predict(history, target, "quadratic")
    exact = a + b * 145.0 + c * 145.0**2
    assert np.allclose(guess.alpha, exact, rtol=1e-10, atol=1e-10 * np.abs(c).max() * 145**2)
    lin = [(s, replace(r, alpha=a + b * s.theta)) for s, r in history]
    assert np.allclose(predict(lin, target, "secant").alpha, a + b * 145.0, rtol=1e-12)
    # a break in the line (another height) leaves only the answers after it
    broken = [(lcpbench.ActuatorScene(theta=100.0, height=4.0, links=40), history[0][1])]
    broken += history[1:]
    two = predict(broken, target, "quadratic")
    expected = history[2][1].alpha + (history[2][1].alpha - history[1][1].alpha) * (15 / 20)
    assert np.allclose(two.alpha, expected, rtol=1e-12)


def test_a_failed_warm_start_is_redone_cold_and_its_cost_counted(monkeypatch):
    """Route against route: a warm start made to fail is redone as the cold solve, the
    same computation, so the same answer bit for bit is promised (the cold answers are
    checked against the equilibrium in test_same_equilibrium_to_1e_8)."""
    import lcpbench.studies.continuation as cont

    real = cont.solve_internal

    def warm_fails(scene, start=None, **kw):
        res = real(scene, start=start, **kw)
        if start is not None:
            res.converged, res.reason = False, "made to fail"
        return res

    monkeypatch.setattr(cont, "solve_internal", warm_fails)
    line = LINE[:3]
    out = solve_sequence(line, predictor="secant", solver="active-set", tol=1e-8)
    cold = [lcpbench.solve(s, solver="active-set", tol=1e-8) for s in line]
    assert all(r.converged for r in out)
    assert [r.extra["continuation"] for r in out] == ["cold"] + ["secant, failed; cold"] * 2
    # the answers are the cold ones; the totals include the failed attempts
    assert all(abs(a.total_force - b.total_force) == 0 for a, b in zip(out, cold))
    lost = sum(r.extra["discarded"]["outer_iterations"] for r in out[1:])
    assert lost >= 2
    assert total_outer(out) == sum(r.outer_iterations for r in cold) + lost


def test_newton_continuation_gives_the_energy_minimum_of_each_scene():
    """method="newton" continues too (its first warm step is a Newton step): each answer
    is the independent energy minimisation's, and the cold Newton answer's, to 1e-8."""
    from lcpbench.reference.energy import minimise_energy

    kw = {"solver": "active-set", "tol": 1e-10, "method": "newton"}
    warm = solve_sequence(LINE[3:7], predictor="quadratic", **kw)
    cold = solve_sequence(LINE[3:7], predictor="none", **kw)
    assert all(r.converged for r in warm + cold)
    assert largest_difference(cold, warm) < 1e-8
    for scene, r in zip(LINE[3:7], warm):
        ref = minimise_energy(scene.chain())
        F0 = max(abs(ref.total_force), scene.EI / scene.length**2)
        assert abs(r.total_force - ref.total_force) / F0 < 1e-8


def test_undamped_continuation_is_refused():
    with pytest.raises(ProblemError, match="globalised' or 'newton"):
        solve_sequence(LINE[:2], method="undamped")
