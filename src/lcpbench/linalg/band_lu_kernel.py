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

__all__ = ["band_solve"]


@njit(cache=True)
def band_solve(ab, kl, ku, rhs):
    """Solve A X = ``rhs`` (N × P, overwritten by X) with A in ``ab`` (overwritten by its
    factor); every row scaled first by its largest entry. False where a pivot is zero
    or not finite (A singular to working precision). Each row's last nonzero column is
    followed through the exchanges and updates, so a sparse band costs its entries, not
    its width."""
    n, p, width = ab.shape[0], rhs.shape[1], ab.shape[1]
    last = np.empty(n, np.int64)  # the last column of each row that may be nonzero
    for r in range(n):  # row equilibration: the pivots compare like with like
        big, last[r] = 0.0, r
        for j in range(width):
            v = abs(ab[r, j])
            if v > 0.0:
                big = max(big, v)
                last[r] = r + j - kl
        if big == 0.0 or not np.isfinite(big):
            return False
        for j in range(width):
            ab[r, j] /= big
        for q in range(p):
            rhs[r, q] /= big
    for i in range(n):
        below = min(n - 1, i + kl)
        piv, best = i, abs(ab[i, kl])
        for r in range(i + 1, below + 1):
            v = abs(ab[r, i - r + kl])
            if v > best:
                piv, best = r, v
        if best == 0.0 or not np.isfinite(best):
            return False
        if piv != i:
            for c in range(i, max(last[i], last[piv]) + 1):
                t = ab[i, c - i + kl]
                ab[i, c - i + kl] = ab[piv, c - piv + kl]
                ab[piv, c - piv + kl] = t
            last[i], last[piv] = last[piv], last[i]
            for q in range(p):
                t = rhs[i, q]
                rhs[i, q] = rhs[piv, q]
                rhs[piv, q] = t
        d, end = ab[i, kl], last[i]
        for r in range(i + 1, below + 1):
            f = ab[r, i - r + kl] / d
            if f == 0.0:
                continue
            ab[r, i - r + kl] = 0.0
            for c in range(i + 1, end + 1):
                ab[r, c - r + kl] -= f * ab[i, c - i + kl]
            last[r] = max(last[r], end)
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
