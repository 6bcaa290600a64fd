"""The frictional step's Delassus products in O(N · cols) (model/friction_step.py,
``slip_product`` and ``contact_gram``) against numpy's dense products of the same
matrices: D X with D = slip_jacobian (both datums, with and without τ's column) and
Bᵀ X with B = [G_n | G_t | f] as _solve_columns builds it."""

import numpy as np
import pytest

from lcpbench.numba_cache import jit_module

# through the kernels' cache (a direct import would cache them beside their sources)
fs = jit_module("lcpbench.model.friction_step")


def _case(seed, links, first, n, right_datum, tau):
    rng = np.random.default_rng(seed)
    alpha = rng.uniform(-1.3, 1.3, links)
    D = fs.slip_jacobian(alpha, first, n, right_datum)
    if tau:
        D = np.hstack([D, np.ones((D.shape[0], 1))])
    return rng, D


@pytest.mark.parametrize("right_datum, tau", [(False, False), (False, True), (True, False)])
@pytest.mark.parametrize("links, first, n", [(12, 1, 11), (9, 0, 10), (15, 1, 14), (7, 2, 4)])
def test_slip_product_is_the_dense_product(links, first, n, right_datum, tau):
    rng, D = _case(links + 3 * first + n, links, first, n, right_datum, tau)
    X = rng.normal(size=(D.shape[1], 6))
    assert np.allclose(fs.slip_product(D, X, first, n), D @ X, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("right_datum, tau", [(False, False), (False, True), (True, False)])
@pytest.mark.parametrize("sloped", [False, True])
def test_contact_gram_is_the_dense_gram(right_datum, tau, sloped):
    links, first, n = 14, 1, 13
    rng, D = _case(7 + sloped, links, first, n, right_datum, tau)
    size = D.shape[1]
    normal_node = np.array([2, 5, 6, 11], np.int64)  # free-node indices
    slope = rng.uniform(-0.4, 0.4, normal_node.size) if sloped else np.zeros(normal_node.size)
    normal_xy = np.column_stack([slope, -np.ones(normal_node.size)]) / np.sqrt(1 + slope**2)[:, None]
    friction_node = (normal_node[[0, 2, 3]] + first).astype(np.int64)  # nodes 0..N
    ts = slope[[0, 2, 3]]
    tangent_xy = np.column_stack([np.ones(3), ts]) / np.sqrt(1 + ts**2)[:, None]
    f = rng.normal(size=size)
    cols = normal_node.size + friction_node.size + 1
    X = rng.normal(size=(size, cols))
    B = np.zeros((size, cols))  # as _solve_columns writes it, column by column
    for r, node in enumerate(normal_node):
        B[:, r] = normal_xy[r, 0] * D[first + node]
        B[node, r] += normal_xy[r, 1]
    for c, node in enumerate(friction_node):
        B[:, normal_node.size + c] = tangent_xy[c, 0] * D[node]
        B[node - first, normal_node.size + c] += tangent_xy[c, 1]
    B[:, -1] = f
    got = fs.contact_gram(X, D, f, normal_node, normal_xy, friction_node, tangent_xy, first, n)
    assert np.allclose(got, B.T @ X, rtol=1e-13, atol=1e-12)
