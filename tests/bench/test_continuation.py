"""Continuation: a neighbour's answer as the start gives the same equilibrium, in fewer steps."""

import pytest

import lcpbench
from lcpbench.bench.continuation import (
    largest_difference,
    predict,
    solve_sequence,
)
from lcpbench.errors import ProblemError

LINE = [lcpbench.ActuatorScene(theta=t, height=3.0, links=40) for t in range(100, 181, 10)]


@pytest.fixture(scope="module")
def tight():
    kw = {"solver": "active-set", "tol": 1e-10}
    return {p: solve_sequence(LINE, predictor=p, **kw) for p in ("none", "previous", "secant")}


def test_same_equilibrium_to_1e_8(tight):
    cold = tight["none"]
    assert all(r.converged for rs in tight.values() for r in rs)
    for p in ("previous", "secant"):
        assert largest_difference(cold, tight[p]) < 1e-8
        for a, b in zip(cold, tight[p]):
            assert abs(a.alpha - b.alpha).max() < 1e-8  # rad


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
