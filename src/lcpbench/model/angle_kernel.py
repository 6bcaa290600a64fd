"""The QP of one SQP step in the link angles α, in O(N) per active-set change, compiled.

The step of :mod:`lcpbench.model.angle_step` is the QP

    minimise   ½ dᵀ B d + ∇Eᵀ d
    subject to y_N + a Σ cos α_k d_k = 0                       (closure, if pinned)
               side_r (limit_r − y_{k_r} − a Σ_{j<k_r} cos α_j d_j) ≥ 0   (the walls)

with B = K + diag(δ), K = Dᵀ diag(k) D tridiagonal (joints couple adjacent links) and
δ the diagonal curvature of the loads, closure and walls (each a sum of functions of one
α_j). Only the constraints' Jacobians are dense (prefix sums). Lifting the node height
increments v_j (j = 1 … N, v_0 = 0) into the unknowns makes them banded:

    v_{k+1} − v_k − a cos α_k d_k = 0     (multiplier ν_k; regular at the vertical),

the closure is the fixed value v_N = −y_N and a wall at its bound the fixed value
v_k = limit − y_k. Per link the unknowns are interleaved (d_k, ν_k, v_{k+1}); the rows

    (B d)_k + a cos α_k ν_k = −∂_k E,   v_{k+1} − v_k − a cos α_k d_k = 0,
    ν_j − ν_{j−1} = 0   (v_j free; ν_N = 0),   v_j = fixed value   (v_j fixed)

have 3 bands either side and are solved by the banded LU of
:func:`lcpbench.linalg.band_lu_kernel.band_solve`: O(N). The multiplier of a fixed v_j
is its row's residual ν_j − ν_{j−1} =: R_j: the closure's λ = R_N, a wall's
μ = −side · R_k.

The walls are handled by the dual active-set method of Goldfarb and Idnani (Math.
Prog. 27, 1983) with the KKT solves above in place of B⁻¹: started from the last step's
active walls (those whose multipliers are negative dropped one by one), each
iteration adds the most violated wall or drops one whose multiplier reaches zero, one
O(N) factorisation each. It needs the QP convex on the closure's tangent space:
:func:`convexify` checks that by the inertia of the tridiagonal B (its LDLᵀ pivots,
Sylvester) and of the closure's Schur complement (Haynsworth), and where it fails
adds a shift σ I, the smallest of a geometric sequence that passes. A shifted step is not Newton's: the
SQP's quadratic rate holds only where the exact Hessian is positive on the closure's
tangent (as near a stable answer with its walls); elsewhere the steps are descent
steps of the merit function, with a linear rate. Loaded through
:func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.band_lu_kernel import band_solve
from ..thresholds import ANGLE_SHIFT_GROWTH, ANGLE_SHIFT_START, ANGLE_SHIFT_TRIES

#: the step's outcome codes
OK, SINGULAR, INFEASIBLE, NO_END = range(4)
#: bands of the interleaved KKT matrix either side of the diagonal
BANDS = 3


@njit(cache=True)
def hessian_bands(alpha, a, jl, jr, k, W, lam, mu, node, side):
    """(diag K, off K, δ): the tridiagonal K = Dᵀ diag(k) D (``off[i]`` = K[i, i+1]) and
    the diagonal δ_j = a sin α_j (W_j + λ − Σ_{r: k_r > j} μ_r side_r) of ∇²(E − λc − μ·g).
    Joint i couples links ``jl[i]`` (−1: a clamp) and ``jr[i]`` = ``jl[i]`` + 1."""
    n = alpha.size
    dk, off, dg = np.zeros(n), np.zeros(max(n - 1, 0)), np.empty(n)
    for i in range(jr.size):
        r, left = jr[i], jl[i]
        dk[r] += k[i]
        if left >= 0:
            dk[left] += k[i]
            off[left] -= k[i]
    push = np.zeros(n + 1)  # Σ μ side at each node
    for r in range(node.size):
        push[node[r]] += mu[r] * side[r]
    tail = 0.0  # Σ over nodes > j
    for j in range(n - 1, -1, -1):
        tail += push[j + 1]
        dg[j] = a * np.sin(alpha[j]) * (W[j] + lam - tail)
    return dk, off, dg


@njit(cache=True)
def _ldl_inertia(diag, off, rhs):
    """(negative pivots, smallest |pivot| over the largest, rhsᵀ T⁻¹ rhs) of the symmetric
    tridiagonal T (LDLᵀ without pivoting: its pivots' signs are T's inertia)."""
    n = diag.size
    piv, z = np.empty(n), np.empty(n)
    neg, small, big = 0, np.inf, 0.0
    for i in range(n):
        if i == 0:
            piv[i], z[i] = diag[i], rhs[i]
        else:
            m = off[i - 1] / piv[i - 1]
            piv[i] = diag[i] - m * off[i - 1]
            z[i] = rhs[i] - m * z[i - 1]
        if piv[i] < 0.0:
            neg += 1
        small, big = min(small, abs(piv[i])), max(big, abs(diag[i]))
        if piv[i] == 0.0 or not np.isfinite(piv[i]):
            return n, 0.0, 0.0
    s = 0.0
    for i in range(n):
        s += z[i] * z[i] / piv[i]
    return neg, small / max(big, 1e-300), s


@njit(cache=True)
def convex_on_closure(diag, off, c, pinned):
    """Whether the QP with the tridiagonal B is strictly convex on the closure's tangent
    (cᵀ d = 0 where ``pinned``): In([B c; cᵀ 0]) = In(B) + In(−cᵀB⁻¹c), so B positive
    definite, or B with one negative eigenvalue and cᵀB⁻¹c < 0. A pivot below 1e-13
    of the largest diagonal entry counts as singular."""
    neg, small, s = _ldl_inertia(diag, off, c)
    if small < 1e-13:
        return False
    if not pinned:
        return neg == 0
    return (neg == 0 and s > 0.0) or (neg == 1 and s < 0.0)


@njit(cache=True)
def convexify(dk, off, dg, c, pinned):
    """(diag of B, σ): B = K + diag(δ) + σ I with the first σ of 0, σ₀, σ₀ g, σ₀ g², …
    (σ₀ = :data:`~lcpbench.thresholds.ANGLE_SHIFT_START` × the largest |K_jj|, |δ_j|;
    g = :data:`~lcpbench.thresholds.ANGLE_SHIFT_GROWTH`) at which the QP is strictly
    convex on the closure's tangent (:func:`convex_on_closure`); σ = −1 where none was."""
    n = dk.size
    d = dk + dg
    top = 0.0
    for j in range(n):
        top = max(top, abs(dk[j]), abs(dg[j]))
    sigma = 0.0
    for t in range(ANGLE_SHIFT_TRIES + 1):
        for j in range(n):
            d[j] = dk[j] + dg[j] + sigma
        if convex_on_closure(d, off, c, pinned):
            return d, sigma
        sigma = ANGLE_SHIFT_START * top if t == 0 else sigma * ANGLE_SHIFT_GROWTH
    return d, -1.0


