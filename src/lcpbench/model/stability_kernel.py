"""The second-order check of an answer: is the equilibrium stable on its contact set?

A converged answer satisfies the first-order conditions (stationarity of the
Lagrangian, signs, complementarity). So does a saddle: in a narrow channel past
θ = 180° the chain has unstable equilibria whose forces are percents away from
the stable neighbour's. A local minimum of the exact energy E(α) on the walls
also needs the second-order condition: the Hessian of the Lagrangian

    L(α) = E(α) + Σ_q [R_q (y_q − h(x_q)) + R'_q (l(x_q) − y_q)] + λ y_N

positive on the tangent space of the active constraints: the right pin's closure
y_N = 0 and the nodes pressed on a wall (reaction R above ``threshold``; weakly
active contacts are left free, which can only refuse more). λ is the closure's
multiplier; the loads are in E; h, l the walls (flat: constants).

In the link angles the Hessian of L is tridiagonal (the springs) plus a diagonal,

    −a sin α_i S_i − a cos α_i X_i,   S_i = Σ_{q>i} ∂L/∂y_q,  X_i = Σ_{q>i} ∂L/∂x_q,

because y_q = Σ_{i<q} a sin α_i and x_q = Σ_{i<q} a cos α_i have diagonal Hessians;
plus, at a held node on a curved wall, the wall's curvature −R h''(x_q) on δx_q².
The held nodes cut the chain into segments. Between held nodes p < q the
displacements are tied by two rows, δy_q − δy_p = Σ a cos α_i δα_i and
δx_q − δx_p = −Σ a sin α_i δα_i (p ≤ i < q), and at a held node δy_q = h'(x_q) δx_q
(0 on a flat wall or the pin); an elastic wall's node has a free δy_q with its
spring ½ k δy_q² instead. On flat walls the δx rows constrain nothing (the δx are
free) and are left out.

The check is the inertia of the KKT matrix of that lifted form (δα, the held
nodes' δx and elastic δy, one multiplier per row): with m rows of full rank,

    neg(reduced Hessian) = neg(KKT) − m          (Sylvester, Haynsworth).

Its LDLᵀ in the order of the chain keeps a few variables coupled at a time (the
frontal matrix below), so the count is O(N). Pivots are 1 × 1, except a δx row's
multiplier with its end's δx (a 2 × 2 block: the δx of a flat wall has no
diagonal). Any such block LDLᵀ is a congruence, so the count is exact; a pivot at
round-off (a singular leading block) is reported as degenerate.

Chains with consecutive joints (joint j between links j and j + 1, or a clamp on
one link): the layouts the scenes build.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: a pivot whose size is below this share of the Hessian's scale is round-off
DEGENERATE = 1e-12
#: return codes of :func:`unstable_directions`
CHECKED, DEGENERATE_PIVOT, NOT_TRIDIAGONAL = 0, 1, 2
FRONT = 10  # slots of the frontal matrix (at most nine are in use at once)
#: node events of :func:`reduced_inertia`
FREE, HELD, ELASTIC = 0, 1, 2
# The front's helpers below are inlined where they are called (``inline="always"``): as
# calls, once per link each, the reference counts of the front's arrays they are handed
# cost a fifth of the judge (25 scenes at N = 140: 30 → 24 µs a scene, the same bits)


@njit(cache=True, inline="always")
def _alloc(F, used):
    """A free slot of the front. Its row and column are zero already: the front starts
    at zero and an elimination zeroes the row and column of each slot it frees."""
    for s in range(FRONT):
        if not used[s]:
            used[s] = True
            return s
    raise RuntimeError("the stability check's front is full (FRONT too small)")


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def _eliminate_pair(F, used, s, t, small, counts):
    """Schur-eliminate slots ``s`` and ``t`` as one 2 × 2 block; its inertia into
    ``counts`` (negative, degenerate)."""
    a, b, c = F[s, s], F[s, t], F[t, t]
    det = a * c - b * b
    used[s] = False
    used[t] = False
    live = F[FRONT]
    m = 0
    for i in range(FRONT):
        if used[i] and (F[i, s] != 0.0 or F[i, t] != 0.0):
            live[m] = i
            m += 1
    if det != 0.0:
        for x in range(m):
            i = int(live[x])
            u = (c * F[i, s] - b * F[i, t]) / det  # (B⁻¹ [F_is, F_it])_s
            v = (a * F[i, t] - b * F[i, s]) / det
            for y in range(m):
                j = int(live[y])
                F[i, j] -= u * F[s, j] + v * F[t, j]
    for r in range(FRONT):
        F[s, r] = F[r, s] = F[t, r] = F[r, t] = 0.0
    if det < 0.0:
        counts[0] += 1
    elif det > 0.0 and a + c < 0.0:
        counts[0] += 2
    counts[1] += det == 0.0


@njit(cache=True)
def lagrangian_hessian(alpha, c, s, jl, jr, k, rest, link_load, first, forces_upper,
                       forces_lower, slope_upper, slope_lower, pinned_right):
    """The tridiagonal Hessian of L in α: (diagonal, off-diagonal, ok).

    ``c``, ``s``: a cos α_i, a sin α_i; ``first`` is the node index of the first free
    node; the reactions (N) and the walls' slopes h'(x), l'(x) (0: flat) run over the
    free nodes. λ is the
    least-squares solution of stationarity ∂L/∂α_i = g_i + a cos α_i S_i
    − a sin α_i X_i = 0, with g the springs' gradient (none when the right end is
    free). ``ok`` is False when a joint joins links that are not neighbours (the
    Hessian is then not tridiagonal).
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
    # ∂L/∂y_q and ∂L/∂x_q at every node: the loads (half of each adjacent link's) and
    # the reactions, R (y − h(x)) above and R' (l(x) − y) below
    fy = np.zeros(links + 1)
    fx = np.zeros(links + 1)
    for i in range(links):
        fy[i] -= 0.5 * link_load[i]
        fy[i + 1] -= 0.5 * link_load[i]
    for i in range(forces_upper.size):
        fy[first + i] += forces_upper[i] - forces_lower[i]
        fx[first + i] += forces_lower[i] * slope_lower[i] - forces_upper[i] * slope_upper[i]
    # suffix sums S_i, X_i, then λ at node N by least squares
    S = np.zeros(links)
    X = np.zeros(links)
    acc = accx = 0.0
    for i in range(links - 1, -1, -1):
        acc += fy[i + 1]
        accx += fx[i + 1]
        S[i] = acc
        X[i] = accx
    lam = 0.0
    if pinned_right:
        num = den = 0.0
        for i in range(links):
            num += (grad[i] + c[i] * S[i] - s[i] * X[i]) * c[i]
            den += c[i] * c[i]
        lam = -num / den if den > 0.0 else 0.0
    for i in range(links):
        diag[i] -= s[i] * (S[i] + lam) + c[i] * X[i]
    return diag, off, True


