"""The second-order check of an answer: is the equilibrium stable on its contact set?

A converged answer satisfies the first-order conditions (stationarity of the
Lagrangian, signs, complementarity). So does a saddle: in a narrow channel past
θ = 180° the chain has unstable equilibria whose forces are percents away from
the stable neighbour's. A local minimum of the exact energy E(α) on the walls
also needs the second-order condition: the Hessian of the Lagrangian

    L(α) = E(α) + Σ_q f_q y_q(α),    f_q = R_q (upper) − R'_q (lower) + λ [q = N],

positive on the tangent space of the active constraints (the right pin's
closure y_N = 0, the nodes pressed on a rigid wall, y_q = h_q). The loads are in
E; λ is the closure's multiplier (the right pin's vertical reaction). Weakly
active contacts (a reaction below ``threshold``) are left free: the check is
then made on a larger space, which can only refuse more (conservative).

The Hessian in the link angles is tridiagonal plus diagonal:

    H = Σ_j k_j ∇φ_j ∇φ_jᵀ − diag(a sin α_i S_i),   S_i = Σ_{q > i} f_q + loads,

because y_q = Σ_{i<q} a sin α_i has the diagonal Hessian −diag(a sin α_i). The
constraint rows are prefix sums of c_i = a cos α_i; differences of consecutive
ones are disjoint segment rows: between two fixed nodes p < q,
δy_q − δy_p = Σ_{p ≤ i < q} c_i δα_i = 0. An elastic wall's node q is not fixed:
it adds ½ k_q δy_q² (its spring) and is a segment end with δy_q free.

So the check is the inertia of the lifted KKT matrix in (δα, δy at elastic
contacts, one multiplier per segment): with m segment rows of full rank,

    neg(reduced Hessian) = neg(KKT) − m          (Sylvester, Haynsworth).

Its LDLᵀ in the order of the chain (each link, then at a segment end the
previous elastic height and the segment's multiplier) keeps at most five
variables coupled at a time (the frontal matrix below), so the whole count is
O(N) with 1 × 1 pivots and no fill beyond the front. Any order of nonzero 1 × 1
pivots is a congruence, so the count of negative pivots is exact; a pivot at
round-off (a singular leading block) is reported as degenerate.

Chains with consecutive joints (joint j between links j and j + 1, or a clamp on
one link): the layouts the scenes build. Flat and elastic walls; a wall
profile's constraint also moves with x and is not covered here.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: a pivot whose size is below this share of the Hessian's scale is round-off
DEGENERATE = 1e-12
#: return codes of :func:`unstable_directions`
CHECKED, DEGENERATE_PIVOT, NOT_TRIDIAGONAL = 0, 1, 2
FRONT = 7  # slots of the frontal matrix (at most six are in use at once)


@njit(cache=True)
def _alloc(F, used):
    for s in range(FRONT):
        if not used[s]:
            used[s] = True
            for t in range(FRONT):
                F[s, t] = 0.0
                F[t, s] = 0.0
            return s
    return -1


@njit(cache=True)
def _eliminate(F, used, s):
    """Schur-eliminate slot ``s`` from the front; returns its pivot. Row FRONT of ``F``
    is scratch: the slots coupled to ``s``."""
    p = F[s, s]
    used[s] = False
    live = F[FRONT]
    m = 0
    for i in range(FRONT):
        if used[i] and F[i, s] != 0.0:
            live[m] = i
            m += 1
    if p != 0.0:
        for x in range(m):
            i = int(live[x])
            r = F[i, s] / p
            for y in range(m):
                j = int(live[y])
                F[i, j] -= r * F[s, j]
    for t in range(FRONT):
        F[s, t] = 0.0
        F[t, s] = 0.0
    return p


@njit(cache=True)
def lagrangian_hessian(alpha, a, jl, jr, k, rest, link_load, first, forces_upper,
                       forces_lower, pinned_right):
    """The tridiagonal Hessian of L in α: (diagonal, off-diagonal, ok).

    ``first`` is the node index of the first free node; the reactions (N) run over
    the free nodes. λ is the least-squares solution of stationarity
    ∂L/∂α_i = g_i + a cos α_i S_i = 0, with g the springs' gradient (0 when the
    right end is free). ``ok`` is False when a joint joins links that are not
    neighbours (the Hessian is then not tridiagonal).
    """
    links = alpha.size
    diag = np.zeros(links)
    off = np.zeros(max(links - 1, 0))
    grad = np.zeros(links)
    for j in range(jr.size):
        r, left = jr[j], jl[j]
        phi = alpha[r] - (alpha[left] if left >= 0 else 0.0)
        t = k[j] * (phi - rest[j])
        diag[r] += k[j]
        grad[r] += t
        if left >= 0:
            if r != left + 1:
                return diag, off, False
            diag[left] += k[j]
            off[left] -= k[j]
            grad[left] -= t
    # f_q at every node: −(the node's half of each adjacent link load) + reactions
    f = np.zeros(links + 1)
    for i in range(links):
        f[i] -= 0.5 * link_load[i]
        f[i + 1] -= 0.5 * link_load[i]
    for i in range(forces_upper.size):
        f[first + i] += forces_upper[i] - forces_lower[i]
    # S_i = Σ_{q > i} f_q (suffix sums), then λ at node N by least squares
    S = np.zeros(links)
    acc = 0.0
    for i in range(links - 1, -1, -1):
        acc += f[i + 1]
        S[i] = acc
    lam = 0.0
    if pinned_right:
        num = den = 0.0
        for i in range(links):
            c = a * np.cos(alpha[i])
            num += (grad[i] + c * S[i]) * c
            den += c * c
        lam = -num / den if den > 0.0 else 0.0
    for i in range(links):
        diag[i] -= a * np.sin(alpha[i]) * (S[i] + lam)
    return diag, off, True


@njit(cache=True)
def _pivot_sign(F, used, s, small, counts):
    """Eliminate slot ``s``; count its pivot in ``counts`` (negative, degenerate)."""
    p = _eliminate(F, used, s)
    counts[0] += p < 0.0
    counts[1] += abs(p) <= small


@njit(cache=True)
def _close_segment(F, used, closing, closing_y, small, counts):
    """Eliminate an ended segment's start height (if elastic), then its multiplier, whose
    pivot is counted as a constraint row's (expected negative)."""
    if closing_y >= 0:
        _pivot_sign(F, used, closing_y, small, counts)
    counts[0] += _eliminate(F, used, closing) < 0.0