@njit(cache=True)
def kkt_solve(bd, off, c, fixed, value, rhs_d, rhs_v):
    """(ok, d, ν, v, R): the lifted KKT system with the rows of the module's docstring,
    (B d)_k + c_k ν_k = ``rhs_d[k]``, v_{k+1} − v_k − c_k d_k = 0, and per node j = 1 … N
    ν_j − ν_{j−1} = ``rhs_v[j]`` where v_j is free, v_j = ``value[j]`` where ``fixed[j]``
    (index 0 unused); R_j = ν_j − ν_{j−1} − ``rhs_v[j]`` (the fixed rows' multipliers)."""
    n = bd.size
    m, kl = 3 * n, BANDS
    ab = np.zeros((m, 3 * kl + 1))
    rhs = np.zeros((m, 1))
    for k in range(n):
        r = 3 * k  # d_k
        ab[r, kl] = bd[k]
        if k > 0:
            ab[r, kl - 3] = off[k - 1]
        if k < n - 1:
            ab[r, kl + 3] = off[k]
        ab[r, kl + 1] = c[k]
        rhs[r, 0] = rhs_d[k]
        r = 3 * k + 1  # ν_k: v_{k+1} − v_k − c_k d_k = 0
        ab[r, kl + 1] = 1.0
        if k > 0:
            ab[r, kl - 2] = -1.0
        ab[r, kl - 1] = -c[k]
        r = 3 * k + 2  # v_{k+1}
        j = k + 1
        if fixed[j]:
            ab[r, kl] = 1.0
            rhs[r, 0] = value[j]
        else:
            if j < n:
                ab[r, kl + 2] = 1.0  # ν_j
            ab[r, kl - 1] = -1.0  # ν_{j−1}
            rhs[r, 0] = rhs_v[j]
    d, nu, v, R = np.empty(n), np.empty(n), np.zeros(n + 1), np.zeros(n + 1)
    if not band_solve(ab, kl, kl, rhs):
        return False, d, nu, v, R
    for k in range(n):
        d[k], nu[k], v[k + 1] = rhs[3 * k, 0], rhs[3 * k + 1, 0], rhs[3 * k + 2, 0]
    for j in range(1, n + 1):
        R[j] = (nu[j] if j < n else 0.0) - nu[j - 1] - rhs_v[j]
    return True, d, nu, v, R


@njit(cache=True)
def _gap(r, y, v, node, side, limit):
    """side_r (limit_r − y_k − v_k): wall r's linearised gap after the step."""
    j = node[r]
    return side[r] * (limit[r] - y[j] - v[j])


