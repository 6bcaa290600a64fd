"""The frictional step's primal equations on an index set, in sparse rows, node by node
(banded): the system :mod:`lcpbench.model.friction_polish` solves (its note gives the
equations). A free right end borders the band: its rotation about the pin couples every
height (K = H + k_r r rᵀ, :func:`lcpbench.model.friction_step._solve_columns`), so the
rotation term ρ = rᵀ δy and a copy ς of the tip's height are two more unknowns, after
every node's, with two more equations (:func:`primal_system`). Compiled
(``@njit(cache=True)``), loaded with the polish.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: a friction pair's state in the index set
STICK, FORWARD, BACKWARD, OFF = 0, 1, -1, 2
#: a sticking pair's slip equation kept (else: the pair p whose T it is held against,
#: or HELD_ALONE: T held at the answer's, a run that a pinned end holds)
KEEP, HELD_ALONE = -2, -1


@njit(cache=True)
def by_node(node, links):
    """(start, order): the items of each node 0..links, ``order[start[i]:start[i + 1]]``
    (a counting sort, O(N + m))."""
    start = np.zeros(links + 2, np.int64)
    for k in range(node.size):
        start[node[k] + 1] += 1
    for i in range(links + 1):
        start[i + 1] += start[i]
    pos = start[:-1].copy()
    order = np.empty(node.size, np.int64)
    for k in range(node.size):
        order[pos[node[k]]] = k
        pos[node[k]] += 1
    return start, order


@njit(cache=True)
def layout(links, first, nh, has_tau, rs, ro, ps, po):
    """The unknowns' indices, node by node: (count, τ, Y, X, L, N, T); −1 where none
    (τ when an end holds x, Y at the pins)."""
    idx = 1 if has_tau else 0
    Y = np.full(links + 1, -1, np.int64)
    X = np.empty(links + 1, np.int64)
    L = np.empty(max(links, 1), np.int64)
    Nv = np.empty(ro.size, np.int64)
    Tv = np.empty(po.size, np.int64)
    for i in range(links + 1):
        if first <= i < first + nh:
            Y[i] = idx
            idx += 1
        X[i] = idx
        idx += 1
        if i < links:
            L[i] = idx
            idx += 1
        for k in range(rs[i], rs[i + 1]):
            Nv[ro[k]] = idx
            idx += 1
        for k in range(ps[i], ps[i + 1]):
            Tv[po[k]] = idx
            idx += 1
    return idx, (0 if has_tau else -1), Y, X, L, Nv, Tv


@njit(cache=True)
def _put(ei, ej, ev, ne, m, j, v):
    if v != 0.0 and j >= 0:
        ei[ne], ej[ne], ev[ne] = m, j, v
        return ne + 1
    return ne


@njit(cache=True)
def _fx(ei, ej, ev, ne, m, i, sign, rs, ro, ps, po, Nv, Tv, normal_xy, tangent_xy):
    """sign · F^x_i, the force along x at node i (its rows' n_x N, its pairs' t_x T)."""
    for k in range(rs[i], rs[i + 1]):
        r = ro[k]
        ne = _put(ei, ej, ev, ne, m, Nv[r], sign * normal_xy[r, 0])
    for k in range(ps[i], ps[i + 1]):
        c = po[k]
        ne = _put(ei, ej, ev, ne, m, Tv[c], sign * tangent_xy[c, 0])
    return ne


@njit(cache=True)
def border_size(rot):
    """The unknowns after the nodes' (the border): 2 (ρ, ς) at a free end (``rot`` = r,
    the free heights' arms about the pin), else 0."""
    return 2 if rot.size else 0


@njit(cache=True)
def tip_spring(bands):
    """s, the tip's spring of a free end's banded core (:func:`primal_system`): H's
    diagonal at the tip (the largest diagonal where that is not positive)."""
    s = bands[0, bands.shape[1] - 1]
    if not s > 0.0:
        s = np.max(np.abs(bands[0]))
    return s if s > 0.0 else 1.0


@njit(cache=True)
def border_values(v, rot, dy):
    """The border's unknowns of an answer (its heights ``dy``) put in ``v`` (the primal
    system's unknowns, :func:`primal_system`): ρ = rᵀ δy, ς = δy at the tip."""
    if rot.size:
        n = v.size
        acc = 0.0
        for j in range(rot.size):
            acc += rot[j] * dy[j]
        v[n - 2] = acc
        v[n - 1] = dy[rot.size - 1]
    return v


