"""The compiled kernel of projected Gauss–Seidel with subspace minimisation (PGS-SM).

Morales, Nocedal & Smelyanskiy, "An algorithm for the fast solution of symmetric
linear complementarity problems", Numer. Math. 111 (2008) 251–266. For a symmetric
positive (semi)definite M the LCP ``0 <= z ⟂ w = M z + q >= 0`` is the QP

    minimise f(z) = ½ zᵀ M z + qᵀ z   over z >= 0,

and one cycle of the method is

1. ``k_gs`` projected Gauss–Seidel sweeps (coordinate descent on f: f never rises),
   whose zero set A = {i : z_i = 0} estimates the active set;
2. up to ``k_sm`` subspace steps on the free set F = {i : z_i > 0}: the reduced
   Newton step ``M_FF d_F = −w_F`` (z_A = 0 held), then a projected search
   z ← P(z + α d), α = 1, ½, ¼, … the first with f(P(z + α d)) <= f(z); the rows the
   projection zeroes join A. A full step that no row blocks is the exact minimiser
   on F; one more such step refines it against round-off, and the phase ends.

The stopping test is lcpbench's own (:mod:`lcpbench.solvers.judge`): the natural
residual max |min(z, w)| / max(1, |q|∞) at most ``eps`` (or its round-off floor right
after an exact subspace solve), evaluated on w recomputed from z after each subspace phase (PGS's own test, scaled by
the diagonal, passes iterates that lcpbench's residuals refuse). f never rises, so the cycles converge
as PGS does; once A is right, one subspace step lands on the answer.

Each function is ``@njit(cache=True)``; it is loaded through
:func:`lcpbench.numba_cache.kernel_module`. With NUMBA_DISABLE_JIT=1 it runs as plain
Python (slowly): there is no numpy twin.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: status codes of :func:`pgs_sm`
SOLVED, MAX_ITER, FAILED = 0, 1, 2
#: backtracking halvings of the projected search before the subspace phase gives up
MAX_HALVINGS = 30


@njit(cache=True)
def _residual(M, q, z, w, scale, floor_ulps):
    """w = M z + q in place; (the natural residual max |min(z, w)| / scale, the round-off
    floor floor_ulps · eps · S / scale with S = max_i Σ_j |M_ij z_j| + |q_i|): the units
    and the floor of lcpbench's own test (:func:`lcpbench.solvers.judge.accept_tol`)."""
    n = z.size
    r = 0.0
    size = 0.0
    for i in range(n):
        acc = q[i]
        mag = abs(q[i])
        for j in range(n):
            t = M[i, j] * z[j]
            acc += t
            mag += abs(t)
        w[i] = acc
        v = abs(min(z[i], acc))
        if v > r:
            r = v
        if mag > size:
            size = mag
    return r / scale, floor_ulps * np.finfo(np.float64).eps * size / scale


@njit(cache=True)
def _change(M, w, z, trial, free, m):
    """f(trial) − f(z) = δᵀw + ½ δᵀMδ, δ = trial − z (nonzero on the free rows only): the
    change itself, not the difference of two values of f, which round-off swamps near
    the answer."""
    lin = 0.0
    quad = 0.0
    for a in range(m):
        i = free[a]
        di = trial[i] - z[i]
        if di == 0.0:
            continue
        lin += di * w[i]
        acc = 0.5 * M[i, i] * di
        for b in range(a):
            acc += M[i, free[b]] * (trial[free[b]] - z[free[b]])
        quad += di * acc
    return lin + quad


@njit(cache=True)
def _sweeps(M, q, z, w, inv_diag, count):
    """``count`` projected Gauss–Seidel sweeps in place (w kept current by columns)."""
    n = z.size
    for _ in range(count):
        for i in range(n):
            new = z[i] - w[i] * inv_diag[i]
            if new < 0.0:
                new = 0.0
            d = new - z[i]
            if d != 0.0:
                z[i] = new
                for k in range(n):
                    w[k] += d * M[k, i]


@njit(cache=True)
def _cholesky(A, m):
    """The lower Cholesky factor of A[:m, :m] in place; False if not positive definite."""
    for j in range(m):
        s = A[j, j]
        for k in range(j):
            s -= A[j, k] * A[j, k]
        if not s > 0.0:
            return False
        s = np.sqrt(s)
        A[j, j] = s
        for i in range(j + 1, m):
            t = A[i, j]
            for k in range(j):
                t -= A[i, k] * A[j, k]
            A[i, j] = t / s
    return True


