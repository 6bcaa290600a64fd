"""The scores of the report (issue 37, item 3): success rate and shifted geometric means
over every scene, failures charged. Expected values are worked out by hand below."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lcpbench.bench.metrics import (
    ITERATION_SHIFT,
    OUTER_LIMIT,
    TIME_SHIFT_MS,
    Evaluated,
    charged_sgm,
    silent_inner,
    summarise,
)
from lcpbench.errors import ProblemError


def test_the_documented_constants():
    # the report states these; the tests below use them as numbers
    assert TIME_SHIFT_MS == 1.0 and ITERATION_SHIFT == 1.0 and OUTER_LIMIT == 200


def test_charged_sgm_by_hand():
    # two successes, shift 1: sqrt((1 + 1)(3 + 1)) - 1 = sqrt(8) - 1
    assert charged_sgm([1.0, 3.0], [True, True], 100.0, 1.0) == pytest.approx(math.sqrt(8) - 1)
    # the second failed: it counts at the charge 100, sqrt(2 * 101) - 1
    assert charged_sgm([1.0, 3.0], [True, False], 100.0, 1.0) == pytest.approx(
        math.sqrt(202) - 1)
    # a failure that ran longer than the charge counts at its own value
    assert charged_sgm([1.0, 300.0], [True, False], 100.0, 1.0) == pytest.approx(
        math.sqrt(2 * 301) - 1)
    # a failure without a measurement (NaN) counts at the charge
    assert charged_sgm([1.0, math.nan], [True, False], 100.0, 1.0) == pytest.approx(
        math.sqrt(202) - 1)
    # shift 0 is the plain geometric mean: (4 * 9)^(1/2) = 6; three values: (1*8*27)^(1/3) = 6
    assert charged_sgm([4.0, 9.0], [True, True], 1.0, 0.0) == pytest.approx(6.0)
    assert charged_sgm([1.0, 8.0, 27.0], [True] * 3, 1.0, 0.0) == pytest.approx(6.0)
    # every run failed: the charge itself
    assert charged_sgm([0.5, 2.0], [False, False], 60.0, 1.0) == pytest.approx(60.0)
    # a mean lies between the smallest and the largest value, round-off of the shift's
    # subtraction included (found by the property below: -4e-16 for zeros)
    assert charged_sgm([0.0, 0.0, 0.0], [True] * 3, 60.0, 1e-13) == 0.0
    assert charged_sgm([2e-293], [True], 60.0, 3.34) == 2e-293
    assert math.isnan(charged_sgm([], [], 60.0, 1.0))


def test_charged_sgm_refuses_bad_input_with_one_clear_error():
    with pytest.raises(ProblemError, match="one 'solved' flag per value"):
        charged_sgm([1.0, 2.0], [True], 10.0, 1.0)
    with pytest.raises(ProblemError, match="finite charge and shift"):
        charged_sgm([1.0], [True], math.inf, 1.0)
    with pytest.raises(ProblemError, match="finite charge and shift"):
        charged_sgm([1.0], [True], 10.0, -1.0)
    with pytest.raises(ProblemError, match="successful run needs a finite value"):
        charged_sgm([-1.0], [True], 10.0, 1.0)
    with pytest.raises(ProblemError, match="successful run needs a finite value"):
        charged_sgm([math.nan], [True], 10.0, 1.0)


_value = st.floats(0.0, 50.0, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(_value, st.booleans()), min_size=1, max_size=12),
       st.integers(0, 11), st.floats(0.0, 5.0))
def test_charging_a_failure_never_lowers_the_score(runs, k, shift):
    values = [v for v, _ in runs]
    solved = [ok for _, ok in runs]
    k %= len(runs)
    as_success = charged_sgm(values, [*solved[:k], True, *solved[k + 1:]], 60.0, shift)
    as_failure = charged_sgm(values, [*solved[:k], False, *solved[k + 1:]], 60.0, shift)
    assert as_failure >= as_success * (1 - 1e-12)
    # and a larger charge never lowers it either
    assert charged_sgm(values, solved, 120.0, shift) >= charged_sgm(values, solved, 60.0,
                                                                    shift) * (1 - 1e-12)


@settings(max_examples=200, deadline=None)
@given(st.lists(_value, min_size=1, max_size=12), st.integers(1, 5), st.floats(0.0, 5.0))
def test_failures_lift_the_score_above_the_successes_alone(values, failures, shift):
    """Charged at least at every success's value, failures can only raise the mean
    of the successes, and the score stays between the smallest value and the charge."""
    alone = charged_sgm(values, [True] * len(values), 60.0, shift)
    with_f = charged_sgm(values + [1.0] * failures, [True] * len(values) + [False] * failures,
                         60.0, shift)
    assert with_f >= alone * (1 - 1e-12)
    assert min(values) * (1 - 1e-12) <= with_f <= 60.0 * (1 + 1e-12)


def _ev(backend, scene, success, ms, outer=3, inner=5, ref=1.0, settings="default"):
    row = {"backend": backend, "settings": settings, "method": "globalised", "scene": scene,
           "tol": 1e-3, "converged": success, "wall_time": ms / 1e3,
           "outer_iterations": outer, "inner_iterations": inner}
    return Evaluated(row, 0.0 if success else math.inf, success, ref)


def test_summary_scores_by_hand():
    ev = [
        _ev("steady", "s1", True, 1.0, outer=3), _ev("steady", "s2", True, 3.0, outer=5),
        _ev("flaky", "s1", True, 1.0, outer=3), _ev("flaky", "s2", False, 0.2, outer=7),
    ]
    by = {r["backend"]: r for r in summarise(ev, time_limit=60.0)}
    s, f = by["steady"], by["flaky"]
    assert s["success"] == 1.0 and f["success"] == 0.5
    # time, shift 1 ms: sqrt(2 * 4) - 1; the failure at the limit, 60 000 ms
    assert s["time_sgm_ms"] == pytest.approx(math.sqrt(8) - 1)
    assert f["time_sgm_ms"] == pytest.approx(math.sqrt(2 * 60001) - 1)
    # outer iterations, shift 1: sqrt(4 * 6) - 1; the failure at the limit 200
    assert s["outer_sgm"] == pytest.approx(math.sqrt(24) - 1)
    assert f["outer_sgm"] == pytest.approx(math.sqrt(4 * 201) - 1)
    assert s["time_sgm_rel"] == pytest.approx(1.0)
    assert f["time_sgm_rel"] == pytest.approx((math.sqrt(2 * 60001) - 1) / (math.sqrt(8) - 1))
    assert s["outer_sgm_rel"] == pytest.approx(1.0)
    # the success-only median is still there, named for what it is
    assert s["time_median_successes_ms"] == pytest.approx(2.0)
    assert f["time_median_successes_ms"] == pytest.approx(1.0)  # the old, flattering figure


def test_a_fast_failing_back_end_no_longer_looks_faster():
    """Issue 37's complaint: over successes only, a back-end that solves just the easy
    scenes looked faster than one that solves them all."""
    ev = [_ev("all", f"s{i}", True, 5.0) for i in range(10)]
    ev += [_ev("easy-only", f"s{i}", i < 4, 0.1) for i in range(10)]
    by = {r["backend"]: r for r in summarise(ev, time_limit=60.0)}
    assert by["easy-only"]["time_median_successes_ms"] < by["all"]["time_median_successes_ms"]
    assert by["easy-only"]["time_sgm_ms"] > by["all"]["time_sgm_ms"]
    # by hand: exp(0.4 ln 1.1 + 0.6 ln 60001) - 1 against 5
    assert by["easy-only"]["time_sgm_ms"] == pytest.approx(
        math.exp(0.4 * math.log(1.1) + 0.6 * math.log(60001.0)) - 1)
    assert by["all"]["time_sgm_ms"] == pytest.approx(5.0)


def test_summarise_refuses_a_bad_time_limit():
    with pytest.raises(ProblemError, match="time_limit"):
        summarise([_ev("a", "s1", True, 1.0)], time_limit=0.0)


def test_back_ends_that_report_no_inner_count():
    ev = [
        # counts its work on the contact scene
        _ev("counts", "free", True, 1.0, inner=0, ref=0.0),
        _ev("counts", "wall", True, 1.0, inner=12, ref=0.4),
        # 0 everywhere, a contact scene included: reports nothing
        _ev("silent", "free", True, 1.0, inner=0, ref=0.0),
        _ev("silent", "wall", True, 1.0, inner=0, ref=0.4),
        # 0 on no-contact scenes only: nothing to tell, so not judged silent
        _ev("free-only", "free", True, 1.0, inner=0, ref=0.0),
    ]
    assert silent_inner(ev) == {"silent"}
    by = {r["backend"]: r for r in summarise(ev, time_limit=60.0)}
    assert by["silent"]["inner_reported"] is False and math.isnan(by["silent"]["inner_mean"])
    assert by["counts"]["inner_reported"] is True and by["counts"]["inner_mean"] == 6.0
