"""The SQP step's banded QP (model/angle_kernel.py) against dense linear algebra.

The oracle is a linear-algebra one, not a route of lcpbench: the same QP written
densely (B = Dᵀ diag(k) D + diag(δ) from its definition, the closure and wall rows as
the prefix sums they are) and solved by enumerating the wall active sets, each by a
dense KKT solve, keeping the one whose multipliers are ≥ 0 and whose other walls hold.
The whole SQP is checked against an independent minimisation of the exact energy
(SLSQP and a Newton polish, reference/energy.py) on a row of two sections whose
answer has links past the vertical.
"""

import itertools

import numpy as np
import pytest

import lcpbench
from lcpbench.model.angle_step import solve_in_angles
from lcpbench.model.chain import node_positions
from lcpbench.numba_cache import jit_module
from lcpbench.problems.sections import SectionedScene
from lcpbench.reference.energy import minimise_energy

# through the kernels' cache (a direct import would cache them beside their sources)
ak = jit_module("lcpbench.model.angle_kernel")


def _instance(seed, n=7, walls=5, pinned=True):
    rng = np.random.default_rng(seed)
    alpha = rng.uniform(-1.4, 1.4, n)
    alpha[n // 2] = np.pi / 2  # a link at the vertical: the lifted rows stay regular
    a = 0.7
    jl = np.arange(-1, n - 1)
    jr = np.arange(n)
    k = rng.uniform(1.0, 3.0, n)
    W = rng.uniform(-0.2, 0.2, n)
    grad = rng.normal(size=n)
    y = np.concatenate(([0.0], np.cumsum(a * np.sin(alpha))))
    last = n - 1 if pinned else n
    # not the node after the vertical link: its height increment is the one before's
    nodes = np.array([j for j in range(1, last + 1) if j != n // 2 + 1])
    node = np.sort(rng.choice(nodes, walls, replace=False))
    side = rng.choice([-1.0, 1.0], walls)
    # the walls hold with a margin at a step d0 that meets the closure: a feasible QP
    c = a * np.cos(alpha)
    d0 = rng.normal(scale=0.3, size=n)
    if pinned:
        d0 -= (y[-1] + c @ d0) / (c @ c) * c
    y0 = y + np.concatenate(([0.0], np.cumsum(c * d0)))
    limit = y0[node] + side * rng.uniform(0.0, 0.2, walls)  # some violated at d = 0
    mu = np.where(rng.uniform(size=walls) < 0.5, rng.uniform(0, 0.1, walls), 0.0)
    lam = np.array([rng.uniform(-0.1, 0.1)])
    return alpha, a, jl, jr, k, W, grad, y, pinned, node, side, limit, lam, mu


def _dense_qp(alpha, a, jl, jr, k, W, grad, y, pinned, node, side, limit, lam, mu):
    n = alpha.size
    D = np.zeros((n, n))
    for i, (left, right) in enumerate(zip(jl, jr, strict=True)):
        D[i, right] += 1.0
        if left >= 0:
            D[i, left] -= 1.0
    mask = (np.arange(n)[None, :] < node[:, None]).astype(float)
    c = a * np.cos(alpha)
    curv = a * np.sin(alpha) * (W + (lam[0] if pinned else 0.0) - (mu * side) @ mask)
    B = D.T @ (k[:, None] * D) + np.diag(curv)
    Jc = c[None, :] if pinned else np.zeros((0, n))
    cval = np.array([y[-1]]) if pinned else np.zeros(0)
    Jg = -side[:, None] * mask * c[None, :]  # g + Jg d ≥ 0
    g = side * (limit - y[node])
    found = []
    for act in itertools.product([False, True], repeat=node.size):
        act = np.array(act, bool)
        A = np.vstack((Jc, Jg[act]))
        m = A.shape[0]
        kkt = np.block([[B, -A.T], [A, np.zeros((m, m))]])
        if np.linalg.matrix_rank(A) < m:  # dependent rows (at the vertical link)
            continue
        sol = np.linalg.solve(kkt, np.concatenate((-grad, -cval, -g[act])))
        d, nu = sol[:n], sol[n:]
        mu_act = nu[cval.size:]
        if np.all(mu_act >= -1e-12) and np.all((g + Jg @ d)[~act] >= -1e-12):
            full = np.zeros(node.size)
            full[act] = mu_act
            found.append((d, nu[:cval.size], full))
    return B, found


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("pinned", [True, False])
def test_the_banded_qp_step_is_the_dense_qp_answer(seed, pinned):
    args = _instance(seed, pinned=pinned)
    B, found = _dense_qp(*args)
    if np.min(np.linalg.eigvalsh(B)) <= 1e-3:  # the oracle's QP must be strictly convex
        pytest.skip("B not positive definite for this draw")
    assert len(found) == 1  # strictly convex: one KKT point
    d_ref, lam_ref, mu_ref = found[0]
    code, d, lam, mu, sigma, _ = ak.qp_step(*args[:8], args[8], *args[9:], 1e-14)
    assert code == ak.OK and sigma == 0.0
    assert np.allclose(d, d_ref, rtol=0, atol=1e-10)
    assert np.allclose(mu, mu_ref, rtol=0, atol=1e-10)
    if pinned:
        assert lam[0] == pytest.approx(lam_ref[0], abs=1e-10)


def _face_convex_by_eigenvalues(bd, off, c, fixed):
    """The oracle: the smallest eigenvalue of Zᵀ B Z, Z a null-space basis (SVD) of the
    runs' constraints Σ_{k in run} c_k d_k = 0."""
    n = bd.size
    B = np.diag(bd) + np.diag(off, 1) + np.diag(off, -1)
    rows, p = [], 0
    for q in range(1, n + 1):
        if fixed[q]:
            row = np.zeros(n)
            row[p:q] = c[p:q]
            rows.append(row)
            p = q
    if not rows:
        return np.min(np.linalg.eigvalsh(B)) > 0
    A = np.array(rows)
    Z = np.linalg.svd(A)[2][len(rows):].T
    return np.min(np.linalg.eigvalsh(Z.T @ B @ Z)) > 0


@pytest.mark.parametrize("seed", range(40))
def test_the_face_convexity_test_reads_the_reduced_inertia(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 12))
    bd = rng.normal(1.0, 1.5, n)  # often indefinite
    off = rng.normal(0.0, 0.7, n - 1)
    c = rng.uniform(-1, 1, n)
    fixed = np.concatenate(([True], rng.uniform(size=n) < 0.3))
    expect = _face_convex_by_eigenvalues(bd, off, c, fixed)
    assert ak.convex_on_face(bd, off, c, fixed) == expect


@pytest.mark.parametrize("links", [20, 30])
def test_two_sections_at_174_degrees_agree_with_the_energy_minimum(links):
    scene = SectionedScene(sections=[(174.0, 15.0), (-174.0, 15.0)], height=2.02, links=links)
    ref = minimise_energy(scene)
    assert ref.success, ref.message
    scale = scene.EI / scene.length**2
    out = solve_in_angles(scene.chain(), tol=1e-12)  # from the rest shape clipped to the wall
    assert out.converged, out.reason
    assert np.degrees(np.max(np.abs(out.alpha))) > 95.0  # links past the vertical
    assert abs(np.sum(out.forces_upper) - np.sum(ref.forces)) <= 1e-9 * scale
    res = lcpbench.solve(scene, tol=1e-8)  # along the loading path, judged
    assert res.converged, res.reason
    assert abs(res.total_force - np.sum(ref.forces)) <= 1e-9 * scale
    assert np.max(np.abs(res.y - ref.y)) <= 1e-9 * scene.length


def test_a_start_from_a_neighbours_answer_and_multipliers_reaches_the_energy_minimum():
    # the loading path's warm start (model.ramp): the answer at 0.95 θ, its angles and
    # reactions (and λ) the first iterate and multipliers; the oracle is SLSQP on the energy
    scene = SectionedScene(sections=[(174.0, 15.0), (-174.0, 15.0)], height=2.02, links=20)
    ref = minimise_energy(scene)
    assert ref.success, ref.message
    scale = scene.EI / scene.length**2
    near = solve_in_angles(scene.chain_at(0.95), tol=1e-12)
    assert near.converged, near.reason
    out = solve_in_angles(scene.chain(), tol=1e-12, start=near.alpha,
                          multipliers=(near.closure, near.forces_upper, near.forces_lower))
    assert out.converged, out.reason
    assert abs(np.sum(out.forces_upper) - np.sum(ref.forces)) <= 1e-9 * scale
    y = node_positions(scene.chain(), out.alpha)[1]
    assert np.max(np.abs(y - ref.y)) <= 1e-9 * scene.length
