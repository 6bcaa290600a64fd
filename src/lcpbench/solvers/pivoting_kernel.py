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
is not): it stops at a budget, at a singular M_SS, or where it comes back to a support
it has left in the same state (a cycle: the rule is deterministic, so it would go round
to the budget), and says so; the caller falls back to a method that is finite (Lemke)
and judges any answer by its own residual.

Each function is ``@njit(cache=True)``; with NUMBA_DISABLE_JIT=1 they run as plain
Python. :func:`lcpbench.model.friction_driver.StepLemke` calls it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: block changes without fewer infeasible unknowns before one change at a time
BLOCK_TRIES = 3
#: the ends of :func:`support_pivots`: a feasible support, the budget, a singular M_SS, a
#: cycle (a support and state seen before: the budget would be spent going round)
DONE, MAX_ITER, SINGULAR, CYCLE = 0, 1, 2, 3


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
def singleton_solve(A, b, pivot_rtol, lstsq_rcond):
    """x with A x = b (A square), its singleton rows and columns eliminated first (the
    presolve of LP codes): a row with one nonzero among the unknowns left fixes that
    unknown; a column with one nonzero among the rows left is solved last from that row.
    What remains is solved by :func:`lu_solve`, and where that is singular to
    ``pivot_rtol`` (and ``lstsq_rcond`` > 0) by its least-squares solution of the least
    norm (singular values below ``lstsq_rcond`` of the largest cut). Both are exact on a
    nonsingular A; they spare the dense solve the unknowns a row or column fixes alone
    (the frictional step's pairs without a normal force: β = 0 by their cone row, λ = |s|
    by their slip row). ok False where A is singular and no least squares is asked."""
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
    row_on = np.ones(k, np.bool_)
    col_on = np.ones(k, np.bool_)
    r = b.copy()
    defer_row = np.empty(k, np.int64)
    defer_col = np.empty(k, np.int64)
    nd = 0
    changed = True
    while changed:
        changed = False
        for i in range(k):  # a singleton row fixes its unknown
            if not row_on[i]:
                continue
            cnt, c = 0, -1
            for j in range(k):
                if col_on[j] and A[i, j] != 0.0:
                    cnt += 1
                    c = j
                    if cnt > 1:
                        break
            if cnt == 1 and abs(A[i, c]) > pivot_rtol * big:
                x[c] = r[i] / A[i, c]
                for ii in range(k):
                    if row_on[ii]:
                        r[ii] -= A[ii, c] * x[c]
                row_on[i], col_on[c], changed = False, False, True
        for j in range(k):  # a singleton column is solved last, from its row
            if not col_on[j]:
                continue
            cnt, rr = 0, -1
            for i in range(k):
                if row_on[i] and A[i, j] != 0.0:
                    cnt += 1
                    rr = i
                    if cnt > 1:
                        break
            if cnt == 1 and abs(A[rr, j]) > pivot_rtol * big:
                defer_row[nd], defer_col[nd] = rr, j
                nd += 1
                row_on[rr], col_on[j], changed = False, False, True
    rows, cols = np.flatnonzero(row_on), np.flatnonzero(col_on)
    m = rows.size
    if m:
        core = np.empty((m, m))
        rhs = np.empty(m)
        for a in range(m):
            rhs[a] = r[rows[a]]
            for c in range(m):
                core[a, c] = A[rows[a], cols[c]]
        y, ok = lu_solve(core.copy(), rhs.copy(), pivot_rtol)
        if not ok:
            if lstsq_rcond <= 0.0:
                return x, False
            y = np.linalg.lstsq(core, rhs, lstsq_rcond)[0]
        for c in range(m):
            x[cols[c]] = y[c]
    for d in range(nd - 1, -1, -1):
        rr, c = defer_row[d], defer_col[d]
        acc = b[rr]
        for j in range(k):
            if j != c:
                acc -= A[rr, j] * x[j]
        x[c] = acc / A[rr, c]
    return x, True