@njit(cache=True)
def reduced_inertia(diag, off, c, event, stiffness):
    """Negative and degenerate pivots of H on the tangent space of the segments.

    ``diag``, ``off``: H (tridiagonal, links); ``c``: a cos α_i; ``event[q]`` for
    node q = 1..links: 0 none, 1 a fixed node (rigid contact or the right pin),
    2 an elastic contact of spring ``stiffness[q]`` (N/mm). Node 0 is fixed.
    Returns (negative eigenvalues of the reduced Hessian, degenerate pivots).

    Order of elimination: link i is eliminated once link i + 1 is in the front; a
    segment that ends at node i + 1 keeps its multiplier (and its start's elastic
    height) until then, so that the multiplier's pivot is the Schur complement
    −cᵀH⁻¹c of its whole segment, never a structural zero.
    """
    links = diag.size
    scale = 0.0
    for i in range(links):
        scale = max(scale, abs(diag[i]))
    small = DEGENERATE * max(scale, 1e-300)
    last_event = 0
    for q in range(1, links + 1):
        if event[q] != 0:
            last_event = q
    F = np.zeros((FRONT + 1, FRONT))  # the front, and a scratch row
    used = np.zeros(FRONT, np.bool_)
    counts = np.zeros(2, np.int64)
    rows = 0
    prev = -1
    mu = _alloc(F, used) if last_event > 0 else -1  # the current segment's multiplier
    yp = -1  # the elastic height at the current segment's start
    closing, closing_y = -1, -1  # a segment that ended at node i: eliminated after link i - 1
    for i in range(links):
        s = _alloc(F, used)
        F[s, s] = diag[i]
        if prev >= 0:
            F[prev, s] = F[s, prev] = off[i - 1]
        if mu >= 0:
            F[mu, s] -= c[i]
            F[s, mu] -= c[i]
        if prev >= 0:
            _pivot_sign(F, used, prev, small, counts)
        if closing >= 0:
            _close_segment(F, used, closing, closing_y, small, counts)
            rows += 1
            closing, closing_y = -1, -1
        prev = s
        q = i + 1
        if event[q] != 0 and mu >= 0:
            y = -1
            if event[q] == 2:
                y = _alloc(F, used)
                F[y, y] = stiffness[q]
                F[mu, y] += 1.0
                F[y, mu] += 1.0
            closing, closing_y = mu, yp
            yp = y
            mu = _alloc(F, used) if q < last_event else -1
            if mu >= 0 and yp >= 0:
                F[mu, yp] -= 1.0
                F[yp, mu] -= 1.0
    if prev >= 0:
        _pivot_sign(F, used, prev, small, counts)
    if closing >= 0:
        _close_segment(F, used, closing, closing_y, small, counts)
        rows += 1
    if yp >= 0:
        _pivot_sign(F, used, yp, small, counts)
    return max(counts[0] - rows, 0), counts[1]


@njit(cache=True)
def unstable_directions(alpha, a, jl, jr, k, rest, link_load, first, forces_upper,
                        forces_lower, stiffness_upper, stiffness_lower, threshold,
                        pinned_right):
    """The second-order check of an answer: (code, unstable directions, degenerate).

    ``code`` is CHECKED, or NOT_TRIDIAGONAL for a joint layout this check does not
    take. ``unstable directions`` counts the negative eigenvalues of the reduced
    Hessian of the Lagrangian (0: a strict local minimum on the contact set,
    unless a pivot is degenerate). A node is held by its wall where its reaction
    exceeds ``threshold`` (N); ``stiffness_*`` are its springs (N/mm, inf: rigid).
    """
    links = alpha.size
    diag, off, ok = lagrangian_hessian(alpha, a, jl, jr, k, rest, link_load, first,
                                       forces_upper, forces_lower, pinned_right)
    if not ok:
        return NOT_TRIDIAGONAL, 0, 0
    c = np.empty(links)
    for i in range(links):
        c[i] = a * np.cos(alpha[i])
    event = np.zeros(links + 1, np.int64)
    stiffness = np.full(links + 1, np.inf)
    for i in range(forces_upper.size):
        q = first + i
        for side in range(2):
            R = forces_upper[i] if side == 0 else forces_lower[i]
            ks = stiffness_upper[i] if side == 0 else stiffness_lower[i]
            if R > threshold:
                if np.isfinite(ks):
                    event[q] = 2
                    stiffness[q] = ks
                else:
                    event[q] = 1
    if pinned_right:
        event[links] = 1
    neg, degenerate = reduced_inertia(diag, off, c, event, stiffness)
    return CHECKED, neg, degenerate
