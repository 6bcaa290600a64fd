"""The frictional contact step (issue 39), compiled: the Stewart–Trinkle LCP of a state.

docs/friction.md derives it. At a configuration α of a chain held in y at both ends,
with the unknowns δ (the free node heights' increments δy, and the translation τ
along x when no end holds x, held in the step by a spring k_τ):

    K δ = f + G_n N + G_t T,

K the banded step's Hessian (:func:`lcpbench.model.compiled_driver.assemble_step`, compiled:
:func:`step_arrays`; near the answer with the springs' curvature T, Newton) plus the
pull's curvature (and k_τ, and a free end's rotation spring), f = −g₀ + P ∂x_N/∂δ, G_n the gaps' and G_t the
slips' Jacobians. Eliminating δ leaves the contact quantities affine in the forces,
(g, s) = (g_f, s_f) + W (N, T) with W = Gᵀ K⁻¹ G (:func:`delassus_form`, Siconos'
fc2d form), and the LCP w = M z + q, 0 <= z ⟂ w >= 0, in z = (N, β⁺, β⁻, λ) with
T = β⁺ − β⁻ (:func:`frictional_lcp`); M is not symmetric.

Against a wall y = h(x) (a profile), N acts along the wall's normal and T along its
tangent t = (1, h')/√(1 + h'²), both at the nodes' current x (lagged: fixed within a
step): a row's gap and a pair's slip are the normal and tangential parts of the
node's displacement, whose x part is the dense row D of :func:`slip_jacobian`.

Each function is ``@njit(cache=True)``; with NUMBA_DISABLE_JIT=1 they run as plain
Python. The driver (:mod:`lcpbench.model.friction_driver`) calls these.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.ldl_kernel import refactor, resolve_columns
from ..solvers.dual_kernel import grad_into
from ..solvers.pivoting_kernel import DONE, support_pivots, symmetric_active_set
from .compiled_kernel import banded_step, geometric_bands, positive_with


@njit(cache=True)
def slip_jacobian(alpha, first, n, right_datum):
    """D (N+1 × n): δx_i = Σ_j D[i, j] δu_j for the heights of the n free nodes
    ``first`` … ``first + n − 1`` (the others held).

    δx_i = −Σ_{k<i} tan α_k (δy_{k+1} − δy_k) with the left end as the datum (its x
    held, or moved by τ); with ``right_datum`` each row is taken relative to the
    right end's (x_N held): δx_i − δx_N.
    """
    links = alpha.size
    t = np.tan(alpha)
    D = np.zeros((links + 1, n))
    for i in range(links + 1):
        for c in range(n):
            j = first + c
            v = 0.0
            if 1 <= j <= i:
                v -= t[j - 1]
            if j < i:
                v += t[j]
            D[i, c] = v
    if right_datum:
        for i in range(links):
            for c in range(n):
                D[i, c] -= D[links, c]
        for c in range(n):
            D[links, c] = 0.0
    return D


@njit(cache=True)
def add_pull_curvature(bands, alpha, a, pull, first):
    """H += P Σ_k d_k d_kᵀ / (a cos³ α_k), d_k = e_{k+1} − e_k on the free heights
    (nodes ``first`` … ``first + n − 1``), H in lower band storage (``bands[p, i] =
    H[i + p, i]``): the curvature of the pull's potential −P x_N (x_N = Σ √(a² −
    Δy_k²)); P > 0 only (a pulled chain is stiffer; a push adds nothing)."""
    if pull <= 0.0:
        return
    n = bands.shape[1]
    for k in range(alpha.size):
        c = np.cos(alpha[k])
        s = pull / (a * c * c * c)
        lo, hi = k - first, k + 1 - first  # free indices of nodes k and k + 1
        ok_lo, ok_hi = 0 <= lo < n, 0 <= hi < n
        if ok_lo:
            bands[0, lo] += s
        if ok_hi:
            bands[0, hi] += s
        if ok_lo and ok_hi:
            bands[1, lo] -= s


@njit(cache=True)
def step_arrays(alpha, a, jl, jr, k, rest, fs, n, nodal_load, pull, right_datum, newton):
    """The chain's part of the step at α, compiled: (bands, f, D, u₀). H (lower band
    storage) is the banded step's (:func:`lcpbench.model.compiled_kernel.banded_step`,
    i.e. :func:`lcpbench.model.compiled_driver.assemble_step`) plus the pull's curvature
    (:func:`add_pull_curvature`); f = −(H u₀ + c) at the linearisation point u₀
    (``ContactStep.gradient(origin)``: Jᵀ k (φ̂(u₀) − φ*) − f_load,
    :func:`~lcpbench.solvers.dual_kernel.grad_into`) plus
    P ∂x_N/∂δ; D the slips' Jacobian (:func:`slip_jacobian`). ``fs``: the shifted
    index (node + 1) of the first free node, as the banded step's. With ``newton``, H
    also takes the springs' curvature T (:func:`lcpbench.model.compiled_kernel.
    geometric_bands`) where H + T is positive definite (the fixed point is the same:
    δ = 0 there)."""
    bands, _, _, coef, origin, _, phi_origin = banded_step(alpha, a, jl, jr, k, rest, fs, n,
                                                         nodal_load)
    first = fs - 1
    add_pull_curvature(bands, alpha, a, pull, first)
    if newton:  # the springs' exact curvature where H + T stays positive definite
        T = np.zeros((2, n))
        geometric_bands(alpha, a, jl, jr, k, rest, fs, n, T, np.empty(alpha.size),
                        np.sin(alpha), np.cos(alpha))
        if positive_with(bands, T, np.empty((4, n)), np.empty(n, np.bool_), n):
            for i in range(n):
                bands[0, i] += T[0, i]
                bands[1, i] += T[1, i]
    D = slip_jacobian(alpha, first, n, right_datum)
    links = alpha.size
    f = grad_into(np.empty(n), np.empty(jr.size), origin,  # the step's gradient at u₀
                  (coef, jr[0], fs, links, origin, phi_origin, k, rest, nodal_load),
                  np.empty((2, 0)))
    for i in range(n):
        f[i] = -f[i]
        if pull != 0.0:
            f[i] += pull * D[links, i]
    return bands, f, D, origin


@njit(cache=True)
def _solve_columns(bands, rot, rot_k, k_tau, f, normal_node, normal_xy, D, friction_node,
                   tangent_xy, first):
    """(X = K⁻¹ B, ok) with B = [G_n | G_t | f] (n × (m_n + m_t + 1)) and K the step's
    matrix: H in lower band storage (``bands``), plus ``rot_k`` r rᵀ when ``rot`` = r
    is not empty (a free end's rotation about the pin), plus k_τ on τ when ``f`` has
    one more entry than H has rows. With both ends held in y, H is positive definite
    and banded: a banded LDLᵀ (:mod:`lcpbench.linalg.ldl_kernel`), O(n) per column.
    A free end's H is singular on the rotation and H + k r rᵀ is dense: solved
    dense. ok False when K is not positive definite (a link at the vertical).

    A wall row r's column is n_x D[node] + n_y e_node (``normal_xy[r]`` = (n_x, n_y):
    the direction in which its gap grows, the wall's normal), a friction pair c's is
    t_x D[node] + t_y e_node (``tangent_xy[c]``: the wall's tangent); on flat walls
    n = (0, ∓1) and t = (1, 0). ``first``: the node of the first free height."""
    n = f.size
    ny = bands.shape[1]
    mn, mt = normal_node.size, friction_node.size
    cols = mn + mt + 1
    BT = np.zeros((cols, n))
    for r in range(mn):
        BT[r, normal_node[r]] = normal_xy[r, 1]
        if normal_xy[r, 0] != 0.0:
            for j in range(n):
                BT[r, j] += normal_xy[r, 0] * D[first + normal_node[r], j]
    for c in range(mt):
        for j in range(n):
            BT[mn + c, j] = tangent_xy[c, 0] * D[friction_node[c], j]
        if tangent_xy[c, 1] != 0.0:
            BT[mn + c, friction_node[c] - first] += tangent_xy[c, 1]
    for j in range(n):
        BT[mn + mt, j] = f[j]
    X = np.ascontiguousarray(BT.T)
    if rot.size:
        K = np.zeros((ny, ny))
        for i in range(ny):
            K[i, i] = bands[0, i]
            for p in (1, 2):
                if i + p < ny:
                    K[i + p, i] = K[i, i + p] = bands[p, i]
            for j in range(ny):
                K[i, j] += rot_k * rot[i] * rot[j]
        X[:ny, :] = np.linalg.solve(K, X[:ny, :])
        ok = True
    else:
        fac = np.empty((4, ny))
        ok = refactor(fac, bands, np.zeros(ny, np.bool_), np.empty(0), 0, ny)
        if ok:
            resolve_columns(fac, X, ny)
    if n > ny:  # τ, held by k_τ alone
        for c in range(cols):
            X[ny, c] = BT[c, ny] / k_tau
    return X, ok


@njit(cache=True)
def slip_product(D, X, first, ny):
    """D X ((N+1) × cols) in O(N · cols), D of :func:`slip_jacobian` (with τ's column of
    ones after its ``ny`` height columns when τ is an unknown).

    Height column c (the free node j = ``first`` + c) holds one value above row j (L_c,
    D[0, c]: 0, or the right end's datum shift), its own entry D[j, c] = −tan α_(j−1)
    (shifted) and one value below (U_c = D[N, c]: tan α_j − tan α_(j−1), shifted): δx_i
    sees the height of every node before i alike, and of every node after i alike. So
    row i of D X is a prefix sum of U_c X_c over the nodes before i, a suffix sum of
    L_c X_c over those after, and its own node's term; the columns past ``ny`` are
    added as they are."""
    rows, cols = D.shape[0], X.shape[1]
    out = np.zeros((rows, cols))
    acc = np.zeros(cols)
    for i in range(rows):  # the nodes before i
        for k in range(cols):
            out[i, k] = acc[k]
        c = i - first
        if 0 <= c < ny and i < rows - 1:
            u = D[rows - 1, c]
            if u != 0.0:
                for k in range(cols):
                    acc[k] += u * X[c, k]
    acc[:] = 0.0
    for i in range(rows - 1, -1, -1):  # the nodes after i, and i's own
        c = i - first
        for k in range(cols):
            out[i, k] += acc[k]
        if 0 <= c < ny:
            d, low = D[i, c], D[0, c] if i > 0 else 0.0
            for k in range(cols):
                out[i, k] += d * X[c, k]
                acc[k] += low * X[c, k]
    for c in range(ny, D.shape[1]):
        for i in range(rows):
            v = D[i, c]
            if v != 0.0:
                for k in range(cols):
                    out[i, k] += v * X[c, k]
    return out


@njit(cache=True)
def contact_gram(X, D, f, normal_node, normal_xy, friction_node, tangent_xy, first, ny):
    """Bᵀ X for B = [G_n | G_t | f] (:func:`_solve_columns`) without walking B: a wall
    row's column is n_y e_node + n_x D[node], a friction pair's t_x D[node] + t_y e_node,
    so with D X (:func:`slip_product`) each row of Bᵀ X costs O(cols), not O(n cols) as
    the dense D rows of the friction pairs (and of the normals on a sloped wall) would."""
    mn, mt = normal_node.size, friction_node.size
    cols = X.shape[1]
    DX = slip_product(D, X, first, ny)
    out = np.zeros((mn + mt + 1, cols))
    for r in range(mn):
        node = normal_node[r]
        nx, ny_ = normal_xy[r, 0], normal_xy[r, 1]
        for k in range(cols):
            out[r, k] = ny_ * X[node, k]
            if nx != 0.0:
                out[r, k] += nx * DX[first + node, k]
    for c in range(mt):
        node = friction_node[c]
        tx, ty = tangent_xy[c, 0], tangent_xy[c, 1]
        for k in range(cols):
            out[mn + c, k] = tx * DX[node, k]
            if ty != 0.0:
                out[mn + c, k] += ty * X[node - first, k]
    for j in range(f.size):
        v = f[j]
        if v != 0.0:
            for k in range(cols):
                out[mn + mt, k] += v * X[j, k]
    return out


@njit(cache=True)
def delassus_form(bands, rot, rot_k, k_tau, f, normal_node, normal_xy, gap, D,
                  friction_node, tangent_xy, slip, first):
    """The contact quantities as affine functions of the forces (docs/friction.md):

    (g, s) = (g_f, s_f) + W (N, T), W = Gᵀ K⁻¹ G (K: :func:`_solve_columns`). Returns W
    ((m_n+m_t)²), the free parts g_f, s_f, X = K⁻¹ [G_n | G_t | f] to recover
    δy = X (N, T, 1), and whether K was positive definite. ``normal_node`` /
    ``normal_xy``: the free node and the wall's normal n (the direction in which the
    gap grows: (0, −1) at a flat upper wall, (0, 1) at a flat lower one) of each wall
    row; ``friction_node``, ``tangent_xy``: the node (0..N) and the wall's tangent t of
    each friction pair (:func:`_solve_columns`; ``first``: the first free node).
    """
    mn, mt = normal_node.size, friction_node.size
    X, ok = _solve_columns(bands, rot, rot_k, k_tau, f, normal_node, normal_xy, D,
                           friction_node, tangent_xy, first)
    m = mn + mt
    BX = contact_gram(X, D, f, normal_node, normal_xy, friction_node, tangent_xy, first,
                      bands.shape[1])
    W = np.ascontiguousarray(BX[:m, :m])
    free = BX[:m, m].copy()
    g_f = gap + free[:mn]
    s_f = slip + free[mn:]
    return W, g_f, s_f, X, ok


@njit(cache=True)
def frictional_lcp(W, g_f, s_f, mu, pair):
    """(M, q) of the step: z = (N, β⁺, β⁻, λ).

    ``mu[r]`` and ``pair[r]``: the Coulomb coefficient of wall row r and its friction
    pair (a channel node's two rows share one pair, cone μ_up N_up + μ_lo N_lo;
    −1: a row without friction).
    """
    mn, mt = g_f.size, s_f.size
    size = mn + 3 * mt
    M = np.zeros((size, size))
    q = np.zeros(size)
    bp, bm, lam = mn, mn + mt, mn + 2 * mt
    for r in range(mn):
        q[r] = g_f[r]
        for c in range(mn):
            M[r, c] = W[r, c]
        for c in range(mt):
            M[r, bp + c] = W[r, mn + c]
            M[r, bm + c] = -W[r, mn + c]
    for i in range(mt):
        q[bp + i] = s_f[i]
        q[bm + i] = -s_f[i]
        for c in range(mn):
            M[bp + i, c] = W[mn + i, c]
            M[bm + i, c] = -W[mn + i, c]
        for c in range(mt):
            M[bp + i, bp + c] = W[mn + i, mn + c]
            M[bp + i, bm + c] = -W[mn + i, mn + c]
            M[bm + i, bp + c] = -W[mn + i, mn + c]
            M[bm + i, bm + c] = W[mn + i, mn + c]
        M[bp + i, lam + i] = 1.0
        M[bm + i, lam + i] = 1.0
        M[lam + i, bp + i] = -1.0
        M[lam + i, bm + i] = -1.0
    for r in range(mn):
        if pair[r] >= 0:
            M[lam + pair[r], r] += mu[r]
    return M, q


@njit(cache=True)
def recover(z, X, mn, mt):
    """(N, T, δ) of an LCP solution z (docs/friction.md: δ = X (N, T, 1))."""
    N = z[:mn].copy()
    T = z[mn:mn + mt] - z[mn + mt:mn + 2 * mt]
    n = X.shape[0]
    d = X[:, mn + mt].copy()
    for j in range(n):
        acc = 0.0
        for r in range(mn):
            acc += X[j, r] * N[r]
        for c in range(mt):
            acc += X[j, mn + c] * T[c]
        d[j] += acc
    return N, T, d


@njit(cache=True)
def frictionless_contacts(M, q, mn, normal_changes, feas_rtol, pivot_rtol):
    """The frictionless contacts of the step: 0 <= N ⟂ W_nn N + g_f >= 0, M's first
    ``mn`` rows and columns (:func:`lcpbench.solvers.pivoting_kernel.symmetric_active_set`,
    at most ``normal_changes`` solves). Returns (N, end, solves)."""
    Mn = np.ascontiguousarray(M[:mn, :mn])
    N, _, end, solves = symmetric_active_set(Mn, q[:mn].copy(), normal_changes, feas_rtol,
                                             pivot_rtol)
    return N, end, solves


@njit(cache=True)
def first_support_from(M, q, pair, N, slide, normal_changes, max_changes, feas_rtol,
                       pivot_rtol, lstsq_rcond):
    """The step's answer by block principal pivoting from a stick/slide/separate guess,
    for a step whose last answer's support does not hold (a path's first step, a chain
    that starts or stops sliding as a whole; docs/friction.md).

    Both guesses start from the frictionless contacts ``N`` (:func:`frictionless_contacts`,
    ended DONE; a caller trying both guesses finds them once) and each pair's free slip
    s⁰ = s_f + W_tn N, σ = sign s⁰ (T opposes it: β⁻ where σ > 0, β⁺ where σ < 0).

    * ``slide`` False (stick): the pressed nodes (N > 0) stick (N, β; λ off the
      support), every other pair slides freely (β, λ: T = 0 on a node without N).
    * ``slide`` True (slide): every pair slides, T = −σ μ N, which leaves an LCP in N
      alone, 0 <= N ⟂ (W_nn − W_nt σ μ) N + g_f >= 0 (not symmetric), solved by
      :func:`~lcpbench.solvers.pivoting_kernel.support_pivots` from the frictionless
      contacts; its contacts with every pair sliding (N, β, λ) are the guess.

    Then ``support_pivots`` on the whole LCP from the guess. ``pair``: each wall row's
    friction pair (−1: none; M's size is m_n + 3 m_t); ``normal_changes``: the budget
    of the LCPs in N alone (their solves are of the contacts' size), ``max_changes`` the
    whole LCP's supports. Returns (z, w, support, end, solves) as ``support_pivots``
    does; the solves counted are this call's."""
    mn = pair.size
    mt = (q.size - mn) // 3
    lam = mn + 2 * mt
    Mn = np.ascontiguousarray(M[:mn, :mn])
    qn = q[:mn].copy()
    S = np.zeros(q.size, np.bool_)
    solves = 0
    sigma = np.zeros(mt)
    for i in range(mt):
        s0 = q[mn + i]
        for r in range(mn):
            s0 += M[mn + i, r] * N[r]
        sigma[i] = 1.0 if s0 > 0.0 else -1.0 if s0 < 0.0 else 0.0
    if slide:  # T = −σ μ N: W_nn N + W_nt T = (W_nn − W_nt σ μ) N
        for r in range(mn):
            p = pair[r]
            if p >= 0:
                c = sigma[p] * M[lam + p, r]  # σ μ (M's cone row holds μ)
                for a in range(mn):
                    Mn[a, r] -= M[a, mn + p] * c
        N, _, _, end, more = support_pivots(Mn, qn, N > 0.0, normal_changes, feas_rtol,
                                            pivot_rtol, lstsq_rcond)
        solves += more
        if end != DONE:
            return np.zeros(q.size), q.copy(), S, end, solves
    pressed = np.zeros(mt, np.bool_)
    for r in range(mn):
        if N[r] > 0.0:
            S[r] = True
            if pair[r] >= 0:
                pressed[pair[r]] = True
    for i in range(mt):
        if sigma[i] > 0.0:
            S[mn + mt + i] = True
        elif sigma[i] < 0.0:
            S[mn + i] = True
        S[lam + i] = slide or not pressed[i]
    z, w, S, end, more = support_pivots(M, q, S, max_changes, feas_rtol, pivot_rtol,
                                        lstsq_rcond)
    return z, w, S, end, solves + more