@njit(cache=True)
def support_pivots(M, q, support, max_changes, feas_rtol, pivot_rtol, lstsq_rcond):
    """Block principal pivoting from ``support`` (bool per unknown). Returns (z, w,
    support, end, solves): the last candidate, its support, DONE (no unknown infeasible
    beyond ``feas_rtol`` · max(1, |q|, |z|); the few within it clipped to 0),
    MAX_ITER (``max_changes`` supports tried), SINGULAR (M_SS singular to
    ``pivot_rtol`` and ``lstsq_rcond`` <= 0) or CYCLE (the walk is back at a support
    it started from before with the same fewest infeasibles and the same rule: every
    support after it repeats, none DONE, so the budget's end is known; the walk ends
    there, where it would have ended MAX_ITER), and the linear solves made. Where M_SS
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
    # the state each solve starts from: its support, the fewest infeasibles so far and
    # the number of changes without fewer (only whether it is below BLOCK_TRIES counts)
    seen = np.empty((max(max_changes, 0), n), np.bool_)
    seen_best = np.empty(max(max_changes, 0), np.int64)
    seen_rule = np.empty(max(max_changes, 0), np.int64)
    for it in range(1, max_changes + 1):
        rule = min(stalled, BLOCK_TRIES)
        for j in range(it - 1):
            if seen_best[j] == best and seen_rule[j] == rule:
                same = True
                for i in range(n):
                    if seen[j, i] != S[i]:
                        same = False
                        break
                if same:
                    return z, w, S, CYCLE, it - 1
        seen[it - 1, :] = S
        seen_best[it - 1], seen_rule[it - 1] = best, rule
        idx = np.flatnonzero(S)
        k = idx.size
        A = np.empty((k, k))
        b = np.empty(k)
        for a in range(k):
            b[a] = -q[idx[a]]
            for c in range(k):
                A[a, c] = M[idx[a], idx[c]]
        # M_SS singular (a run of sticking nodes: T per node indeterminate): the
        # least-squares answer of the least norm, kept only if it is feasible
        x, ok = singleton_solve(A, b, pivot_rtol, lstsq_rcond)
        if not ok:
            return z, w, S, SINGULAR, it
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


@njit(cache=True)
def symmetric_active_set(M, q, max_changes, feas_rtol, pivot_rtol):
    """The LCP of a symmetric positive semidefinite M — the convex QP min ½ zᵀMz + qᵀz
    over z >= 0 — by the primal active set of Lawson & Hanson (*Solving Least Squares
    Problems*, 1974, ch. 23, NNLS): from z = 0, the unknown with the most negative w
    joins the free set F; z_F = −M_FF⁻¹ q_F, and where that makes some z < 0 the step
    from the last z stops at the first that reaches 0, which leaves F. Each change
    lowers the QP's objective, so no set repeats (M_FF positive definite). Returns
    (z, w, end, solves): DONE (no w below −``feas_rtol`` · max(1, |q|, |z|)),
    MAX_ITER (``max_changes`` solves) or SINGULAR (M_FF singular to ``pivot_rtol``)."""
    n = q.size
    z = np.zeros(n)
    F = np.zeros(n, np.bool_)
    qmax = 0.0
    for i in range(n):
        qmax = max(qmax, abs(q[i]))
    solves = 0
    while True:
        w = M @ z + q
        zmax = 0.0
        for i in range(n):
            zmax = max(zmax, abs(z[i]))
        eps = feas_rtol * max(1.0, qmax, zmax)
        j = -1
        for i in range(n):
            if not F[i] and w[i] < -eps and (j < 0 or w[i] < w[j]):
                j = i
        if j < 0:
            for i in range(n):
                w[i] = max(w[i], 0.0)
            return z, w, DONE, solves
        F[j] = True
        while True:
            if solves >= max_changes:
                return z, w, MAX_ITER, solves
            idx = np.flatnonzero(F)
            k = idx.size
            A = np.empty((k, k))
            b = np.empty(k)
            for a in range(k):
                b[a] = -q[idx[a]]
                for c in range(k):
                    A[a, c] = M[idx[a], idx[c]]
            y, ok = lu_solve(A, b, pivot_rtol)
            solves += 1
            if not ok:
                return z, w, SINGULAR, solves
            share, block = 1.0, -1
            for a in range(k):
                i = idx[a]
                if y[a] <= 0.0 and z[i] / (z[i] - y[a]) < share:
                    share, block = z[i] / (z[i] - y[a]), i
            for a in range(k):
                i = idx[a]
                z[i] += share * (y[a] - z[i])
            if block < 0:
                break
            z[block] = 0.0  # the first to reach 0 leaves F, with any other at 0
            for a in range(k):
                i = idx[a]
                if z[i] <= 0.0:
                    z[i] = 0.0
                    F[i] = False


@njit(cache=True)
def natural_residuals(M, q, z):
    """lcpbench's residuals of a candidate z of the LCP (M, q), in one pass after
    w = M z + q (:func:`lcpbench.solvers.base.lcp_residuals` documents them; no matrix
    temporaries). Returns (natural, min_z, min_w, complementarity, w): max|min(z, w)|,
    min(z, 0), min(w, 0) and |zᵀw|, each but min_z divided by max(1, |q|_∞); a NaN in
    z or w makes each one it enters NaN (as numpy's minimum and max do)."""
    n = q.size
    w = M @ z
    scale = 1.0
    for i in range(n):
        w[i] += q[i]
        if abs(q[i]) > scale:
            scale = abs(q[i])
    natural, min_z, min_w = 0.0, 0.0, 0.0
    for i in range(n):
        m = min(z[i], w[i]) if z[i] == z[i] and w[i] == w[i] else np.nan
        if abs(m) > natural or m != m:
            natural = abs(m)
        if z[i] < min_z or z[i] != z[i]:
            min_z = z[i]
        if w[i] < min_w or w[i] != w[i]:
            min_w = w[i]
        if natural != natural and min_z != min_z and min_w != min_w:
            break
    return natural / scale, min_z, min_w / scale, abs(np.dot(z, w)) / scale, w
