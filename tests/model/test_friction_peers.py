"""The frictional step against Siconos' fc2d solvers, on the same step handed over in
their own form (issue 39, target 2): where a peer answers SOLVED, its reactions agree
with lcpbench's Lemke to 1e-6 relative."""

from dataclasses import replace

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.model.friction_driver import FrictionState, frictional_step, step_lemke
from lcpbench.model.friction_solvers import fc2d_contacts
from lcpbench.solvers import siconos_bridge
from lcpbench.solvers.siconos_fc2d import coulomb_residual, solve_fc2d

if not siconos_bridge.available():
    pytest.skip("siconos not installed for the system python "
                "(apt-get install python3-siconos)", allow_module_level=True)


def _random_steps(count, seed=39):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        ends = [("pinned", "slider"), ("slider", "slider")][rng.integers(2)]
        scene = ActuatorScene(theta=float(rng.uniform(100, 170)),
                              height=float(rng.uniform(1.5, 4.0)),
                              links=int(rng.choice([12, 16, 20])),
                              friction=float(rng.uniform(0.1, 0.8)),
                              pull=float(rng.uniform(0.0, 0.05)),
                              channel=bool(rng.random() < 0.3),
                              left_end=ends[0], right_end=ends[1])
        placed = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                        right_end="pinned", pull=0.0), tol=1e-10)
        chain = scene.chain()
        x_prev = placed.x + rng.normal(0.0, 0.05, placed.x.size)  # slips of 0.05 mm
        yield frictional_step(scene, chain, FrictionState(placed.alpha.copy()), x_prev,
                              pressed=np.ones(chain.free_nodes.size, bool))


def test_siconos_fc2d_agrees_with_lemke_on_random_frictional_steps():
    answered = {"lemke": 0, "nsgs": 0, "enum": 0}
    for fs in _random_steps(12):
        sol = step_lemke(fs.M, fs.q)
        assert sol.solved, sol.message
        W, q, mu = fc2d_contacts(fs)  # the form the fc2d back-ends are handed
        mn = fs.normal_node.size
        ours = np.empty(2 * mn)
        ours[0::2] = sol.z[:mn]
        ours[1::2] = (sol.z[mn:2 * mn] - sol.z[2 * mn:3 * mn])[fs.pair]
        assert coulomb_residual(W, q, mu, ours) <= 1e-10
        for method in answered:
            if method == "enum" and mn > 8:
                continue
            peer = solve_fc2d(W, q, mu, method=method)
            if peer.solved:
                answered[method] += 1
                scale = np.abs(ours).max()
                np.testing.assert_allclose(peer.r, ours, rtol=0, atol=1e-6 * scale)
    assert answered["lemke"] >= 6, answered  # the peer answers most steps
