"""The judge's force error bound from a second judge step (lcpbench.model.judge_bound).

Expected values come from theory (a sequence that contracts linearly by ρ, whose
limit is known, so the error of every term is known exactly) and from an
independent method, the direct minimisation of the exact energy
(:mod:`lcpbench.reference.energy`: no contact step, no judge).
"""

from __future__ import annotations

import numpy as np
import pytest

from lcpbench import ActuatorScene, solve
from lcpbench.numba_cache import kernel_module
from lcpbench.reference.energy import minimise_energy
from lcpbench.thresholds import RHO_MAX, RHO_MIN


@pytest.fixture(scope="module")
def kern():
    return kernel_module("lcpbench.model.judge_bound", "force_error_bound")


def _linear(limit, c, rho, k):
    """Term k of R_k = R* + c ρ^k: contracts by exactly ρ per step towards R*."""
    return limit + c * rho ** k


@pytest.mark.parametrize("rho", [0.5, 0.9, 0.99])
def test_the_two_step_bound_is_the_error_under_linear_contraction(kern, rho):
    # R_k − R_{k+1} = c ρ^k (1 − ρ), R_{k+1} − R_{k+2} = c ρ^{k+1} (1 − ρ); with ρ' = ρ:
    # |d| + |e| / (1 − ρ) = |c| ρ^k (1 − ρ + ρ) = |R_k − R*|, the error exactly
    rng = np.random.default_rng(3)
    limit, c, k, F0 = rng.uniform(0.1, 1.0, 7), rng.uniform(1e-4, 1e-3, 7), 5, 2.0
    r0, r1, r2 = (_linear(limit, c, rho, k + j) for j in range(3))
    zero = np.zeros(7)
    total, _ = kern.force_error_bound(r0 - r1, zero, r1 - r2, zero, RHO_MAX, rho, 0.0, 0.0,
                                      F0, True)
    truth = abs(np.sum(r0) - np.sum(limit)) / F0
    assert total == pytest.approx(truth, rel=1e-9)
    # the driver's ρ at its cap (a back-end's pessimistic steps) would say 100 / (1/(1-ρ))
    # times more; the bound takes the smaller estimate
    one, _ = kern.force_error_bound(r0 - r1, zero, r1 - r2, zero, RHO_MAX, rho, 0.0, 0.0,
                                    F0, False)
    assert one == pytest.approx(np.sum(r0 - r1) / (1 - RHO_MAX) / F0, rel=1e-12)
    assert total <= one


def test_the_bound_is_the_smaller_estimate_and_the_node_bound_the_one_step(kern):
    # a driver that contracts fast (ρ = ½) against a judge whose steps do not (ρ' at the
    # cap): the one-step estimate is the smaller, and stays the bound
    d_up, d_lo = np.array([1e-6, -3e-6]), np.array([0.0, 2e-6])
    e_up, e_lo = np.array([1e-6, 1e-6]), np.array([0.0, -1e-6])
    total, node = kern.force_error_bound(d_up, d_lo, e_up, e_lo, 0.5, 0.99, 1e-12, 1e-12, 1.0,
                                         True)
    one = 2 * max(abs(d_up.sum()), abs(d_lo.sum())) + 1e-12
    two = max(abs(d_up.sum()) + 100 * abs(e_up.sum()), abs(d_lo.sum()) + 100 * abs(e_lo.sum()))
    assert two + 2e-12 > one
    assert total == pytest.approx(one, rel=1e-12)
    assert node == pytest.approx(2 * 3e-6, rel=1e-12)  # κ max_i |d_i|, per node
    # each wall on its own: the channel's lower wall sets the two-step estimate here
    total, _ = kern.force_error_bound(d_up, d_lo, 0 * e_up, e_lo, 0.99, 0.5, 0.0, 0.0, 1.0,
                                      True)
    assert total == pytest.approx(max(abs(d_up.sum()), abs(d_lo.sum()) + 2 * 1e-6), rel=1e-12)


@pytest.mark.parametrize("first, second, rho", [
    (1e-3, 1e-4, RHO_MIN),   # faster than ½: clamped up
    (1e-3, 7e-4, 0.7),
    (1e-3, 2e-3, RHO_MAX),   # growing: clamped down
    (1e-20, 1e-20, RHO_MIN),  # both at the round-off of an angle
    (1e-20, 1e-6, RHO_MAX),
    (1e-3, np.nan, RHO_MAX),
])
def test_the_judge_contraction_is_its_step_ratio_clamped(kern, first, second, rho):
    assert kern.judge_contraction(first, second) == pytest.approx(rho, rel=1e-15)


# the audit's scene whose driver stops 5.4e-4 F0 from the answer at tol 1e-3 (the one-step
# bound said 1.1e-3); a paper scene with two contact regions, and a channel
SCENES = [ActuatorScene(theta=96.664, height=4.4103, links=173, length=41.55, EI=35.664,
                        weight=0.00397),
          ActuatorScene(theta=180.0, height=2.0),
          ActuatorScene(theta=150.0, height=3.0, links=60, channel=True)]
RUNS = [({"tol": 1e-3}), ({"tol": 1e-6}), ({"solver": "osqp", "settings": "high", "tol": 1e-9,
                                            "formulation": "best"})]


@pytest.mark.parametrize("scene", SCENES, ids=["audit", "paper-180-2", "channel"])
def test_the_bound_is_not_below_the_true_error(scene):
    ref = minimise_energy(scene, start=solve(scene, settings="high", tol=1e-11).alpha)
    assert ref.success, ref.message
    ref_lower = np.zeros(0) if ref.forces_lower is None else ref.forces_lower
    for kw in RUNS:
        res = solve(scene, **kw)
        j = res.judgement
        assert np.isfinite(j.force_error_bound), (kw, j.reason)
        # the second step is taken where the one-step estimate exceeds tau; there it
        # settles (the audit scene at tol 1e-3: one step says 1.1e-3 > tau)
        assert np.isfinite(j.judge_contraction) or j.force_error_bound <= j.force_tol, kw
        if scene is SCENES[0] and kw == {"tol": 1e-3}:
            assert np.isfinite(j.judge_contraction)
        F0 = j.force_unit
        err = abs(res.total_force - ref.total_force) / F0
        if scene.channel:
            err = max(err, abs(float(np.sum(res.forces_lower)) - float(np.sum(ref_lower))) / F0)
        node = np.max(np.abs(np.concatenate([res.forces - ref.forces,
                                             (res.forces_lower - ref_lower)
                                             if scene.channel else []]))) / F0
        # the reference's own accuracy: its KKT check, 1e-9 dimensionless
        assert j.force_error_bound + 1e-9 >= err, (kw, j.force_error_bound, err)
        assert j.node_error_bound + 1e-9 >= node, (kw, j.node_error_bound, node)