@njit(cache=True, inline="always")
def _pivot_sign(F, used, s, small, counts):
    """Eliminate slot ``s``; count its pivot in ``counts`` (negative, degenerate)."""
    p = _eliminate(F, used, s)
    counts[0] += p < 0.0
    counts[1] += abs(p) <= small


@njit(cache=True, inline="always")
def _close_segment(F, used, mu_y, mu_x, x_end, y_start, small, counts):
    """Eliminate an ended segment: its start's elastic height, its δy row's multiplier,
    then its δx row's multiplier with the end's δx as a 2 × 2 block. Returns the rows."""
    if y_start >= 0:
        _pivot_sign(F, used, y_start, small, counts)
    counts[0] += _eliminate(F, used, mu_y) < 0.0
    if mu_x < 0:
        return 1
    _eliminate_pair(F, used, mu_x, x_end, small, counts)
    return 2


@njit(cache=True)
def reduced_inertia(diag, off, c, s, event, stiffness, slope, curvature, use_x,
                    pinned_right):
    """Negative and degenerate pivots of H on the tangent space of the held nodes.

    ``diag``, ``off``: H (tridiagonal, links); ``c``, ``s``: a cos α_i, a sin α_i.
    Per node q = 0..links: ``event[q]`` FREE, HELD (a wall or the right pin holds it:
    δy_q = ``slope[q]`` δx_q) or ELASTIC (a spring ``stiffness[q]`` (N/mm) on δy_q);
    ``curvature[q]`` on δx_q². Node 0 is the left pin. ``use_x``: the δx rows (a
    curved wall somewhere); the right pin is a roller (its δx free). Returns
    (negative eigenvalues of the reduced Hessian, degenerate pivots).

    Order: link i is eliminated once link i + 1 is in the front; a segment that ends
    at node i + 1 is closed after link i, so that its multipliers' pivots are Schur
    complements over the whole segment, never structural zeros.
    """
    links = diag.size
    scale = 0.0
    for i in range(links):
        scale = max(scale, abs(diag[i]))
    small = DEGENERATE * max(scale, 1e-300)
    last_event = 0
    for q in range(1, links + 1):
        if event[q] != FREE:
            last_event = q
    F = np.zeros((FRONT + 1, FRONT))  # the front, and a scratch row
    used = np.zeros(FRONT, np.bool_)
    counts = np.zeros(2, np.int64)
    rows = 0
    prev = -1
    # the current segment's rows (δy, δx multipliers) and its start's elastic δy
    mu_y = mu_x = y_start = -1
    closing = np.full(4, -1, np.int64)  # a segment ended: mu_y, mu_x, end δx, start δy
    if last_event > 0:
        mu_y = _alloc(F, used)
        if use_x and not (_next(event, 0) == links and pinned_right):
            mu_x = _alloc(F, used)
    for i in range(links):
        t = _alloc(F, used)
        F[t, t] = diag[i]
        if prev >= 0:
            F[prev, t] = F[t, prev] = off[i - 1]
        if mu_y >= 0:
            F[mu_y, t] -= c[i]
            F[t, mu_y] -= c[i]
        if mu_x >= 0:
            F[mu_x, t] += s[i]
            F[t, mu_x] += s[i]
        if prev >= 0:
            _pivot_sign(F, used, prev, small, counts)
        if closing[0] >= 0:
            rows += _close_segment(F, used, closing[0], closing[1], closing[2], closing[3],
                                   small, counts)
            closing[:] = -1
        prev = t
        q = i + 1
        if event[q] == FREE or mu_y < 0:
            continue
        x_end = -1
        if mu_x >= 0:  # the end's δx: its wall's curvature, its δx row
            x_end = _alloc(F, used)
            F[x_end, x_end] = curvature[q]
            F[mu_x, x_end] = F[x_end, mu_x] = 1.0
        y_end = -1
        if event[q] == ELASTIC:
            y_end = _alloc(F, used)
            F[y_end, y_end] = stiffness[q]
            F[mu_y, y_end] = F[y_end, mu_y] = 1.0
        elif x_end >= 0:  # held on a wall: δy_q = slope δx_q
            F[mu_y, x_end] = F[x_end, mu_y] = slope[q]
        closing[0], closing[1], closing[2], closing[3] = mu_y, mu_x, x_end, y_start
        mu_y = mu_x = -1
        if q < last_event:  # the next segment's rows, tied to this node's δx, δy
            mu_y = _alloc(F, used)
            nxt = _next(event, q)
            if use_x and not (nxt == links and pinned_right):
                mu_x = _alloc(F, used)
                if x_end >= 0:
                    F[mu_x, x_end] = F[x_end, mu_x] = -1.0
            if y_end >= 0:
                F[mu_y, y_end] = F[y_end, mu_y] = -1.0
            elif x_end >= 0:
                F[mu_y, x_end] = F[x_end, mu_y] = -slope[q]
        y_start = y_end
    if prev >= 0:
        _pivot_sign(F, used, prev, small, counts)
    if closing[0] >= 0:
        rows += _close_segment(F, used, closing[0], closing[1], closing[2], closing[3],
                               small, counts)
    if y_start >= 0:
        _pivot_sign(F, used, y_start, small, counts)
    return max(counts[0] - rows, 0), counts[1]