@njit(cache=True)
def primal_system(bands, f, t, k_tau, first, right_datum, gap, slip, compliance,
                  normal_node, normal_xy, friction_node, tangent_xy, mu, pair, rot, rot_k,
                  contact, state, hold, T0, eps_t):
    """The step's primal equations on an index set, in sparse rows: (ei, ej, ev, rhs,
    count, the unknowns' layout (τ, Y, X, L, N, T)). ``t``: tan α per link (as given:
    the caller levels it); ``contact`` per wall row, ``state`` per pair (STICK, FORWARD,
    BACKWARD, OFF), ``hold`` per pair (KEEP its slip equation, HELD_ALONE: T = T⁰, or
    the pair p: T − T_p = T⁰ − T⁰_p); ``eps_t``: a sticking pair's compliance (its slip
    equation t·(δx, δy) + ε_t (T − T⁰) = −s; 0: none). The equations come node by node, as the unknowns
    (:func:`layout`), so the system is banded; as many equations as unknowns. A free
    right end (``rot`` = r, the free heights' arms about the pin, and ``rot_k``: K = H +
    k_r r rᵀ) borders it (the module's note): the heights' rows get k_r r_j ρ, and the
    tip's row s δy_tip − s ς (s, :func:`tip_spring`: 0 where ς = δy_tip, and it makes
    the band's heights H + s e eᵀ, definite: the band alone is not singular on the
    rotation), and two rows come last, ρ − rᵀ δy = 0 and ς − δy_tip = 0 (the exact
    oracle's ρ, benchmarks/exact_friction.py); the count then includes ρ, ς (the last
    two, :func:`border_size`). Also
    returned: ``plain``, per entry whether it is in the system with ``eps_t`` = 0 (all
    but the compliances), and ``rhs0``, that system's right-hand side (the same entries
    and values, in the same order, as a call with ``eps_t`` = 0)."""
    nh, links = bands.shape[1], t.size
    has_tau = f.size > nh
    rs, ro = by_node(first + normal_node, links)
    ps, po = by_node(friction_node, links)
    n, tau, Y, X, L, Nv, Tv = layout(links, first, nh, has_tau, rs, ro, ps, po)
    nb = border_size(rot)
    rho, sig, tip, spring = n, n + 1, first + nh - 1, tip_spring(bands) if nb else 0.0
    n += nb
    cap = 16 * n + 4 * (ro.size + po.size) + 4 * nh + 16
    ei = np.empty(cap, np.int64)
    ej = np.empty(cap, np.int64)
    ev = np.empty(cap)
    rhs = np.zeros(n + 2)
    plain = np.ones(cap, np.bool_)
    stick_row = np.full(n + 2, -1, np.int64)  # the pair whose slip equation row m is
    ne, m = 0, 0
    for i in range(links + 1):
        if i == 0:
            if has_tau:  # k_τ τ − L_0 − F^x_0 = f_τ
                ne = _put(ei, ej, ev, ne, m, tau, k_tau)
                ne = _put(ei, ej, ev, ne, m, L[0], -1.0)
                ne = _fx(ei, ej, ev, ne, m, 0, -1.0, rs, ro, ps, po, Nv, Tv, normal_xy,
                         tangent_xy)
                rhs[m] = f[nh]
                m += 1
            if not right_datum:  # x_0 = τ (or 0)
                ne = _put(ei, ej, ev, ne, m, X[0], 1.0)
                ne = _put(ei, ej, ev, ne, m, tau, -1.0)
                m += 1
        else:  # δx_i − δx_{i−1} + tan α_{i−1} (δy_i − δy_{i−1}) = 0
            ne = _put(ei, ej, ev, ne, m, X[i], 1.0)
            ne = _put(ei, ej, ev, ne, m, X[i - 1], -1.0)
            ne = _put(ei, ej, ev, ne, m, Y[i], t[i - 1])
            ne = _put(ei, ej, ev, ne, m, Y[i - 1], -t[i - 1])
            m += 1
        if Y[i] >= 0:  # the heights' equilibrium at node i
            j = i - first
            for jj in range(max(0, j - 2), min(nh, j + 3)):
                ne = _put(ei, ej, ev, ne, m, Y[first + jj], bands[abs(j - jj), min(j, jj)])
            for k in range(rs[i], rs[i + 1]):
                ne = _put(ei, ej, ev, ne, m, Nv[ro[k]], -normal_xy[ro[k], 1])
            for k in range(ps[i], ps[i + 1]):
                ne = _put(ei, ej, ev, ne, m, Tv[po[k]], -tangent_xy[po[k], 1])
            if i >= 1:
                ne = _put(ei, ej, ev, ne, m, L[i - 1], t[i - 1])
            if i < links:
                ne = _put(ei, ej, ev, ne, m, L[i], -t[i])
            if nb:  # a free end: k_r r_j ρ, and at the tip s (δy_tip − ς)
                ne = _put(ei, ej, ev, ne, m, rho, rot_k * rot[j])
                if i == tip:
                    ne = _put(ei, ej, ev, ne, m, Y[i], spring)
                    ne = _put(ei, ej, ev, ne, m, sig, -spring)
            rhs[m] = f[j]
            m += 1
        if i < links:  # the link's horizontal force
            ne = _put(ei, ej, ev, ne, m, L[i], 1.0)
            if right_datum:  # L_i = L_{i−1} − F^x_i
                if i >= 1:
                    ne = _put(ei, ej, ev, ne, m, L[i - 1], -1.0)
                ne = _fx(ei, ej, ev, ne, m, i, 1.0, rs, ro, ps, po, Nv, Tv, normal_xy,
                         tangent_xy)
            else:  # L_i = L_{i+1} + F^x_{i+1}
                if i + 1 < links:
                    ne = _put(ei, ej, ev, ne, m, L[i + 1], -1.0)
                ne = _fx(ei, ej, ev, ne, m, i + 1, -1.0, rs, ro, ps, po, Nv, Tv, normal_xy,
                         tangent_xy)
            m += 1
        for k in range(rs[i], rs[i + 1]):
            r = ro[k]
            if contact[r]:  # n·(δx, δy) + N/k = −g
                ne = _put(ei, ej, ev, ne, m, X[i], normal_xy[r, 0])
                ne = _put(ei, ej, ev, ne, m, Y[i], normal_xy[r, 1])
                ne = _put(ei, ej, ev, ne, m, Nv[r], compliance[r])
                rhs[m] = -gap[r]
            else:
                ne = _put(ei, ej, ev, ne, m, Nv[r], 1.0)
            m += 1
        for k in range(ps[i], ps[i + 1]):
            c = po[k]
            st = state[c]
            if st == OFF:
                ne = _put(ei, ej, ev, ne, m, Tv[c], 1.0)
            elif st == STICK and hold[c] == KEEP:  # t·(δx, δy) = −s
                ne = _put(ei, ej, ev, ne, m, X[i], tangent_xy[c, 0])
                ne = _put(ei, ej, ev, ne, m, Y[i], tangent_xy[c, 1])
                if eps_t != 0.0:
                    plain[ne] = False
                ne = _put(ei, ej, ev, ne, m, Tv[c], eps_t)
                rhs[m] = -slip[c] + eps_t * T0[c]
                stick_row[m] = c
            elif st == STICK:  # T held at the answer's split
                ne = _put(ei, ej, ev, ne, m, Tv[c], 1.0)
                rhs[m] = T0[c]
                if hold[c] >= 0:
                    ne = _put(ei, ej, ev, ne, m, Tv[hold[c]], -1.0)
                    rhs[m] -= T0[hold[c]]
            else:  # T + σ Σ μ N = 0 (the pair's rows are at its node)
                ne = _put(ei, ej, ev, ne, m, Tv[c], 1.0)
                for kk in range(rs[i], rs[i + 1]):
                    r = ro[kk]
                    if pair[r] == c:
                        ne = _put(ei, ej, ev, ne, m, Nv[r], st * mu[r])
            m += 1
        if i == links and right_datum:  # x_N held
            ne = _put(ei, ej, ev, ne, m, X[links], 1.0)
            m += 1
    if nb:  # the border's rows: ρ − rᵀ δy = 0, ς − δy_tip = 0
        ne = _put(ei, ej, ev, ne, m, rho, 1.0)
        for j in range(nh):
            ne = _put(ei, ej, ev, ne, m, Y[first + j], -rot[j])
        m += 1
        ne = _put(ei, ej, ev, ne, m, sig, 1.0)
        ne = _put(ei, ej, ev, ne, m, Y[tip], -1.0)
        m += 1
    rhs0 = rhs[:m].copy()
    for r in range(m):
        if stick_row[r] >= 0:
            rhs0[r] = -slip[stick_row[r]] + 0.0 * T0[stick_row[r]]
    return ei[:ne], ej[:ne], ev[:ne], rhs[:m], n, (tau, Y, X, L, Nv, Tv), plain[:ne], rhs0
