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
active walls, improved by up to :data:`GUESSES` primal-dual guesses (Hintermüller, Ito
and Kunisch 2002: walls with negative multipliers out, violated walls in, all at
once), then the walls whose multipliers are negative dropped one by one; each
iteration adds the most violated wall or drops one whose multiplier reaches zero, one
O(N) factorisation each. It needs the QP convex on the face of its active set:
:func:`convex_on_face` counts the negative eigenvalues of that face's KKT matrix in O(N)
(the runs of links between fixed nodes eliminated one after the other), on the face the
solve starts from and on the face of its answer. Where either is not convex, B gets a
shift σ I, the smallest of a geometric sequence that passes (:func:`qp_step`). A shifted
step is not Newton's: the SQP's quadratic rate holds only where the exact Hessian is
positive on the active face (as near a stable answer); elsewhere the steps are descent
steps of the merit function, at a linear rate. Loaded through
:func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.band_lu_kernel import band_solve
from ..thresholds import ANGLE_SHIFT_GROWTH, ANGLE_SHIFT_START, ANGLE_SHIFT_TRIES, SQP_SHORTEST
from .chain_kernel import armijo, energy  # once (numba_cache)

#: the step's outcome codes
OK, SINGULAR, INFEASIBLE, NO_END = range(4)
#: the SQP's outcome codes (:func:`solve_sqp`)
CONVERGED, QP_FAILED, MAX_STEPS = range(3)
#: no link turns by more than this in one SQP step (rad)
STEP_CAP = 0.5
#: bands of the interleaved KKT matrix either side of the diagonal
BANDS = 3
#: primal-dual active-set guesses before the dual active set (each one banded solve)
GUESSES = 64


@njit(cache=True)
def hessian_bands(sines, a, jl, jr, k, W, lam, mu, node, side):
    """(diag K, off K, δ): the tridiagonal K = Dᵀ diag(k) D (``off[i]`` = K[i, i+1]) and
    the diagonal δ_j = a sin α_j (W_j + λ − Σ_{r: k_r > j} μ_r side_r) of ∇²(E − λc − μ·g),
    ``sines``: sin α. Joint i couples links ``jl[i]`` (−1: a clamp) and ``jr[i]`` =
    ``jl[i]`` + 1."""
    n = sines.size
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
        dg[j] = a * sines[j] * (W[j] + lam - tail)
    return dk, off, dg


