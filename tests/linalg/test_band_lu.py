"""The banded LU with partial pivoting (linalg/band_lu_kernel.py): against numpy's dense
solve of the same matrix, where pivoting is needed (a zero diagonal), with rows of very
different scales, and a singular matrix refused."""

from __future__ import annotations

import numpy as np
import pytest

from lcpbench.numba_cache import kernel_module

lu = kernel_module("lcpbench.linalg.band_lu_kernel")


def banded(rng, n, kl, ku, zero_diagonal=False):
    """A random banded matrix, dense, and in the kernel's row storage."""
    A = np.zeros((n, n))
    for r in range(n):
        for c in range(max(0, r - kl), min(n, r + ku + 1)):
            A[r, c] = rng.standard_normal()
    if zero_diagonal:
        A[np.arange(n), np.arange(n)] = 0.0
    return A, stored(A, kl, ku)


def stored(A, kl, ku):
    n = A.shape[0]
    ab = np.zeros((n, 2 * kl + ku + 1))
    for r in range(n):
        for c in range(max(0, r - kl), min(n, r + ku + 1)):
            ab[r, c - r + kl] = A[r, c]
    return ab


@pytest.mark.parametrize("kl, ku, zero", [(1, 1, False), (8, 8, False), (3, 5, True),
                                          (8, 8, True)])
def test_band_solve_is_numpys_dense_solve(kl, ku, zero):
    rng = np.random.default_rng(kl * 10 + ku)
    A, ab = banded(rng, 60, kl, ku, zero_diagonal=zero)
    B = rng.standard_normal((60, 3))
    X = B.copy()
    assert lu.band_solve(ab, kl, ku, X)
    want = np.linalg.solve(A, B)  # (both backward stable: apart by at most ~ cond ε)
    assert np.max(np.abs(A @ X - B)) <= 1e-13 * 60 * np.max(np.abs(A)) * np.max(np.abs(X))
    assert np.max(np.abs(X - want)) <= 1e-14 * np.linalg.cond(A) * np.max(np.abs(want))


def test_rows_of_very_different_scales():
    """Rows scaled by 1e-8 … 1e8 (as a force balance beside a kinematic row): the row
    equilibration leaves the pivots and the answer as the unscaled system's."""
    rng = np.random.default_rng(5)
    A, _ = banded(rng, 40, 4, 4)
    B = rng.standard_normal((40, 2))
    D = 10.0 ** rng.uniform(-8, 8, 40)
    X = D[:, None] * B
    assert lu.band_solve(stored(D[:, None] * A, 4, 4), 4, 4, X)
    want = np.linalg.solve(A, B)
    assert np.max(np.abs(X - want)) <= 1e-9 * np.max(np.abs(want))


def test_a_singular_matrix_is_refused():
    """A zero row, and a zero column (no pivot in it: elimination never fills a column
    that is zero throughout)."""
    rng = np.random.default_rng(7)
    A, _ = banded(rng, 20, 2, 2)
    A[10] = 0.0
    assert not lu.band_solve(stored(A, 2, 2), 2, 2, np.ones((20, 1)))
    A, _ = banded(rng, 20, 2, 2)
    A[:, 13] = 0.0
    assert not lu.band_solve(stored(A, 2, 2), 2, 2, np.ones((20, 1)))
