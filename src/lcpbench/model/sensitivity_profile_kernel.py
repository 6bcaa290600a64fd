"""The profile sensitivities' KKT solve compiled, in O(N) (:mod:`lcpbench.model.sensitivity_profile`).

At the answer α with reactions λ on the active rows A (the derivation:
:mod:`lcpbench.model.sensitivity_profile` and docs/design.md), per parameter p

    B du − J_xᵀ (q + v) + Σ_r s_r dλ_r e_k = −∂_p∇E,   q_k = β_k dx_k + s_k h'_k dλ_k,
    h'_k dx_k − du_k = −s_k ∂_p c_k   (k ∈ A),          dx = J_x du,

with B = H + T − Σ_r λ_r s_r h'_r ∇²x_k (pentadiagonal), β = λ s h'', v = λ s ∂_p h'
and J_x the dense lower-triangular Jacobian of the nodes' x. J_x is a running sum, so
lifting the nodes' dx and the suffix sums W_j = Σ_{k>j} (q + v)_k into the unknowns
makes the system banded: per node i, in the order (du_i, dx_i, W_i, dλ_i),

    dx_i − dx_{i−1} + tan α_{i−1} (du_i − du_{i−1}) = 0          (dx_0 = 0),
    W_i − W_{i+1} − q_{i+1} = v_{i+1}                             (W_N = 0),
    (B du)_i + tan α_{i−1} W_{i−1} − tan α_i W_i + s_i dλ_i = −(∂_p∇E)_i   (J_xᵀ: p_{i−1} − p_i,
                                                                    p_j = −tan α_j W_j),

and the row of the constraint at an active node. The unknowns that are fixed (dλ_i = 0
off the active rows, du_i = 0 at a pinned node, dx_0 = 0, W_N = 0) are left out: about
3 per node, at most 8 bands either side (B couples nodes two apart), solved by the
banded LU with partial pivoting (:func:`lcpbench.linalg.band_lu_kernel.band_solve`) for
the parameters wanted at once: O(N) whatever the number of contact nodes. The walls are read as the
solve reads them (:func:`lcpbench.model.wall_kernel.walls_at`, their tables of cubic
pieces; the plan refuses a profile without one). Loaded through
:func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.band_lu_kernel import band_solve
from .compiled_kernel import banded_step, geometric_bands
from .sensitivity_kernel import LOAD, REST, SPRING, gradient_derivative
from .wall_kernel import walls_at

#: the output rows: θ, the walls moved apart, EI, the weight, the walls scaled about
#: the pin (ℓ's derivative is made of the weight's and this one's)
THETA, HEIGHT, EI_, WEIGHT, SCALE = range(5)
OK, SINGULAR = 0, 1
#: the lifted system's unknowns at a node
DU, DX, W, DL = range(4)


@njit(cache=True)
def derivatives(alpha, a, jl, jr, k, rest, fs, nodal_load, lo_rows, hi_rows, ku, cu_, kl, cl_,
                fu, fl, eps_R, drest, dk, unit_load, L, want):
    """(code, du, dfu, dfl, u, one_sided): the derivatives of the free nodes' heights and
    the upper and lower reactions, one row per parameter (THETA … SCALE), those of
    ``want`` written, the rest zero; code SINGULAR where the KKT matrix at the answer's
    contact set is singular. ``drest``, ``dk``, ``unit_load``: ∂φ*/∂θ per joint, ∂k/∂EI
    per joint, the nodal load at unit weight; ``ku``, ``cu_`` (``kl``, ``cl_``): the
    upper (lower) wall's table, empty where it is flat; ``u``: the free nodes' heights; ``one_sided``: the nodes touching a
    wall (gap ≤ 1e-9 ``L``) without force."""
    n, links, nj = lo_rows.size, alpha.size, jr.size
    first = fs - 1  # the node of free index 0
    sines, cosines = np.sin(alpha), np.cos(alpha)
    bands, _, _, coef, origin, _, phi_origin = banded_step(alpha, a, jl, jr, k, rest, fs, n,
                                                         nodal_load)
    T, mu = np.zeros((2, n)), np.empty(links)
    geometric_bands(alpha, a, jl, jr, k, rest, fs, n, T, mu, sines, cosines)
    xf, yf, hi, lo = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    h1, l1, h2, l2 = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    walls_at(sines, cosines, a, fs, hi_rows, lo_rows, ku, cu_, kl, cl_, xf, yf, hi, lo, h1, l1,
             h2, l2)
    # the active rows: side s (+1 upper, −1 lower), λ, the wall's height, slope, curvature
    side, lam, hgt, slope, curv = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    one_sided = np.zeros(n, np.bool_)
    for i in range(n):
        if fu[i] > eps_R and np.isfinite(hi_rows[i]):
            side[i], lam[i], hgt[i], slope[i], curv[i] = 1.0, fu[i], hi[i], h1[i], h2[i]
        elif fl[i] > eps_R and np.isfinite(lo_rows[i]):
            side[i], lam[i], hgt[i], slope[i], curv[i] = -1.0, fl[i], lo[i], l1[i], l2[i]
        touching = (np.isfinite(hi_rows[i]) and hi[i] - yf[i] <= 1e-9 * L) or \
            (np.isfinite(lo_rows[i]) and yf[i] - lo[i] <= 1e-9 * L)
        one_sided[i] = touching and not (fu[i] > eps_R or fl[i] > eps_R)
    # B = H + T + Σ_j (−c_j) d_j d_jᵀ, c_j = −(Σ over the rows past link j of λ s h') /
    # (a cos³ α_j), d_j = e_{j+1} − e_j
    tan = sines / cosines
    suffix = 0.0
    for j in range(links - 1, -1, -1):
        i = j + 1 - first  # node j + 1
        if 0 <= i < n:
            suffix += lam[i] * side[i] * slope[i]
        c = -suffix / (a * cosines[j] ** 3)
        for node in (j, j + 1):
            if 0 <= node - first < n:
                bands[0, node - first] -= c
        if 0 <= j - first and j + 1 - first < n:
            bands[1, j - first] += c
    for i in range(n):
        bands[0, i] += T[0, i]
        bands[1, i] += T[1, i]
    # the right-hand sides' parts: −∂∇E (the energy's), ∂c, ∂h' (the walls')
    P = 5
    dgrad, dc, dgc = np.zeros((P, n)), np.zeros((P, n)), np.zeros((P, n))
    m, none_n, none_j, Tz = np.empty(nj), np.zeros(n), np.zeros(nj), np.zeros((2, n))
    if want[THETA]:
        gradient_derivative(dgrad[THETA], REST, drest, coef, jr[0], fs, links, origin,
                            phi_origin, k, rest, m, none_n, none_j, Tz)
    if want[EI_]:
        gradient_derivative(dgrad[EI_], SPRING, dk, coef, jr[0], fs, links, origin, phi_origin,
                            k, rest, m, none_n, none_j, Tz)
    if want[WEIGHT]:
        gradient_derivative(dgrad[WEIGHT], LOAD, unit_load, coef, jr[0], fs, links, origin,
                            phi_origin, k, rest, m, none_n, none_j, Tz)
    for i in range(n):
        if side[i] != 0.0:
            dc[HEIGHT, i] = 1.0  # both walls apart: c = s (h − u) grows by 1
            # scaled about the pin: δh = h − x h', δh' = −x h''
            dc[SCALE, i] = side[i] * (hgt[i] - xf[i] * slope[i])
            dgc[SCALE, i] = -xf[i] * curv[i]
    # the right-hand sides' columns: the parameters wanted
    cols = np.full(P, -1, np.int64)
    nw = 0
    for p in range(P):
        if want[p]:
            cols[p] = nw
            nw += 1
    # the lifted system's unknowns, node by node (du, dx, W, dλ), those that are not
    # fixed: du at a pinned node, dx_0 (the left pin's x), W_N (no link N), dλ off the
    # active rows are 0; each has its own row
    at = np.full((links + 1, 4), -1, np.int64)
    N = 0
    for node in range(links + 1):
        i = node - first
        for c, there in ((DU, 0 <= i < n), (DX, node >= 1), (W, node < links),
                         (DL, 0 <= i < n and side[i] != 0.0)):
            if there:
                at[node, c] = N
                N += 1
    rows, cols_, vals = np.empty(18 * (links + 1), np.int64), \
        np.empty(18 * (links + 1), np.int64), np.empty(18 * (links + 1))
    rhs = np.zeros((N, max(nw, 1)))
    ne = 0
    for node in range(links + 1):
        i = node - first
        r = at[node, DU]  # the force balance of a free node
        if r >= 0:
            for off in range(-2, 3):
                i2 = i + off
                if 0 <= i2 < n:
                    b = bands[0, i] if off == 0 else (
                        bands[1, min(i, i2)] if abs(off) == 1 else bands[2, min(i, i2)])
                    ne = _put(rows, cols_, vals, ne, r, at[node + off, DU], b)
            if node >= 1:
                ne = _put(rows, cols_, vals, ne, r, at[node - 1, W], tan[node - 1])
            if node < links:
                ne = _put(rows, cols_, vals, ne, r, at[node, W], -tan[node])
            if at[node, DL] >= 0:
                ne = _put(rows, cols_, vals, ne, r, at[node, DL], side[i])
            for p in range(P):
                if cols[p] >= 0:
                    rhs[r, cols[p]] = -dgrad[p, i]
        r = at[node, DX]  # dx: the running sum
        if r >= 0:
            ne = _put(rows, cols_, vals, ne, r, r, 1.0)
            if at[node - 1, DX] >= 0:
                ne = _put(rows, cols_, vals, ne, r, at[node - 1, DX], -1.0)
            if at[node, DU] >= 0:
                ne = _put(rows, cols_, vals, ne, r, at[node, DU], tan[node - 1])
            if at[node - 1, DU] >= 0:
                ne = _put(rows, cols_, vals, ne, r, at[node - 1, DU], -tan[node - 1])
        r = at[node, W]  # W: the suffix sums of q + v
        if r >= 0:
            ne = _put(rows, cols_, vals, ne, r, r, 1.0)
            if at[node + 1, W] >= 0:
                ne = _put(rows, cols_, vals, ne, r, at[node + 1, W], -1.0)
            i2 = i + 1
            if at[node + 1, DL] >= 0:
                ne = _put(rows, cols_, vals, ne, r, at[node + 1, DX],
                          -lam[i2] * side[i2] * curv[i2])  # β dx
                ne = _put(rows, cols_, vals, ne, r, at[node + 1, DL], -side[i2] * slope[i2])
                for p in range(P):
                    if cols[p] >= 0:
                        rhs[r, cols[p]] = lam[i2] * side[i2] * dgc[p, i2]
        r = at[node, DL]  # the constraint of an active row
        if r >= 0:
            ne = _put(rows, cols_, vals, ne, r, at[node, DX], slope[i])
            ne = _put(rows, cols_, vals, ne, r, at[node, DU], -1.0)
            for p in range(P):
                if cols[p] >= 0:
                    rhs[r, cols[p]] = -side[i] * dc[p, i]
    kl = ku = 0
    for e in range(ne):
        kl, ku = max(kl, rows[e] - cols_[e]), max(ku, cols_[e] - rows[e])
    ab = np.zeros((N, 2 * kl + ku + 1))
    for e in range(ne):
        ab[rows[e], cols_[e] - rows[e] + kl] += vals[e]
    du, dfu, dfl = np.zeros((P, n)), np.zeros((P, n)), np.zeros((P, n))
    if not band_solve(ab, kl, ku, rhs):
        return SINGULAR, du, dfu, dfl, origin, one_sided
    for p in range(P):
        if cols[p] < 0:
            continue
        for i in range(n):
            node = first + i
            du[p, i] = rhs[at[node, DU], cols[p]]
            if at[node, DL] >= 0:
                if side[i] > 0.0:
                    dfu[p, i] = rhs[at[node, DL], cols[p]]
                else:
                    dfl[p, i] = rhs[at[node, DL], cols[p]]
    return OK, du, dfu, dfl, origin, one_sided


@njit(cache=True)
def _put(rows, cols, vals, ne, r, c, v):
    """Entry (r, c) = v of the lifted system (c < 0: a fixed unknown, left out)."""
    if c < 0:
        return ne
    rows[ne], cols[ne], vals[ne] = r, c, v
    return ne + 1