@njit(cache=True, inline="always")
def _next(event, q):
    """The next node after q that a wall, a spring or the pin holds (0: none)."""
    for r in range(q + 1, event.size):
        if event[r] != FREE:
            return r
    return 0


@njit(cache=True)
def unstable_directions(alpha, a, jl, jr, k, rest, link_load, first, forces_upper,
                        forces_lower, stiffness_upper, stiffness_lower, slope_upper,
                        slope_lower, curvature_upper, curvature_lower, threshold,
                        pinned_right):
    """The second-order check of an answer: (code, unstable directions, degenerate).

    ``code`` is CHECKED, or NOT_TRIDIAGONAL for a joint layout this check does not
    take. ``unstable directions`` counts the negative eigenvalues of the reduced
    Hessian of the Lagrangian (0: a strict local minimum on the contact set,
    unless a pivot is degenerate). Per free node: a node is held by its wall where
    its reaction exceeds ``threshold`` (N); ``stiffness_*`` are the walls' springs
    (N/mm, inf: rigid); ``slope_*``, ``curvature_*`` the walls' h', h'' at the
    node's x (0: flat).
    """
    links = alpha.size
    c = np.empty(links)
    s = np.empty(links)
    for i in range(links):
        c[i] = a * np.cos(alpha[i])
        s[i] = a * np.sin(alpha[i])
    return unstable_directions_at(alpha, c, s, jl, jr, k, rest, link_load, first,
                                  forces_upper, forces_lower, stiffness_upper,
                                  stiffness_lower, slope_upper, slope_lower, curvature_upper,
                                  curvature_lower, threshold, pinned_right)


