"""The judge's exact step in increments (model/judge_exact_kernel.increments_step), the one
the judge kernel takes from LARGE_N links, checked by the step's KKT conditions written
out in energy_oracle (an independent check: the step in increments is a strictly convex
QP, so its conditions decide the answer, whatever the start set and the pivots).

The step is the one the large-N driver assembles (model/large_n.increments_at) from the
same inputs: the walls at the nodes' x and the slope load of the answer's reactions on a
wall profile; the walls' springs from the chain's stiffness k, where the judge kernel
takes the compliances 1/k the solve kernel's arguments carry.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from energy_oracle import assert_elastic_step_kkt, assert_step_kkt
from known_answers import stenosis

from lcpbench import ActuatorScene
from lcpbench.model.kernel_call import kernel_args
from lcpbench.model.large_driver import run_large
from lcpbench.model.large_n import increments_at
from lcpbench.model.profile import slope_load, wall_rows
from lcpbench.model.step_solver import make_step_solver
from lcpbench.numba_cache import kernel_module


def _kernel():
    """The judge's step in increments and its node states (FREE, UP, LO)."""
    return kernel_module("lcpbench.model.judge_exact_kernel")


SCENES = {
    "rigid": dict(),
    "channel": dict(channel=True),
    "elastic": dict(wall_stiffness=0.1),
    "stiff elastic channel": dict(wall_stiffness=1e4, channel=True),
    "stenosis": dict(wall_profile=stenosis()),
}


def _judge_step(chain, alpha, forces, state, *, from_state):
    """increments_step at α as the judge kernel calls it: its walls and load (a profile's
    at the nodes' x, with the slope load of ``forces``), the pull ε_R of a small force."""
    a, _, _, k, rest, _, load, fs, lower, upper, _, _, cu, cl = kernel_args(chain)[1:]
    profiled = chain.profiled_walls
    if profiled:
        rows = wall_rows(chain, alpha)
        upper, lower = rows[2], rows[3]
        load = chain.nodal_load + slope_load(chain, alpha, *(np.maximum(f, 0.0)
                                                             for f in forces), rows)
    n = chain.free_nodes.size
    u, net, roundoff, noise = (np.empty(n) for _ in range(4))
    alpha_next = np.empty(alpha.size)
    f64 = np.ascontiguousarray
    rounds, _, _, dalpha = _kernel().increments_step(
        f64(alpha, dtype=float), a, k, rest, f64(load, dtype=float), f64(lower, dtype=float),
        f64(upper, dtype=float), cu, cl, fs, 1e-9 * chain.force_scale, *forces, profiled,
        from_state, state, u, net, roundoff, noise, alpha_next)
    step = increments_at(chain, alpha, walls=(lower, upper), load=load)
    return rounds, u, net, dalpha, alpha_next, step


@pytest.mark.parametrize("kind", sorted(SCENES))
def test_the_judges_step_in_increments_meets_the_steps_kkt_conditions(kind):
    chain = replace(ActuatorScene(150, 3.0, links=200, **SCENES[kind]).chain(),
                    increments=True)
    out = run_large(chain, make_step_solver("auto"), tol=1e-3)
    assert out.converged
    rng = np.random.default_rng(7)
    n = chain.free_nodes.size
    # 1e-5 rad off the answer's α, where the step moves the chain by more than the
    # round-off of its terms (at the answer itself d ~ 0 and the KKT conditions, relative
    # to the terms' size, test round-off alone), from the answer's contact set (the
    # judge's first step) and again from the settled one (its second step's start)
    alpha = out.alpha + 1e-5 * rng.standard_normal(out.alpha.size)
    kern = _kernel()
    state = np.full(n, kern.FREE, dtype=np.int64)
    for from_state in (False, True):
        rounds, u, net, dalpha, alpha_next, step = _judge_step(
            chain, alpha, (out.forces_upper, out.forces_lower), state, from_state=from_state)
        assert rounds > 0  # it settled
        d = u - step.heights  # the answer in increments about u₀
        if chain.elastic_walls:  # stationary with the springs; R their forces
            up, lo = assert_elastic_step_kkt(step, d, rtol=1e-9)
            R = up - lo
        else:  # R = −(H d + f) from the step's bands
            R = assert_step_kkt(step, d, rtol=1e-9)
            # the contact set it reports holds its nodes on their walls
            assert np.allclose(d[state == kern.UP], step.upper[state == kern.UP], rtol=0,
                               atol=1e-12 * chain.length)
            assert np.allclose(d[state == kern.LO], step.lower[state == kern.LO], rtol=0,
                               atol=1e-12 * chain.length)
        # its net reactions are those, to round-off of the gradient's terms
        size = step.gradient_scale(d) + np.abs(R)
        assert np.all(np.abs(net - R) <= 1e-9 * size)
        assert dalpha == np.max(np.abs(alpha_next - alpha))
