"""Symmetric banded matrices in LAPACK's lower banded storage.

``bands[k, i]`` holds H[i + k, i] (k = 0 is the diagonal), the layout of
``scipy.linalg.solveh_banded(..., lower=True)``. The contact step's Hessian
H = K (eq. 30) is pentadiagonal, so ``bands`` has three rows there; these
helpers take any bandwidth.
"""

from __future__ import annotations

from typing import Any

import numpy as np


class _Lazy:
    """A module imported at its first attribute look-up (``lazy.csc_matrix``)."""

    def __init__(self, name: str):
        self._name = name

    def __getattr__(self, attr: str) -> Any:
        import importlib

        return getattr(importlib.import_module(self._name), attr)


#: ``scipy.sparse``, imported when a QP back-end first builds a matrix, not at start-up
sparse = _Lazy("scipy.sparse")


def banded_matvec(bands: np.ndarray, u: np.ndarray) -> np.ndarray:
    """H @ u for a symmetric matrix of bandwidth ``bands.shape[0] - 1``."""
    out = bands[0] * u
    for k in range(1, bands.shape[0]):
        if k >= u.size:
            break
        out[k:] += bands[k, :-k] * u[:-k]
        out[:-k] += bands[k, :-k] * u[k:]
    return out


def solveh_banded(ab, b, **kw):
    """``scipy.linalg.solveh_banded``, importing scipy.linalg at the first call (it
    costs a tenth of a second at start-up, and the compiled default solve never
    calls it)."""
    from scipy.linalg import solveh_banded as solve

    return solve(ab, b, **kw)


def cholesky_banded(ab, **kw):
    """``scipy.linalg.cholesky_banded``, importing scipy.linalg at the first call."""
    from scipy.linalg import cholesky_banded as factor

    return factor(ab, **kw)


def sub_bands(bands: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Lower banded storage of the principal submatrix H[idx, idx] (idx sorted).

    A principal submatrix of a matrix of bandwidth b has bandwidth at most b:
    its entry (p + k, p) is H[idx[p + k], idx[p]], read from the bands when
    the two indices are at most b apart.
    """
    b = bands.shape[0] - 1
    m = idx.size
    sub = np.zeros((max(min(b, m - 1), 0) + 1, m))
    sub[0] = bands[0, idx]
    for k in range(1, sub.shape[0]):
        gap = idx[k:] - idx[:-k]
        ok = gap <= b
        vals = np.zeros(m - k)
        vals[ok] = bands[gap[ok], idx[:-k][ok]]
        sub[k, : m - k] = vals
    return sub


def dense_to_bands(P: np.ndarray) -> np.ndarray:
    """Lower banded storage of a symmetric matrix, at its actual bandwidth."""
    n = P.shape[0]
    rows, cols = np.nonzero(np.tril(P))
    b = int(np.max(rows - cols, initial=0))
    bands = np.zeros((b + 1, n))
    for k in range(b + 1):
        bands[k, : n - k] = np.diagonal(P, -k)
    return bands