@njit(cache=True)
def qp_step(alpha, a, jl, jr, k, W, grad, y, pinned, node, side, limit, lam, mu, gap_tol):
    """(code, d, λ', μ', σ, changes): the step d of the SQP at α (the QP of the module's
    docstring with B from the multipliers ``lam`` (one value, read where ``pinned``) and
    ``mu`` of the last step), the step's closure and wall multipliers, the shift σ of
    :func:`convexify` and the number of active-set changes. ``grad``: ∇E at α; ``y``:
    the node heights (N + 1); ``node``/``side``/``limit`` per wall row: its node (1 … N),
    +1 an upper and −1 a lower wall, its height. The last step's walls with μ > 0 start
    the active set. A wall counts as violated where its gap is below −``gap_tol``."""
    n, nw = alpha.size, node.size
    dk, off, dg = hessian_bands(alpha, a, jl, jr, k, W, lam[0] if pinned else 0.0, mu, node,
                                side)
    c = a * np.cos(alpha)
    lam_out, u = np.zeros(1 if pinned else 0), np.zeros(nw)
    bd, sigma = convexify(dk, off, dg, c, pinned)
    if sigma < 0.0:
        return SINGULAR, np.zeros(n), lam_out, u, sigma, 0
    fixed, value, zero_v = np.zeros(n + 1, np.bool_), np.zeros(n + 1), np.zeros(n + 1)
    zero_d, zero_val, minus_grad = np.zeros(n), np.zeros(n + 1), -grad
    if pinned:
        fixed[n], value[n] = True, -y[n]
    act = np.zeros(nw, np.bool_)
    for r in range(nw):
        if mu[r] > 0.0 and not fixed[node[r]]:
            act[r], fixed[node[r]], value[node[r]] = True, True, limit[r] - y[node[r]]
    changes = 0
    while True:  # the warm set's walls with negative multipliers dropped, most negative first
        ok, d, nu, v, R = kkt_solve(bd, off, c, fixed, value, minus_grad, zero_v)
        if not ok:
            return SINGULAR, d, lam_out, u, sigma, changes
        worst, low = -1, 0.0
        for r in range(nw):
            if act[r]:
                u[r] = -side[r] * R[node[r]]
                if u[r] < low:
                    worst, low = r, u[r]
        if worst < 0:
            break
        act[worst], fixed[node[worst]], u[worst] = False, False, 0.0
        changes += 1
    lam_now = R[n] if pinned else 0.0
    for _ in range(10 * nw + 50):
        p, low = -1, -gap_tol
        for r in range(nw):
            if not act[r]:
                s = _gap(r, y, v, node, side, limit)
                if s < low:
                    p, low = r, s
        if p < 0:  # the QP's answer: once more from its active set, to round-off
            ok, d2, nu2, v2, R2 = kkt_solve(bd, off, c, fixed, value, minus_grad, zero_v)
            good = ok
            for r in range(nw):
                u2 = -side[r] * R2[node[r]] if act[r] else 0.0
                if ok and (u2 < -1e-9 * (abs(u[r]) + 1e-300)
                           or (not act[r] and _gap(r, y, v2, node, side, limit) < -gap_tol)):
                    good = False
            if good:
                d, v, lam_now = d2, v2, R2[n] if pinned else 0.0
                for r in range(nw):
                    u[r] = max(-side[r] * R2[node[r]], 0.0) if act[r] else 0.0
            if pinned:
                lam_out[0] = lam_now
            return OK, d, lam_out, u, sigma, changes
        up = 0.0
        rhs_v = np.zeros(n + 1)
        rhs_v[node[p]] = -side[p]
        while True:  # Goldfarb-Idnani: move toward wall p, dropping walls whose μ reaches 0
            ok, z, nz, zv, Rz = kkt_solve(bd, off, c, fixed, zero_val, zero_d, rhs_v)
            if not ok:
                return SINGULAR, d, lam_out, u, sigma, changes
            npz = -side[p] * zv[node[p]]
            t1 = -_gap(p, y, v, node, side, limit) / npz if npz > 0.0 else np.inf
            t2, block = np.inf, -1
            for r in range(nw):
                if act[r]:
                    w = -side[r] * Rz[node[r]]
                    if w < 0.0 and -u[r] / w < t2:
                        t2, block = -u[r] / w, r
            t = min(t1, t2)
            if not np.isfinite(t):
                return INFEASIBLE, d, lam_out, u, sigma, changes
            for j in range(n):
                d[j] += t * z[j]
            for j in range(n + 1):
                v[j] += t * zv[j]
            for r in range(nw):
                if act[r]:
                    u[r] += t * (-side[r] * Rz[node[r]])
            lam_now += t * Rz[n]
            up += t
            changes += 1
            if t1 <= t2:
                act[p], fixed[node[p]], value[node[p]], u[p] = True, True, limit[p] - y[node[p]], up
                break
            act[block], fixed[node[block]], u[block] = False, False, 0.0
    return NO_END, d, lam_out, u, sigma, changes