@njit(cache=True)
def _cho_solve(L, m, b):
    """Solve (L Lᵀ) x = b for the first m entries of b, in place."""
    for i in range(m):
        t = b[i]
        for k in range(i):
            t -= L[i, k] * b[k]
        b[i] = t / L[i, i]
    for i in range(m - 1, -1, -1):
        t = b[i]
        for k in range(i + 1, m):
            t -= L[k, i] * b[k]
        b[i] = t / L[i, i]


@njit(cache=True)
def _subspace(M, q, z, w, k_sm):
    """Up to ``k_sm`` subspace steps with a projected search (module note, step 2).

    Returns (steps taken, whether one was a full unblocked step: F's exact minimiser).
    """
    n = z.size
    free = np.empty(n, np.int64)
    L = np.empty((n, n))
    d = np.empty(n)
    trial = np.empty(n)
    steps = 0
    exact = False
    for _ in range(k_sm):
        m = 0
        for i in range(n):
            if z[i] > 0.0:
                free[m] = i
                m += 1
        if m == 0:
            break
        for a in range(m):
            for b in range(a + 1):
                L[a, b] = M[free[a], free[b]]
            d[a] = -w[free[a]]
        if not _cholesky(L, m):
            break  # M_FF singular: leave it to the sweeps
        _cho_solve(L, m, d)
        alpha = 1.0
        accepted = False
        blocked = False
        for _h in range(MAX_HALVINGS):
            trial[:] = z
            blocked = False
            for a in range(m):
                v = z[free[a]] + alpha * d[a]
                if v <= 0.0:
                    v = 0.0
                    blocked = True
                trial[free[a]] = v
            if _change(M, w, z, trial, free, m) <= 0.0:
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            break
        # w += M (trial − z), then z = trial
        for a in range(m):
            i = free[a]
            dz = trial[i] - z[i]
            if dz != 0.0:
                for k in range(n):
                    w[k] += dz * M[k, i]
                z[i] = trial[i]
        steps += 1
        if alpha == 1.0 and not blocked:
            if exact:
                break  # the refinement step is done
            exact = True
    return steps, exact


@njit(cache=True)
def pgs_sm(M, q, z, eps, max_cycles, k_gs, k_sm, floor_ulps):
    """PGS-SM on the LCP (M, q) from ``z`` (>= 0, updated in place); it stops where the
    natural residual max |min(z, w)| / max(1, |q|∞) is at most ``eps``, or at most its
    round-off floor (:func:`_residual`) after an exact subspace solve.

    Returns (status, cycles, sweeps, subspace steps, residual, w).
    """
    n = z.size
    inv_diag = np.empty(n)
    scale = 1.0
    for i in range(n):
        inv_diag[i] = 1.0 / M[i, i]
        scale = max(scale, abs(q[i]))
    w = np.empty(n)
    res, floor = _residual(M, q, z, w, scale, floor_ulps)
    sweeps = 0
    steps = 0
    cycles = 0
    # every answer ends a subspace phase: a start or a PGS iterate within eps in these
    # units can still be far from the answer in the contact step's own (the gaps of the
    # walled rows against their reactions)
    while cycles < max_cycles:
        cycles += 1
        _sweeps(M, q, z, w, inv_diag, k_gs)
        sweeps += k_gs
        res, floor = _residual(M, q, z, w, scale, floor_ulps)
        if not np.isfinite(res):
            return FAILED, cycles, sweeps, steps, res, w
        taken, exact = _subspace(M, q, z, w, k_sm)
        steps += taken
        res, floor = _residual(M, q, z, w, scale, floor_ulps)
        if not np.isfinite(res):
            return FAILED, cycles, sweeps, steps, res, w
        # the floor only after an exact subspace solve: a PGS iterate at the floor's
        # size is not yet the answer (its rows' errors are far above round-off)
        if res <= eps or (exact and res <= floor):
            return SOLVED, cycles, sweeps, steps, res, w
    return MAX_ITER, cycles, sweeps, steps, res, w
