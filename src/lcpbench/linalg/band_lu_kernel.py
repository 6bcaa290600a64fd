"""A general banded system solved by Gaussian elimination with partial pivoting, compiled.

The matrix A (N × N, ``kl`` bands below the diagonal and ``ku`` above) is stored by rows,
entry (r, c) at ``ab[r, c − r + kl]``, in an array N × (2 kl + ku + 1): the ``kl`` extra
columns on the right take the fill of the row exchanges (LAPACK's dgbsv keeps the same
room, by columns). Elimination costs O(N kl (kl + ku)) and each right-hand side
O(N (kl + ku)). It serves systems that are banded but neither symmetric nor definite
(the lifted KKT system of the profile sensitivities,
:mod:`lcpbench.model.sensitivity_profile_kernel`). Loaded through
:func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["band_factor", "band_resolve", "band_solve"]


@njit(cache=True)
def band_solve(ab, kl, ku, rhs):
    """Solve A X = ``rhs`` (N × P, overwritten by X) with A in ``ab`` (overwritten by its
    factor); every row scaled first by its largest entry. False where a pivot is zero
    or not finite (A singular to working precision). Each row's last nonzero column is
    followed through the exchanges and updates, so a sparse band costs its entries, not
    its width."""
    n, p, width = ab.shape[0], rhs.shape[1], ab.shape[1]
    for r in range(n):  # row equilibration: the pivots compare like with like
        big = 0.0
        for j in range(width):
            big = max(big, abs(ab[r, j]))
        if big == 0.0 or not np.isfinite(big):
            return False
        for j in range(width):
            ab[r, j] /= big
        for q in range(p):
            rhs[r, q] /= big
    piv = np.empty(n, np.int64)
    last = np.empty(n, np.int64)
    if not band_factor(ab, kl, piv, last):
        return False
    return band_resolve(ab, kl, piv, last, rhs)


@njit(cache=True)
def band_factor(ab, kl, piv, last):
    """A = P L U in place (``ab`` as :func:`band_solve`'s, not scaled here): U on and
    above the diagonal, L's multipliers of column i in its rows below, where column i's
    entries were (LAPACK's dgbtrf keeps them so, by columns); ``piv[i]`` the row exchanged
    with row i at step i, ``last[r]`` the last column of row r that may be nonzero. False
    where a pivot is zero or not finite. The factor serves any number of right-hand sides
    (:func:`band_resolve`)."""
    n, width = ab.shape[0], ab.shape[1]
    for r in range(n):
        last[r] = r
        for j in range(width):
            if ab[r, j] != 0.0:
                last[r] = r + j - kl
    for i in range(n):
        below = min(n - 1, i + kl)
        p, best = i, abs(ab[i, kl])
        for r in range(i + 1, below + 1):
            v = abs(ab[r, i - r + kl])
            if v > best:
                p, best = r, v
        if best == 0.0 or not np.isfinite(best):
            return False
        piv[i] = p
        if p != i:
            for c in range(i, max(last[i], last[p]) + 1):
                t = ab[i, c - i + kl]
                ab[i, c - i + kl] = ab[p, c - p + kl]
                ab[p, c - p + kl] = t
            last[i], last[p] = last[p], last[i]
        d, end = ab[i, kl], last[i]
        for r in range(i + 1, below + 1):
            f = ab[r, i - r + kl] / d
            ab[r, i - r + kl] = f  # L's multiplier, kept for the right-hand sides
            if f == 0.0:
                continue
            for c in range(i + 1, end + 1):
                ab[r, c - r + kl] -= f * ab[i, c - i + kl]
            last[r] = max(last[r], end)
    return True


@njit(cache=True)
def band_resolve(ab, kl, piv, last, rhs):
    """X with A X = ``rhs`` (N × P, overwritten) from :func:`band_factor`'s factor: the
    exchanges and L's multipliers in the order of the elimination, then U backwards.
    False where X is not finite."""
    n, p = ab.shape[0], rhs.shape[1]
    for i in range(n):
        r0 = piv[i]
        if r0 != i:
            for q in range(p):
                t = rhs[i, q]
                rhs[i, q] = rhs[r0, q]
                rhs[r0, q] = t
        for r in range(i + 1, min(n - 1, i + kl) + 1):
            f = ab[r, i - r + kl]
            if f != 0.0:
                for q in range(p):
                    rhs[r, q] -= f * rhs[i, q]
    for i in range(n - 1, -1, -1):
        for q in range(p):
            s = rhs[i, q]
            for c in range(i + 1, last[i] + 1):
                s -= ab[i, c - i + kl] * rhs[c, q]
            rhs[i, q] = s / ab[i, kl]
    for i in range(n):
        for q in range(p):
            if not np.isfinite(rhs[i, q]):
                return False
    return True
