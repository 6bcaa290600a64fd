"""A run out of outer iterations says when max|Δα| had stalled, and what tol the
iteration can reach (lcpbench.model.driver.stall, out_of_iterations).

The synthetic sequences are built to the definition (a contraction that halves the
best max|Δα| within STALL_STEPS steps is not a stall; a plateau is). The end-to-end
case asks for tol = 1e-14 rad at N = 1000, below the accuracy the contact steps are
computed to there, and checks the hint by its consequence: asked for the suggested
tol, the same (deterministic) iteration stops at the step the reason names.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.model.driver import (
    STALL_STEPS,
    STEP_ACCURACY_DALPHA,
    StepRecord,
    out_of_iterations,
    stall,
)


def records(dalphas) -> list[StepRecord]:
    return [StepRecord(1, "solved", 0.0, 0.0, 1.0, float(d), 0.0) for d in dalphas]


def test_a_linear_contraction_is_not_a_stall():
    # 0.93 per step halves max|Δα| in 10 steps (0.93^10 = 0.48): still converging
    assert stall(records(0.5 * 0.93 ** np.arange(200))) is None


def test_a_run_shorter_than_two_windows_is_not_judged():
    assert stall(records([1e-14] * (2 * STALL_STEPS - 1))) is None


def test_a_plateau_is_a_stall_from_its_first_step_within_a_factor_two():
    head = [0.7, 0.25, 3e-2, 7e-4, 1e-5]  # outer iterations 1-5
    plateau = np.where(np.arange(60) % 3 == 0, 3e-14, 5e-14)  # from iteration 6
    best, since = stall(records(head + list(plateau)))
    assert best == 3e-14
    assert since == len(head) + 1


def test_a_stall_above_the_step_accuracy_gets_no_hint():
    # a back-end cycling at 2e-6 rad: stalled, but not the accuracy of the steps
    out = out_of_iterations(np.zeros(3), 2, records([1e-3] + [2e-6, 4e-6] * 20), 41, tol=1e-9)
    assert "stalled, no lower than 2.00e-06 rad since outer iteration 2" in out.reason
    assert "accuracy" not in out.reason and "ask for" not in out.reason
    assert not out.converged


def test_still_converging_when_out_of_iterations_says_nothing_more():
    r = lcpbench.solve(ActuatorScene(theta=150.0, height=3.0, links=140), tol=1e-9,
                       max_outer=3)
    assert not r.converged
    assert r.reason.startswith("no convergence in 3 outer iterations")
    assert "stalled" not in r.reason


@pytest.mark.parametrize("engine", ["compiled", "numpy"])
def test_tol_below_the_step_accuracy_names_what_the_iteration_reaches(engine):
    scene = ActuatorScene(theta=150.0, height=3.0, links=1000)
    r = lcpbench.solve(scene, tol=1e-14, engine=engine)
    assert not r.converged
    m = re.search(r"no lower than ([0-9.e+-]+) rad since outer iteration (\d+), the accuracy "
                  r"of the contact steps; tol = 1e-14 rad is below it, ask for more than "
                  r"([0-9.e+-]+) rad", r.reason)
    assert m, r.reason
    best, since, ask = float(m[1]), int(m[2]), float(m[3])
    assert 1e-14 < best <= STEP_ACCURACY_DALPHA
    assert ask > best and since < 200
    assert ask >= 2.0 * best  # rounded up, never down
    # the consequence: asked for the suggested tol (a hair above it), the same
    # deterministic iteration stops, at the latest where the reason said it first came
    # within a factor 2 of its best
    again = lcpbench.solve(scene, tol=ask * (1.0 + 1e-9), engine=engine)
    assert again.outer_iterations <= since
