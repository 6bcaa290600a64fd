"""One accuracy knob (issue 40, item 4): ``solve(scene, accuracy=a)``.

The answer's total force is within a of the scene's energy minimum (the direct
minimisation of the exact energy, tests/energy_oracle.py: no contact step, driver or
judge; ~1e-11 of F₀ from the equilibrium on these scenes), the judge's bound
meets a, the translation is the settings profiles' (one meaning), and the
internals ``engine`` and ``scaled`` are no longer parameters of ``solve``.
"""

from __future__ import annotations

import inspect

import pytest
from energy_oracle import energy_minimum

import lcpbench
from lcpbench.accuracy import accuracy_settings, driver_tol_for
from lcpbench.api import solve_internal
from lcpbench.errors import ProblemError
from lcpbench.solvers.base import PROFILES
from lcpbench.solvers.selection import Selection

#: paper-grid scenes (θ, h) at N = 60: contact near a pin, in the middle, grazing, none
SCENES = [(150.0, 3.0), (180.0, 2.0), (90.0, 4.0), (120.0, 6.0), (40.0, 5.0)]


def _reference(scene):
    """The energy minimum's total force (its accuracy, ~1e-11 F₀, is far below the
    smallest accuracy asked here, 1e-7)."""
    return energy_minimum(scene).total_force


@pytest.mark.parametrize("theta,height", SCENES)
@pytest.mark.parametrize("accuracy", [1e-2, 1e-4, 1e-7])
def test_the_force_is_within_the_accuracy_asked(theta, height, accuracy):
    scene = lcpbench.ActuatorScene(theta=theta, height=height, links=60)
    res = lcpbench.solve(scene, accuracy=accuracy)
    assert res.converged, res.reason
    f0 = max(abs(_reference(scene)), scene.EI / scene.length**2)
    assert abs(res.total_force - _reference(scene)) <= accuracy * f0
    assert res.force_error_bound <= accuracy
    assert res.tol == min(accuracy, 1e-3)


@pytest.mark.parametrize("profile,accuracy", [("low", 1e-3), ("mid", 1e-6), ("high", 1e-9)])
def test_a_profile_is_an_accuracy(profile, accuracy):
    got, want = accuracy_settings(accuracy), PROFILES[profile]
    assert (got.eps, got.driver_tol) == (want.eps, want.driver_tol)


def test_select_probes_at_the_accuracys_driver_tol():
    from lcpbench.bench import select

    assert select.driver_tol_for is driver_tol_for


def test_a_loose_tol_is_tightened_until_the_bound_meets_the_accuracy():
    """With the expert's tol 1e-3 the judge allows a bound of 1e-3; the accuracy 1e-6
    continues the answer at tol 1e-8, where the judge's rule guarantees 1e-6."""
    scene = lcpbench.ActuatorScene(theta=150.0, height=3.0, links=60)
    loose = lcpbench.solve(scene, tol=1e-3)
    assert loose.converged and loose.force_error_bound > 1e-6
    res = lcpbench.solve(scene, accuracy=1e-6, tol=1e-3)
    assert res.converged and res.force_error_bound <= 1e-6 and res.tol == 1e-8
    assert [r.name for r in res.retries] == ["accuracy"]
    f0 = max(abs(_reference(scene)), scene.EI / scene.length**2)
    assert abs(res.total_force - _reference(scene)) <= 1e-6 * f0


def test_an_accuracy_out_of_reach_is_not_marked_converged():
    scene = lcpbench.ActuatorScene(theta=150.0, height=3.0, links=60)
    res = lcpbench.solve(scene, accuracy=1e-6, tol=1e-3, max_outer=2)
    assert not res.converged
    assert "exceeds accuracy 1.0e-06" in res.reason


@pytest.mark.parametrize("kw,match", [
    (dict(accuracy=2.0), "accuracy must be a number in"),
    (dict(accuracy="high"), "accuracy must be a number"),
    (dict(accuracy=1e-6, settings="high"), "give accuracy or settings, not both"),
])
def test_bad_accuracy_names_the_parameter(kw, match):
    with pytest.raises(ProblemError, match=match):
        lcpbench.solve(lcpbench.ActuatorScene(links=10), **kw)


def test_a_selection_and_an_accuracy_are_refused_together():
    sel = Selection("active-set", "default", 1e-6, 1e-6, 1e-3, 1e-9, "test")
    with pytest.raises(ProblemError, match="Selection carries its own accuracy"):
        lcpbench.solve(lcpbench.ActuatorScene(links=10), sel, accuracy=1e-6)


def test_the_internals_left_solves_signature():
    params = inspect.signature(lcpbench.solve).parameters
    assert "accuracy" in params and "tol" in params
    assert not {"engine", "scaled"} & set(params)
    with pytest.raises(TypeError):
        lcpbench.solve(lcpbench.ActuatorScene(links=10), engine="numpy")
    # still reachable one level down, with the same answer; the numpy engine is gone
    scene = lcpbench.ActuatorScene(theta=150.0, height=3.0, links=30)
    assert solve_internal(scene, engine="compiled").total_force == \
        lcpbench.solve(scene).total_force
    with pytest.raises(ProblemError, match="engine='numpy' was removed"):
        solve_internal(scene, engine="numpy")
