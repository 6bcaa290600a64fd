"""Banded storage against dense numpy: the independent reference is H itself."""

import numpy as np
import pytest

from lcpbench.linalg import banded_matvec, dense_to_bands, sub_bands


def _random_banded(n: int, b: int, rng) -> np.ndarray:
    A = rng.standard_normal((n, n))
    A = A + A.T
    i, j = np.indices((n, n))
    A[np.abs(i - j) > b] = 0.0
    return A


@pytest.mark.parametrize("n,b", [(1, 0), (2, 2), (7, 1), (9, 2), (12, 3)])
def test_matvec_and_round_trip_match_dense(n, b):
    rng = np.random.default_rng(n * 10 + b)
    H = _random_banded(n, b, rng)
    bands = dense_to_bands(H)
    assert bands.shape[0] - 1 <= b
    u = rng.standard_normal(n)
    np.testing.assert_allclose(banded_matvec(bands, u), H @ u, rtol=0, atol=1e-12)


@pytest.mark.parametrize("idx", [[0, 1, 2, 3, 4, 5, 6, 7, 8, 9], [0, 2, 3, 7, 8], [1, 4, 9], [5]])
def test_principal_submatrix(idx):
    rng = np.random.default_rng(3)
    H = _random_banded(10, 2, rng)
    idx = np.asarray(idx)
    sub = sub_bands(dense_to_bands(H), idx)
    dense = np.zeros((idx.size, idx.size))
    for k in range(sub.shape[0]):
        dense += np.diag(sub[k, : idx.size - k], -k)
        if k:
            dense += np.diag(sub[k, : idx.size - k], k)
    np.testing.assert_array_equal(dense, H[np.ix_(idx, idx)])
