"""Faces of a symmetric positive definite H with more than two sub-diagonals, for the dual
walk of a general box QP (:func:`lcpbench.solvers.dual_kernel.box_qp`; an LCP's M).

A *face* of H holds its ``fixed`` nodes: their rows and columns are the identity's.
Where H has b sub-diagonals with b + 1 < n (``fac`` of shape (2, b + 1, n)), the face is
factored whole by the banded Cholesky (:func:`wide_factor`, O(n b²)); otherwise (``fac``
of shape (2, max(n, 2), n): a wide H, a dense LCP's M) its free block is gathered and
factored by LAPACK's Cholesky (:func:`dense_factor`, through numpy.linalg). No node is
held by a spring on these faces. ``fac[1, 0]`` marks the free nodes of the face last
factored. The contact step's faces (two sub-diagonals) are :mod:`.ldl_kernel`'s.
Loaded only through :func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def wide_factor(fac, bands, fixed):
    """The banded Cholesky L of the face ``fixed`` of H (b = bands.shape[0] − 1
    sub-diagonals; a fixed node's row and column the identity's), O(n b²), into
    ``fac[0]`` (row k: L[j + k, j]); ``fac[1, 0]`` marks the free nodes. False where the
    face is not positive definite."""
    n, b = fixed.size, bands.shape[0] - 1
    L = fac[0]
    for j in range(n):
        fac[1, 0, j] = 0.0 if fixed[j] else 1.0
    for j in range(n):
        if fixed[j]:
            L[0, j] = 1.0
            for k in range(1, b + 1):
                L[k, j] = 0.0
            continue
        s = bands[0, j]
        for p in range(max(j - b, 0), j):
            s -= L[j - p, p] * L[j - p, p]
        if not s > 0.0:
            return False
        d = np.sqrt(s)
        L[0, j] = d
        for k in range(1, b + 1):
            i = j + k
            if i >= n or fixed[i]:
                L[k, j] = 0.0
                continue
            t = bands[k, j]
            for p in range(max(i - b, 0), j):
                t -= L[i - p, p] * L[j - p, p]
            L[k, j] = t / d
    return True


@njit(cache=True)
def wide_resolve(fac, x):
    """x ← the face's solve of x (:func:`wide_factor`): L Lᵀ, banded."""
    n, L = x.size, fac[0]
    b = L.shape[0] - 1
    for j in range(n):
        s = x[j]
        for p in range(max(j - b, 0), j):
            s -= L[j - p, p] * x[p]
        x[j] = s / L[0, j]
    for j in range(n - 1, -1, -1):
        s = x[j]
        for k in range(1, min(b, n - 1 - j) + 1):
            s -= L[k, j] * x[j + k]
        x[j] = s / L[0, j]


@njit(cache=True)
def free_block_factor(fac, bands, fixed, shift):
    """The faces of H with more than two sub-diagonals: the banded Cholesky where
    ``fac`` is (2, b + 1, n) with b + 1 < n (:func:`wide_factor`, O(n b²)), else
    LAPACK's Cholesky of the free block (:func:`dense_factor`). No node is held by a
    spring on these faces: springs (``shift``) are refused (False)."""
    if shift.size:
        return False
    if fac.shape[1] < fixed.size:
        return wide_factor(fac, bands, fixed)
    return dense_factor(fac, bands, fixed)


@njit(cache=True)
def free_block_resolve(fac, x):
    """x ← the solve of the last face :func:`free_block_factor` factored."""
    if fac.shape[1] < x.size:
        wide_resolve(fac, x)
    else:
        dense_resolve(fac, x)


@njit(cache=True)
def dense_factor(fac, bands, fixed):
    """The Cholesky factor L of the face ``fixed`` of H (lower band storage ``bands``, any
    bandwidth) on its free nodes, gathered (LAPACK's, numpy.linalg.cholesky), into
    ``fac[0]``'s leading block; ``fac[1, 0]`` marks the free nodes, ``fac[1, 1]`` lists
    them. False where the face is not positive definite. No node is held by a spring
    here (the dual walk of a general QP, :func:`lcpbench.solvers.dual_kernel.box_qp`)."""
    n, b = fixed.size, bands.shape[0] - 1
    f = 0
    for i in range(n):
        fac[1, 0, i] = 0.0 if fixed[i] else 1.0
        if not fixed[i]:
            fac[1, 1, f] = i
            f += 1
    if f == 0:
        return True
    A = np.empty((f, f))
    for p in range(f):
        i = int(fac[1, 1, p])
        for q in range(p + 1):
            j = int(fac[1, 1, q])
            A[p, q] = bands[i - j, j] if i - j <= b else 0.0
            A[q, p] = A[p, q]
    try:
        L = np.linalg.cholesky(A)
    except Exception:  # (numba: LinAlgError) not positive definite
        return False
    fac[0, :f, :f] = L
    return True


@njit(cache=True)
def dense_resolve(fac, x):
    """x ← the face's solve of x (:func:`dense_factor`): L Lᵀ on the free nodes; a
    fixed node's row is the identity's."""
    n = x.size
    f = 0
    for i in range(n):
        if fac[1, 0, i] > 0.0:
            f += 1
    L = fac[0]
    y = np.empty(f)
    for p in range(f):  # L y = x on the free nodes
        s = x[int(fac[1, 1, p])]
        for q in range(p):
            s -= L[p, q] * y[q]
        y[p] = s / L[p, p]
    for p in range(f - 1, -1, -1):  # Lᵀ z = y
        s = y[p]
        for q in range(p + 1, f):
            s -= L[q, p] * y[q]
        y[p] = s / L[p, p]
    for p in range(f):
        x[int(fac[1, 1, p])] = y[p]