@njit(cache=True)
def convex_on_face(bd, off, c, fixed):
    """Whether the QP with the tridiagonal B (diagonal ``bd``, ``off``) is strictly convex
    on the face where the node heights with ``fixed`` (per node 0 … N; node 0 always)
    do not move: on each run of links between two fixed nodes Σ c_k d_k = 0.

    The KKT matrix of that face, ordered run by run (the run's d, then its multiplier),
    is block tridiagonal, coupled by one entry of B between runs. Eliminating run after
    run (each run's block M = [T c; cᵀ 0] gives In(T) + In(−cᵀT⁻¹c), Haynsworth, and
    passes −b² (M⁻¹)_ll to the next run's first diagonal entry) counts its negative
    eigenvalues in O(N): the face is convex iff they are as many as the runs' constraints.
    A pivot below 1e-13 of the largest diagonal entry (or such a cᵀT⁻¹c) counts as
    singular: not convex."""
    n = bd.size
    big = 0.0
    for k in range(n):
        big = max(big, abs(bd[k]))
    tiny = 1e-13 * max(big, 1e-300)
    neg, rows, carry, p = 0, 0, 0.0, 0
    while p < n:
        q = p + 1
        while q < n and not fixed[q]:
            q += 1
        piv, z, s, size = 0.0, 0.0, 0.0, 0.0  # the run p … q−1 (links), LDLᵀ in place
        for k in range(p, q):
            if k == p:
                piv, z = bd[k] - carry, c[k]
            else:
                m = off[k - 1] / piv
                piv, z = bd[k] - m * off[k - 1], c[k] - m * z
            if not abs(piv) > tiny or not np.isfinite(piv):
                return False
            if piv < 0.0:
                neg += 1
            s += z * z / piv
            size += z * z / abs(piv)
        inv_last = 1.0 / piv  # (T⁻¹)_ll
        if fixed[q]:  # the run's constraint (q = N: the closure)
            if not abs(s) > 1e-13 * size:
                return False
            rows += 1
            if s > 0.0:
                neg += 1
            x_last = z / piv  # (T⁻¹c)_l
            inv_last -= x_last * x_last / s
        if q < n:
            carry = off[q - 1] * off[q - 1] * inv_last
        p = q
    return neg == rows


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
    ``mu`` of the last step), the step's closure and wall multipliers, the shift σ and
    the number of active-set changes. ``grad``: ∇E at α; ``y``: the node heights
    (N + 1); ``node``/``side``/``limit`` per wall row: its node (1 … N), +1 an upper and
    −1 a lower wall, its height. The last step's walls with μ > 0 start the active set.
    A wall counts as violated where its gap is below −``gap_tol``.

    σ is the first of 0, σ₀, σ₀ g, σ₀ g², … (σ₀ = :data:`~lcpbench.thresholds.ANGLE_SHIFT_START`
    × the largest |K_jj|, |δ_j|; g = :data:`~lcpbench.thresholds.ANGLE_SHIFT_GROWTH`) at
    which B = K + diag(δ) + σ I is convex on the face of the starting active set and on
    the face of the answer's (:func:`convex_on_face`), and the QP was solved."""
    return _qp_step(np.sin(alpha), a * np.cos(alpha), a, jl, jr, k, W, grad, y, pinned, node,
                    side, limit, lam, mu, gap_tol)


@njit(cache=True)
def _qp_step(sines, c, a, jl, jr, k, W, grad, y, pinned, node, side, limit, lam, mu,
             gap_tol):
    """:func:`qp_step` at the α of ``sines`` (sin α) and ``c`` (a cos α), which the SQP
    has from its line search and its gradient (:func:`solve_sqp`)."""
    n, nw = sines.size, node.size
    dk, off, dg = hessian_bands(sines, a, jl, jr, k, W, lam[0] if pinned else 0.0, mu, node,
                                side)
    top = 0.0
    for j in range(n):
        top = max(top, abs(dk[j]), abs(dg[j]))
    bd, sigma, changes = np.empty(n), 0.0, 0
    warm = np.zeros(n + 1, np.bool_)
    warm[n] = pinned
    for r in range(nw):
        if mu[r] > 0.0:
            warm[node[r]] = True
    code = SINGULAR
    d, lam_out, u = np.zeros(n), np.zeros(1 if pinned else 0), np.zeros(nw)
    for t in range(ANGLE_SHIFT_TRIES + 1):
        for j in range(n):
            bd[j] = dk[j] + dg[j] + sigma
        if convex_on_face(bd, off, c, warm):
            code, d, lam_out, u, more, face = _solve_qp(bd, off, c, grad, y, pinned, node,
                                                        side, limit, mu, gap_tol)
            changes += more
            # (the answer's face is the starting one where no wall changed: convex)
            if code == OK and (more == 0 or convex_on_face(bd, off, c, face)):
                return OK, d, lam_out, u, sigma, changes
        sigma = ANGLE_SHIFT_START * top if t == 0 else sigma * ANGLE_SHIFT_GROWTH
    return code if code != OK else SINGULAR, d, lam_out, u, -1.0, changes


