"""The Newton outer step (issue 19, item 2): the exact Hessian of the energy.

Expected values: the curvature term T against finite differences of the
exact energy gradient (an independent computation), the answer against the
Gauss–Newton scheme and the direct energy minimisation, and the step-size
sequence against the definition of quadratic convergence.
"""

import numpy as np
import pytest

from lcpbench import ActuatorScene, CantileverScene, solve
from lcpbench.model.chain import alpha_from_heights, energy, heights
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.newton import geometric_bands, newton_step
from lcpbench.reference.energy import minimise_energy


def _dense(bands):
    n = bands.shape[1]
    H = np.diag(bands[0])
    for k in (1, 2):
        off = np.diag(bands[k, : n - k], -k)
        H += off + off.T
    return H


def _energy_of_heights(chain, u, ref):
    alpha = alpha_from_heights(chain, u, ref)
    return energy(chain, alpha)


@pytest.mark.parametrize("scene", [ActuatorScene(theta=150, height=3, links=12, weight=0.01),
                                   CantileverScene(links=10)])
def test_exact_hessian_matches_finite_differences_of_the_energy(scene):
    chain = scene.chain()
    rng = np.random.default_rng(3)
    alpha = chain.rest_alpha + 0.05 * rng.standard_normal(chain.links)
    u0 = heights(chain, alpha)
    alpha = alpha_from_heights(chain, u0, alpha)  # a closed chain through u0
    step = assemble_step(chain, alpha)
    H_exact = _dense(step.bands) + _dense(geometric_bands(chain, alpha))
    n, h = u0.size, 1e-4 * chain.link_length
    fd = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            ei, ej = np.eye(n)[i] * h, np.eye(n)[j] * h
            fd[i, j] = (_energy_of_heights(chain, u0 + ei + ej, alpha)
                        - _energy_of_heights(chain, u0 + ei - ej, alpha)
                        - _energy_of_heights(chain, u0 - ei + ej, alpha)
                        + _energy_of_heights(chain, u0 - ei - ej, alpha)) / (4 * h * h)
    scale = np.max(np.abs(H_exact))
    assert np.max(np.abs(fd - H_exact)) <= 1e-5 * scale
    # and the Gauss–Newton H alone misses the curvature by much more than that
    assert np.max(np.abs(fd - _dense(step.bands))) > 1e-3 * scale


def test_newton_model_keeps_the_exact_gradient_at_the_linearisation_point():
    scene = ActuatorScene(theta=150, height=3, links=40)
    chain = scene.chain()
    step = assemble_step(chain, chain.rest_alpha)
    nstep, used = newton_step(step, chain)
    assert used
    u0 = step.origin
    assert np.allclose(nstep.gradient(u0), step.gradient(u0), rtol=0, atol=1e-12)
    assert np.allclose(nstep.gradient(u0), nstep.matvec(u0) + nstep.linear, rtol=1e-9,
                       atol=1e-9 * np.max(np.abs(step.linear)))


@pytest.mark.parametrize("theta,height,weight", [(150, 3.0, 0.000245), (180, 0.6, 0.000245),
                                                 (120, 2.0, 0.0)])
def test_newton_finds_the_same_equilibrium_as_the_energy_minimum(theta, height, weight):
    scene = ActuatorScene(theta=theta, height=height, links=60, weight=weight)
    res = solve(scene, method="newton", tol=1e-10)
    assert res.converged, res.reason
    ref = minimise_energy(scene)
    assert ref.success
    assert res.total_force == pytest.approx(ref.total_force, rel=1e-8)
    gn = solve(scene, tol=1e-10)
    assert np.max(np.abs(res.alpha - gn.alpha)) < 1e-9


def test_newton_converges_quadratically_near_the_answer():
    """|Δα_{k+1}| <= C |Δα_k|² once in the quadratic region (Gauss–Newton: linear)."""
    scene = ActuatorScene(theta=150, height=3, links=140)
    res = solve(scene, method="newton", tol=1e-12)
    assert res.converged, res.reason
    d = [s.max_dalpha for s in res.steps if s.max_dalpha > 1e-13]
    tail = d[-3:]
    assert tail[-1] <= 10 * tail[-2] ** 2  # quadratic: the exponent doubles
    gn = solve(scene, tol=1e-12)
    g = [s.max_dalpha for s in gn.steps if s.max_dalpha > 1e-13]
    # Gauss–Newton's last ratios stay linear (a constant factor, not a square)
    assert g[-1] > 10 * g[-2] ** 2
