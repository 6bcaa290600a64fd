"""Lemke's pivots, compiled: the loop of :func:`lcpbench.solvers.lemke.lemke`.

The revised tableau ``[B^{-1} | B^{-1} q]``, the lexicographic minimum-ratio test with
its tie tolerances and the complementary pivot rule, as :mod:`lcpbench.solvers.lemke`
describes them; that module sets the problem up and checks the answer (refinement,
residuals). Each function is ``@njit(cache=True)``, loaded through
:func:`lcpbench.numba_cache.kernel_module`; with NUMBA_DISABLE_JIT=1 they run as plain
Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: the kernel's ends: z0 left the basis, the pivot budget, a secondary ray, a
#: non-finite pivot row
DONE, MAX_ITER, RAY, FAILED = 0, 1, 2, 3


@njit(cache=True)
def _tied(col, a, noise, tie_rtol):
    """Mask of the rows whose ratio ``col / a`` ties with the smallest: within
    ``tie_rtol`` (|min| + both rows' noise over a): the lexicographic rule's ties."""
    m = col.size
    ratios = col / a
    j = 0
    for i in range(1, m):
        if ratios[i] < ratios[j]:
            j = i
    least = ratios[j]
    out = np.empty(m, np.bool_)
    for i in range(m):
        slack = tie_rtol * (abs(least) + noise[j] / a[j] + noise[i] / a[i])
        out[i] = ratios[i] <= least + slack
    return out


@njit(cache=True)
def lexmin_row(binv, rhs, rows, a, prefer, qnorm, tie_rtol):
    """Row of the lexicographic minimum ratio among ``rows`` (lemke._lexmin_row): the
    right-hand side ``rhs`` first (noise × ``qnorm``), then the columns of ``binv`` in
    order, each stage keeping the rows tied with the minimum; ``prefer`` wins if it
    survives the first stage."""
    n = binv.shape[0]
    m = rows.size
    noise = np.zeros(m)
    col = np.empty(m)
    for i in range(m):
        r = rows[i]
        big = 0.0
        for k in range(n):
            v = abs(binv[r, k])
            if v > big:
                big = v
        noise[i] = big
        col[i] = rhs[r]
    keep = _tied(col, a, noise * qnorm, tie_rtol)
    rows, a, noise = rows[keep], a[keep], noise[keep]
    for i in range(rows.size):
        if rows[i] == prefer:
            return prefer
    k = 0
    while rows.size > 1 and k < n:
        cut = False
        for c in range(k, n):
            col = np.empty(rows.size)
            for i in range(rows.size):
                col[i] = binv[rows[i], c]
            tied = _tied(col, a, noise, tie_rtol)
            if not tied.all():
                rows, a, noise = rows[tied], a[tied], noise[tied]
                k = c + 1
                cut = True
                break
        if not cut:
            break
    return rows[0]


@njit(cache=True)
def pivots(M, q, d, pivot_tol, max_pivots, qnorm, tie_rtol):
    """Lemke's pivots from the artificial basis (covering ``d``) until z0 leaves, the
    budget runs out, a secondary ray or a non-finite pivot row. Returns (binv, rhs, basis,
    end, pivots, entering): the tableau [B^{-1} | B^{-1} q], the variable basic in each
    row (w: 0..n−1, z: n..2n−1, z0: 2n), one of DONE/MAX_ITER/RAY/FAILED, the pivots
    made and the variable that found no pivot (RAY)."""
    n = q.size
    z0 = 2 * n
    binv = np.eye(n)
    rhs = q.copy()
    MT = np.ascontiguousarray(M.T)  # (row i: M[:, i], contiguous for BLAS)
    basis = np.arange(n)
    a = -d.copy()
    r = lexmin_row(binv, rhs, np.arange(n), d.copy(), -1, qnorm, tie_rtol)
    entering = z0
    it = 0
    while True:
        if it >= max_pivots:
            return binv, rhs, basis, MAX_ITER, it, entering
        piv = a[r]
        for k in range(n):
            binv[r, k] /= piv
        rhs[r] /= piv
        for i in range(n):
            if i != r and a[i] != 0.0:
                f = a[i]
                for k in range(n):
                    binv[i, k] -= f * binv[r, k]
                rhs[i] -= f * rhs[r]
        it += 1
        leaving = basis[r]
        basis[r] = entering
        if leaving == z0:
            return binv, rhs, basis, DONE, it, entering
        ok = np.isfinite(rhs[r])
        for k in range(n):
            ok = ok and np.isfinite(binv[r, k])
        if not ok:
            return binv, rhs, basis, FAILED, it, entering
        if leaving < n:  # w left: z of the same index enters, column −B^{-1} M[:, i]
            entering = leaving + n
            a = -np.dot(binv, MT[leaving])  # (BLAS, as numpy's binv @ M[:, i])
        else:  # z left: w of the same index enters, column B^{-1} e_i
            entering = leaving - n
            for i in range(n):
                a[i] = binv[i, entering]
        amax = 0.0
        for i in range(n):
            amax = max(amax, abs(a[i]))
        count = 0
        for i in range(n):
            if amax > 0.0 and a[i] > pivot_tol * amax:
                count += 1
        if count == 0:
            return binv, rhs, basis, RAY, it, entering
        rows = np.empty(count, np.int64)
        ar = np.empty(count)
        count = 0
        prefer = -1
        for i in range(n):
            if basis[i] == z0:
                prefer = i
            if amax > 0.0 and a[i] > pivot_tol * amax:
                rows[count] = i
                ar[count] = a[i]
                count += 1
        r = lexmin_row(binv, rhs, rows, ar, prefer, qnorm, tie_rtol)