@njit(cache=True)
def _solve_qp(bd, off, c, grad, y, pinned, node, side, limit, mu, gap_tol):
    """(code, d, λ', μ', changes, fixed): the QP with the tridiagonal B (:func:`qp_step`)
    and the nodes fixed at its answer (its active set, and the closure)."""
    n, nw = bd.size, node.size
    lam_out, u = np.zeros(1 if pinned else 0), np.zeros(nw)
    fixed, value, zero_v = np.zeros(n + 1, np.bool_), np.zeros(n + 1), np.zeros(n + 1)
    zero_d, zero_val, minus_grad = np.zeros(n), np.zeros(n + 1), -grad
    if pinned:
        fixed[n], value[n] = True, -y[n]
    act = np.zeros(nw, np.bool_)
    for r in range(nw):
        if mu[r] > 0.0 and not fixed[node[r]]:
            act[r], fixed[node[r]], value[node[r]] = True, True, limit[r] - y[node[r]]
    changes = 0
    solved = False  # whether d, ν, v, R are the KKT solve of the present fixed set
    for _ in range(GUESSES):  # primal-dual guesses of the active set: many changes a solve
        ok, d, nu, v, R = kkt_solve(bd, off, c, fixed, value, minus_grad, zero_v)
        if not ok:
            break
        moved = False
        for r in range(nw):
            j = node[r]
            if act[r] and -side[r] * R[j] < 0.0:
                act[r], fixed[j], moved = False, False, True
            elif not act[r] and not fixed[j] and _gap(r, y, v, node, side, limit) < -gap_tol:
                act[r], fixed[j], value[j], moved = True, True, limit[r] - y[j], True
        if not moved:
            solved = True
            break
        changes += 1
    while True:  # the warm set's walls with negative multipliers dropped, most negative first
        if not solved:
            ok, d, nu, v, R = kkt_solve(bd, off, c, fixed, value, minus_grad, zero_v)
            if not ok:
                return SINGULAR, d, lam_out, u, changes, fixed
        solved = False
        worst, low = -1, 0.0
        for r in range(nw):
            if act[r]:
                u[r] = -side[r] * R[node[r]]
                if u[r] < low:
                    worst, low = r, u[r]
        if worst < 0:
            solved = True
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
        if p < 0 and solved:  # no step since the last solve: that is the QP's answer
            if pinned:
                lam_out[0] = lam_now
            return OK, d, lam_out, u, changes, fixed
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
            return OK, d, lam_out, u, changes, fixed
        up, solved = 0.0, False
        rhs_v = np.zeros(n + 1)
        rhs_v[node[p]] = -side[p]
        while True:  # Goldfarb-Idnani: move toward wall p, dropping walls whose μ reaches 0
            ok, z, nz, zv, Rz = kkt_solve(bd, off, c, fixed, zero_val, zero_d, rhs_v)
            if not ok:
                return SINGULAR, d, lam_out, u, changes, fixed
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
                return INFEASIBLE, d, lam_out, u, changes, fixed
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
    return NO_END, d, lam_out, u, changes, fixed


# -- the SQP's outer loop (model.angle_step.solve_in_angles) ---------------------------
@njit(cache=True)
def _state(alpha, a, jl, jr, k, rest, link_load, pinned, node, side, limit):
    """(y, E, |c|, Σ max(−g, 0), max(0, max −g), sin α) at α: the node heights (N + 1),
    the exact energy, the closure c = a Σ sin α (pinned; else 0), the walls' gaps g and
    the sines (the next step's Hessian reads them where α is taken)."""
    n = alpha.size
    sines = np.sin(alpha)
    y = np.empty(n + 1)
    y[0] = 0.0
    for i in range(n):
        y[i + 1] = y[i] + a * sines[i]
    E = energy(alpha, a, jl, jr, k, rest, link_load, sines)
    c = 0.0
    if pinned:
        for i in range(n):
            c += sines[i]
        c = abs(a * c)
    short, worst = 0.0, 0.0
    for r in range(node.size):
        g = side[r] * (limit[r] - y[node[r]])
        if g < 0.0:
            short -= g
        worst = max(worst, -g)
    return y, E, c, short, worst, sines


@njit(cache=True)
def _gradient(alpha, ac, jl, jr, k, rest, W):
    """∇E at α: the springs' torques k(φ − φ*) on their two links, minus a cos α_i W_i
    (``ac``: a cos α)."""
    grad = np.zeros(alpha.size)
    for j in range(jr.size):
        left = alpha[jl[j]] if jl[j] >= 0 else 0.0
        t = k[j] * ((alpha[jr[j]] - left) - rest[j])
        grad[jr[j]] += t
        if jl[j] >= 0:
            grad[jl[j]] -= t
    for i in range(alpha.size):
        grad[i] -= ac[i] * W[i]
    return grad


