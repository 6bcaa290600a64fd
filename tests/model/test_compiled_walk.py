"""The compiled dual walk's incremental bookkeeping (solvers/dual_kernel.py).

The walk keeps its held nodes, picks and changed nodes as lists and computes
r = g + H d₀ only where d₀ reaches; the certificate takes the gradient and its
scale in one pass. Checked against independent computations: the contact step's
answer against the step's KKT conditions written out in the test
(tests/energy_oracle.assert_step_kkt) and against the primal active set of the numpy reference (another method on
the same strictly convex QP, whose answer is unique) on asymmetric steps, cold
and warm-started from wrong contact sets (so that the walk releases walls), and
the fused gradient and term size against the gradient alone (bit for bit) and
against J, T and the loads written out in numpy.
"""

from __future__ import annotations

import numpy as np
import pytest
from energy_oracle import assert_step_kkt

from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.kernel_call import kernel_args
from lcpbench.numba_cache import kernel_module
from lcpbench.problems.scenes import ActuatorScene
from lcpbench.solvers.banded import solve_banded_qp
from lcpbench.solvers.base import Status

kernel = kernel_module("lcpbench.model.compiled_kernel", "solve_chain")
dual = kernel_module("lcpbench.model.compiled_dual")
walk = kernel_module("lcpbench.solvers.dual_kernel")


def _perturbed(scene, seed):
    chain = scene.chain()
    rng = np.random.default_rng(seed)
    alpha = chain.rest_alpha * 0.85 + 0.01 * rng.standard_normal(chain.links)  # no symmetry
    return chain, alpha


def _kernel_step(chain, alpha, warm_up=None):
    ra, a, jl, jr, k, rest, _, nodal_load, fs, lo, hi, L, F, cu, cl = kernel_args(chain)
    n = lo.size
    flags = 0 if warm_up is None else 2
    up = np.zeros(n, bool) if warm_up is None else np.ascontiguousarray(warm_up)
    return kernel.contact_step(np.ascontiguousarray(alpha), a, jl, jr, k, rest, fs, n, nodal_load,
                                lo, hi, L, F, cu, cl, np.zeros(n), up, np.zeros(n, bool), flags,
                                20 * n + 50, 1e-3)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("warm", ["cold", "wrong"])
def test_contact_step_is_the_primal_active_sets_answer(seed, warm):
    scene = ActuatorScene(theta=120 + 10 * seed, height=2.0 + 0.5 * seed, links=90)
    chain, alpha = _perturbed(scene, seed)
    ref = solve_banded_qp(assemble_step(chain, alpha), method="primal")
    assert ref.status is Status.SOLVED
    warm_up = None
    if warm == "wrong":  # walls away from the contacts, where the walk must release them
        rng = np.random.default_rng(seed)
        warm_up = np.isfinite(chain.upper) & (rng.random(chain.upper.size) < 0.3)
        warm_up &= ~ref.active_upper
    got = _kernel_step(chain, alpha, warm_up)
    code, u, r_up = got[0], got[1], got[2]
    assert code == 0
    assert_step_kkt(assemble_step(chain, alpha), u)  # the step's KKT conditions, by hand
    assert np.array_equal(u >= chain.upper, ref.active_upper)
    span = 1.0 + np.max(np.abs(ref.u))
    assert np.max(np.abs(u - ref.u)) <= 1e-9 * span
    # each answer is certified to rtol 1e-9 of the size of the terms that cancel, which
    # exceed the reactions here by up to ~100x
    force = max(np.max(ref.forces_upper), chain.force_scale)
    assert np.max(np.abs(r_up - ref.forces_upper)) <= 1e-7 * force


def test_fused_gradient_and_term_size():
    chain, alpha = _perturbed(ActuatorScene(theta=150, height=3.0, links=140), 5)
    got = _kernel_step(chain, alpha)
    gp = got[9]
    n, nj = chain.upper.size, gp[0].shape[0]
    rng = np.random.default_rng(0)
    for newton in (False, True):
        T = np.zeros((2, n)) if not newton else rng.standard_normal((2, n))
        u = got[1] + 1e-3 * rng.standard_normal(n)
        g1, m = np.empty(n), np.empty(nj)
        walk.grad_into(g1, m, u, gp, T)
        f1, f2 = np.empty(n), np.empty(n)
        dual.grad_and_scale(f1, f2, np.empty(nj), np.empty(nj), u, gp, T)
        assert np.array_equal(f1, g1)
        # the size of the terms, ContactStep.gradient_scale written out in numpy:
        # |J| |u − u₀| + |φ₀| + |φ*| scaled by k, through |J|ᵀ, plus |f| and |T| |u − u₀|
        coef, b0, fs, _, origin, phi0, k, rest, load = gp
        J = np.zeros((nj, n))
        for j in range(nj):
            for c in range(3):
                if 0 <= b0 - fs + j + c < n:
                    J[j, b0 - fs + j + c] = coef[j, c]
        du = np.abs(u - origin)
        Tfull = np.diag(T[0]) + np.diag(T[1, :-1], 1) + np.diag(T[1, :-1], -1)
        size = (np.abs(J).T @ ((np.abs(J) @ du + np.abs(phi0) + np.abs(rest)) * k)
                + np.abs(load) + np.abs(Tfull) @ du)
        assert np.allclose(f2, size, rtol=1e-13, atol=0.0)
        # and the gradient itself: Jᵀ k (J (u − u₀) + φ₀ − φ*) − f + T (u − u₀)
        grad = J.T @ ((J @ (u - origin) + phi0 - rest) * k) - load + Tfull @ (u - origin)
        assert np.allclose(g1, grad, rtol=0.0, atol=1e-12 * np.max(size))
