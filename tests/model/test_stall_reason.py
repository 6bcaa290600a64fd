"""A run out of outer iterations says when max|Δα| had stalled, and whether the
requested tol is below the accuracy of the contact steps (lcpbench.model.outer.stall,
out_of_iterations).

The synthetic sequences are built to the definition: a contraction that halves the
smallest max|Δα| within STALL_STEPS steps is not a stall, a plateau is, and the level
reported is where the iteration sits (the last STALL_STEPS steps), not a one-off dip.
The end-to-end case asks for tol = 1e-14 rad at N = 2000, below what the steps resolve
there (their round-off: max|Δα| stalls near 6e-14 rad).
"""

from __future__ import annotations

import re

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.api import solve_internal
from lcpbench.model.outer import (
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
    level, since = stall(records(head + list(plateau)))
    assert level == 3e-14
    assert since == len(head) + 1


def test_the_level_is_where_the_iteration_sits_not_a_dip_before():
    # one step at 1e-12, then cycling at 1e-5..2e-5: stalled at 1e-5, which is no
    # step accuracy, and tol 1e-13 is not said to be out of reach for that reason
    out = out_of_iterations(np.zeros(3), 2, records([0.7, 0.1, 1e-12] + [1e-5, 2e-5] * 20),
                            43, tol=1e-13)
    assert "stalled, no lower than 1.00e-05 rad over the last 10 steps" in out.reason
    assert "accuracy" not in out.reason and "reach" not in out.reason
    assert not out.converged


def test_a_stall_above_the_step_accuracy_is_not_called_accuracy():
    out = out_of_iterations(np.zeros(3), 2, records([1e-3] + [2e-6, 4e-6] * 20), 41, tol=1e-9)
    assert ("stalled, no lower than 2.00e-06 rad over the last 10 steps and within a "
            "factor 2 of that since outer iteration 2") in out.reason
    assert "accuracy" not in out.reason and "reach" not in out.reason


def test_a_short_run_out_of_iterations_says_nothing_more():
    r = lcpbench.solve(ActuatorScene(theta=150.0, height=3.0, links=140), tol=1e-9,
                       max_outer=3)
    assert not r.converged
    assert r.reason.startswith("no convergence in 3 outer iterations")
    assert "stalled" not in r.reason


def test_tol_below_the_step_accuracy_is_named_out_of_reach():
    r = solve_internal(ActuatorScene(theta=150.0, height=3.0, links=2000), tol=1e-14,
                       engine="compiled")
    assert not r.converged
    m = re.search(r"no convergence in 200 outer iterations .*no lower than ([0-9.e+-]+) rad "
                  r"over the last 10 steps and within a factor 2 of that since outer "
                  r"iteration (\d+), the accuracy of the contact steps; tol = 1e-14 rad is "
                  r"below it, out of the driver's reach", r.reason)
    assert m, r.reason
    level, since = float(m[1]), int(m[2])
    assert 1e-14 < level <= STEP_ACCURACY_DALPHA
    assert since <= 200 - STALL_STEPS


def test_stop_on_stall_ends_a_stalled_run_and_leaves_a_converging_one_alone():
    """compiled_driver.run(stop_on_stall=True), the run after a kernel stop: a row of
    two sections whose height steps crawl (a link near the vertical, the steps cut to
    ~1e-4) ends at the first stall (2 STALL_STEPS steps, the stall named in the reason)
    instead of running all of max_outer; a run that converges is the same run."""
    from lcpbench import SectionedScene
    from lcpbench.model.compiled_driver import run as run_driver
    from lcpbench.model.step_solver import make_step_solver

    chain = SectionedScene(sections=[(179.6, 15.0), (-179.6, 15.0)], height=4.38,
                           links=140).chain()
    out = run_driver(chain, make_step_solver("active-set"), tol=1e-3, max_outer=200,
                     stop_on_stall=True)
    assert not out.converged and len(out.steps) < 200 and "stalled" in out.reason
    assert stall(out.steps) is not None  # (the definition, on the steps it took)
    paper = ActuatorScene(theta=150, height=3.0, links=40).chain()
    runs = [run_driver(paper, make_step_solver("active-set"), tol=1e-10, stop_on_stall=flag)
            for flag in (False, True)]
    assert runs[0].converged and runs[1].converged
    assert np.array_equal(runs[0].alpha, runs[1].alpha)