@njit(cache=True)
def solve_sqp(alpha, a, jl, jr, k, rest, link_load, W, pinned, node, side, limit, lam, mu,
              gap_tol, tol, max_iter, scale, length, feasible):
    """(code, α, step sizes, energies, λ, μ): the SQP in the link angles from ``alpha``
    with the first step's multipliers ``lam`` (closure) and ``mu`` (per wall row).

    Each step: the QP of :func:`qp_step` at α (its step d capped at :data:`STEP_CAP`
    per link), then an Armijo search on the ℓ₁ merit E + ρ(|c| + Σ max(−g, 0)),
    ρ = 2 max|(λ', μ')| + 1e-8 ``scale``/``length`` (``scale`` = EI/ℓ), halving t
    from 1 to SQP_SHORTEST; a step below ``tol`` is taken whole (the merit is round-off
    there). :data:`CONVERGED` after the second full step in a row below ``tol`` with
    the constraints met to ``feasible`` × ``length`` (the active walls' gaps then sit
    at round-off); :data:`QP_FAILED` where a QP failed; :data:`MAX_STEPS` after
    ``max_iter`` steps. ``k``, ``rest``: the joints' stiffness and rest angle,
    ``link_load``: μ per link, ``W``: the load's weights of a cos α_i in ∇E."""
    alpha = alpha.copy()
    sizes, energies = np.empty(max_iter), np.empty(max_iter)
    y, E, c, short, worst, sines = _state(alpha, a, jl, jr, k, rest, link_load, pinned, node,
                                          side, limit)
    near = False
    for it in range(max_iter):
        ac = a * np.cos(alpha)  # (the gradient's and the QP's)
        grad = _gradient(alpha, ac, jl, jr, k, rest, W)
        code, d, lam_new, mu_new, _, _ = _qp_step(sines, ac, a, jl, jr, k, W, grad, y, pinned,
                                                  node, side, limit, lam, mu, gap_tol)
        if code != OK:
            return QP_FAILED, alpha, sizes[:it], energies[:it], lam, mu
        size = 0.0
        for i in range(d.size):
            size = max(size, abs(d[i]))
        if size > STEP_CAP:
            d = d * (STEP_CAP / size)
        big = 0.0
        for v in lam_new:
            big = max(big, abs(v))
        for v in mu_new:
            big = max(big, abs(v))
        rho = 2.0 * big + 1e-8 * scale / length
        m0 = E + rho * (c + short)
        slope = -rho * (c + short)
        dot = 0.0
        for i in range(d.size):
            dot += grad[i] * d[i]
        slope += dot
        noise = 1e-13 * (abs(m0) + scale)
        t = 1.0
        while True:
            trial = alpha + t * d
            y, E_t, c_t, short_t, worst_t, sines_t = _state(trial, a, jl, jr, k, rest,
                                                            link_load, pinned, node, side,
                                                            limit)
            if size < tol:
                break
            step = armijo(t, E_t + rho * (c_t + short_t), m0, slope, noise, SQP_SHORTEST)
            if step == t or step == 0.0:  # (below SQP_SHORTEST: the last trial is taken)
                break
            t = step
        alpha, E, c, short, worst, sines = trial, E_t, c_t, short_t, worst_t, sines_t
        if pinned:
            lam = lam_new
        mu = mu_new
        moved = 0.0
        for i in range(d.size):
            moved = max(moved, abs(d[i]))
        sizes[it], energies[it] = t * moved, E
        whole = t == 1.0 and size < tol
        if whole and max(c, worst) < feasible * length and near:
            return CONVERGED, alpha, sizes[:it + 1], energies[:it + 1], lam, mu
        near = whole
    return MAX_STEPS, alpha, sizes, energies, lam, mu