@njit(cache=True)
def unstable_directions_at(alpha, c, s, jl, jr, k, rest, link_load, first, forces_upper,
                           forces_lower, stiffness_upper, stiffness_lower, slope_upper,
                           slope_lower, curvature_upper, curvature_lower, threshold,
                           pinned_right):
    """:func:`unstable_directions` given ``c``, ``s``: a cos α_i and a sin α_i (the caller
    has them: the judge's exact geometry, model.judge_checks.positions)."""
    links = alpha.size
    diag, off, ok = lagrangian_hessian(alpha, c, s, jl, jr, k, rest, link_load, first,
                                       forces_upper, forces_lower, slope_upper,
                                       slope_lower, pinned_right)
    if not ok:
        return NOT_TRIDIAGONAL, 0, 0
    event = np.zeros(links + 1, np.int64)
    stiffness = np.full(links + 1, np.inf)
    slope = np.zeros(links + 1)
    curvature = np.zeros(links + 1)
    use_x = False
    for i in range(forces_upper.size):
        q = first + i
        for side in range(2):
            R = forces_upper[i] if side == 0 else forces_lower[i]
            if not R > threshold:
                continue
            ks = stiffness_upper[i] if side == 0 else stiffness_lower[i]
            if np.isfinite(ks):
                event[q] = ELASTIC
                stiffness[q] = ks
            else:
                event[q] = HELD
                slope[q] = slope_upper[i] if side == 0 else slope_lower[i]
            # the wall's curvature in L: −R h''(x) above, +R' l''(x) below
            curvature[q] = -R * curvature_upper[i] if side == 0 else R * curvature_lower[i]
            use_x = use_x or slope[q] != 0.0 or curvature[q] != 0.0
    if pinned_right:
        event[links] = HELD
    neg, degenerate = reduced_inertia(diag, off, c, s, event, stiffness, slope, curvature,
                                      use_x, pinned_right)
    return CHECKED, neg, degenerate
