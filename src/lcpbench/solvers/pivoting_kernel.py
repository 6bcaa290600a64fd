"""Block principal pivoting from a support, compiled: a warm start for any square LCP.

The LCP w = M z + q, 0 <= z ⟂ w >= 0. A support S (the unknowns z_i that may be > 0)
fixes a candidate: z_S = −M_SS⁻¹ q_S, z = 0 off S, w = M z + q (so w_S = 0). The
candidate is the answer when z_S >= 0 and w off S >= 0. Otherwise the infeasible
unknowns change side (Júdice & Pires, *Computers Ops Res* 21, 1994: every infeasible
one at once, then, after :data:`BLOCK_TRIES` changes without fewer infeasibles, one at
a time, the lowest index first: Murty's rule). Started from the support of a nearby
problem's answer (the last step of a frictional path, whose stick/slide/separate
pattern mostly holds), it takes a few linear solves of the support's size. No
finiteness result holds for a matrix that is not a P-matrix (the frictional step's M
is not): it stops at a budget, or at a singular M_SS, and says so; the caller falls
back to a method that is finite (Lemke) and judges any answer by its own residual.

Each function is ``@njit(cache=True)``; with NUMBA_DISABLE_JIT=1 they run as plain
Python. :func:`lcpbench.model.friction_driver.StepLemke` calls it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: block changes without fewer infeasible unknowns before one change at a time
BLOCK_TRIES = 3
#: the ends of :func:`support_pivots`: a feasible support, the budget, a singular M_SS
DONE, MAX_ITER, SINGULAR = 0, 1, 2


@njit(cache=True)
def lu_solve(A, b, pivot_rtol):
    """x with A x = b by Gaussian elimination with partial pivoting (A, b overwritten);
    ok False where a pivot is at most ``pivot_rtol`` of A's largest entry (singular to
    that tolerance)."""
    k = b.size
    big = 0.0
    for i in range(k):
        for j in range(k):
            big = max(big, abs(A[i, j]))
    x = np.zeros(k)
    if k == 0:
        return x, True
    if big == 0.0:
        return x, False
    for c in range(k):
        p = c
        for i in range(c + 1, k):
            if abs(A[i, c]) > abs(A[p, c]):
                p = i
        if abs(A[p, c]) <= pivot_rtol * big:
            return x, False
        if p != c:
            for j in range(k):
                A[c, j], A[p, j] = A[p, j], A[c, j]
            b[c], b[p] = b[p], b[c]
        for i in range(c + 1, k):
            f = A[i, c] / A[c, c]
            if f != 0.0:
                for j in range(c + 1, k):
                    A[i, j] -= f * A[c, j]
                b[i] -= f * b[c]
    for i in range(k - 1, -1, -1):
        acc = b[i]
        for j in range(i + 1, k):
            acc -= A[i, j] * x[j]
        x[i] = acc / A[i, i]
    return x, True


@njit(cache=True)
def support_pivots(M, q, support, max_changes, feas_rtol, pivot_rtol, lstsq_rcond):
    """Block principal pivoting from ``support`` (bool per unknown). Returns (z, w,
    support, end, solves): the last candidate, its support, DONE (no unknown infeasible
    beyond ``feas_rtol`` · max(1, |q|, |z|); the few within it clipped to 0),
    MAX_ITER (``max_changes`` supports tried) or SINGULAR (M_SS singular to
    ``pivot_rtol`` and ``lstsq_rcond`` <= 0), and the linear solves made. Where M_SS
    is singular to ``pivot_rtol`` the candidate is its least-squares solution of the
    least norm (singular values below ``lstsq_rcond`` of the largest cut): a
    consistent singular system has many answers, any of them the LCP's if feasible."""
    n = q.size
    S = support.copy()
    z = np.zeros(n)
    w = q.copy()
    best, stalled = n + 1, 0
    qmax = 0.0
    for i in range(n):
        qmax = max(qmax, abs(q[i]))
    for it in range(1, max_changes + 1):
        idx = np.flatnonzero(S)
        k = idx.size
        A = np.empty((k, k))
        b = np.empty(k)
        for a in range(k):
            b[a] = -q[idx[a]]
            for c in range(k):
                A[a, c] = M[idx[a], idx[c]]
        x, ok = lu_solve(A.copy(), b.copy(), pivot_rtol)
        if not ok:  # M_SS singular (a run of sticking nodes: T per node indeterminate):
            # the least-squares answer of the least norm, kept only if it is feasible
            if k == 0 or lstsq_rcond <= 0.0:
                return z, w, S, SINGULAR, it
            x = np.linalg.lstsq(A, b, lstsq_rcond)[0]
        z[:] = 0.0
        zmax = 0.0
        for a in range(k):
            z[idx[a]] = x[a]
            zmax = max(zmax, abs(x[a]))
        w = M @ z + q
        eps = feas_rtol * max(1.0, qmax, zmax)
        bad = 0
        first = -1
        for i in range(n):
            if (S[i] and z[i] < -eps) or (not S[i] and w[i] < -eps):
                bad += 1
                if first < 0:
                    first = i
        if bad == 0:
            for i in range(n):
                if z[i] < 0.0:
                    z[i] = 0.0
                if w[i] < 0.0:
                    w[i] = 0.0
            return z, w, S, DONE, it
        if bad < best:
            best, stalled = bad, 0
        else:
            stalled += 1
        if stalled < BLOCK_TRIES:
            for i in range(n):
                if (S[i] and z[i] < -eps) or (not S[i] and w[i] < -eps):
                    S[i] = not S[i]
        else:
            S[first] = not S[first]
    return z, w, S, MAX_ITER, max_changes
