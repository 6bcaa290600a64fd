"""A load–unload cycle (issue 39): hysteresis with friction, none without."""

from __future__ import annotations

import numpy as np
import pytest

import lcpbench
from lcpbench.errors import ProblemError
from lcpbench.studies.load_cycle import load_cycle

PRESSURES = [60.0, 90.0, 120.0, 150.0, 172.37]  # kPa: θ 58.4°–149.4° (actuator 1)


def _scene(mu):
    return lcpbench.ActuatorScene(theta=90, height=5.5, channel=True, links=30, friction=mu)


def test_without_friction_loading_and_unloading_are_the_frictionless_solve():
    c = load_cycle(_scene(0.0), PRESSURES)
    assert c.converged.all()
    np.testing.assert_allclose(c.force, c.frictionless, rtol=1e-9, atol=1e-12)
    (_, up), (_, down) = c.branch(True), c.branch(False)
    np.testing.assert_allclose(up, down, rtol=1e-9, atol=1e-12)


def test_with_friction_loading_and_unloading_differ_at_the_same_pressure():
    c = load_cycle(_scene(0.3), PRESSURES)
    assert c.converged.all()
    (p_up, up), (p_dn, down) = c.branch(True), c.branch(False)
    np.testing.assert_array_equal(p_up, p_dn)
    touching = c.frictionless[c.loading] > 1e-3  # N: pressures where the walls are pressed
    below_peak = touching & (p_up < p_up[-1])
    assert below_peak.any()
    gap = np.abs(up - down)[below_peak] / up[below_peak]
    assert np.all(gap > 1e-3), gap  # hysteresis: a history-dependent force
    # and the loading branch is not the frictionless model either
    assert np.max(np.abs(up - c.frictionless[c.loading])[touching]) > 1e-3 * up.max()


def test_bad_pressures_are_refused():
    with pytest.raises(ProblemError, match="pressures must be"):
        load_cycle(_scene(0.3), [100.0, 50.0])
