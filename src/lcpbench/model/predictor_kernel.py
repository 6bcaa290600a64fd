"""The continuation predictor, compiled once: the start of a scene from the answers
solved before it (:class:`lcpbench.studies.continuation.Solved`, which calls
:func:`predict_start` on its planes' arrays, and the line kernel,
:func:`lcpbench.model.batch_kernel.solve_line`, on its line's).

The rules (:class:`~lcpbench.studies.continuation.Solved` states them): 1. across the
lines, the nearest answer at the same θ where neither it nor the line touches a wall;
2. a line that touches, beside a line at the nearest height that touches too: that
answer plus the extrapolated difference of the two lines; 3. the polynomial in θ
through the nearest answers of the scene's line (all touching a wall or all not;
``adaptive``: of the degree after the smallest change, :func:`best_degree`); 4. the
nearest answer at the same θ; 5. (the line kernel's, for several planes in one call)
the nearest answer of the scene's kin. Every function is ``@njit(cache=True)``;
``NUMBA_DISABLE_JIT=1`` runs them as plain Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def nearest_answers(s, by_h, theta, height, plane, ok, touch, most, idx, val):
    """The answers before ``s`` that ``ok`` accepts, of its plane (``plane``:
    each row's): on its line in θ (``by_h``) or at its θ (the other lines); nearest
    first, the latest answer per value, all touching a wall as the nearest does. Fills
    ``idx``, ``val``; the count."""
    at = theta[s] if by_h else height[s]
    vals = np.empty(s)
    ids = np.empty(s, np.int64)
    n = 0
    for i in range(s):
        if not ok[i] or plane[i] != plane[s]:
            continue
        if by_h:
            if height[i] != height[s]:
                continue
            v = theta[i]
        else:
            if theta[i] != theta[s]:
                continue
            v = height[i]
        if v == at:
            continue
        vals[n], ids[n] = v, i
        n += 1
    order = np.argsort(vals[:n], kind="mergesort")  # stable: equal values in the order added
    c = 0
    sv, si = np.empty(n), np.empty(n, np.int64)
    for q in range(n):
        v, i = vals[order[q]], ids[order[q]]
        if c and sv[c - 1] == v:
            si[c - 1] = i  # the latest answer per value
        else:
            sv[c], si[c] = v, i
            c += 1
    vals, ids = sv, si
    hi = 0
    while hi < c and vals[hi] < at:
        hi += 1
    lo = hi - 1
    got = 0
    while got < most and (lo >= 0 or hi < c):
        if hi >= c or (lo >= 0 and at - vals[lo] <= vals[hi] - at):
            v, i, lo = vals[lo], ids[lo], lo - 1
        else:
            v, i, hi = vals[hi], ids[hi], hi + 1
        if got and touch[i] != touch[idx[0]]:
            break
        idx[got], val[got] = i, v
        got += 1
    return got


@njit(cache=True)
def extrapolations(t, ts, values, m):
    """Row j: the polynomial through the first j + 1 of the ``m`` points (ts[i],
    values[i]) (distinct ts; Lagrange), evaluated at t. Each weight gains the factor
    d_j / (d_j − d_i) of the point j added, d_i = t − t_i."""
    d = np.empty(m)
    for i in range(m):
        d[i] = t - ts[i]
    W = np.zeros((m, m))
    W[0, 0] = 1.0
    for j in range(1, m):
        for i in range(j):
            W[j, i] = W[j - 1, i] * d[j] / (d[j] - d[i])
        p = 1.0
        for q in range(j):
            p = p * (d[q] / (d[q] - d[j]))
        W[j, j] = p
    cols = values.shape[1]
    ps = np.zeros((m, cols))
    for j in range(m):
        for i in range(m):
            w = W[j, i]
            for c in range(cols):
                ps[j, c] += w * values[i, c]
    return ps


@njit(cache=True)
def best_degree(ps, m):
    """Of the ``m`` successive extrapolations ``ps`` (rows, one more point each), the one
    after the smallest change max|p_(j+1) − p_j| (the last where m < 3)."""
    if m < 3:
        return ps[m - 1]
    best, at = np.inf, 0
    for j in range(m - 1):
        worst = 0.0
        for c in range(ps.shape[1]):
            worst = max(worst, abs(ps[j + 1, c] - ps[j, c]))
        if worst < best:
            best, at = worst, j
    return ps[at + 1]


@njit(cache=True)
def predict_start(s, theta, height, plane, kin, where, ok, touch, alphas, most, adaptive):
    """The start of scene ``s`` (θ, h: ``theta[s]``, ``height[s]``) from the accepted
    (``ok``) answers ``alphas`` before it (``touch``: each touches a wall), by the rules
    1-4 from the answers of its plane (at most ``most`` on its line), and
    where they find none (no answer of its plane on its line in θ or at its θ), 5. the
    nearest answer of its kin as it is (:func:`nearest_kin`): (start α, index of the
    answer whose last step warm-starts it); index −1: a cold start."""
    links = alphas.shape[1]
    none = np.empty(0)
    if most == 0:
        return none, -1
    li, lv = np.empty(most, np.int64), np.empty(most)
    ai, av = np.empty(1, np.int64), np.empty(1)
    nl = nearest_answers(s, True, theta, height, plane, ok, touch, most, li, lv)
    na = nearest_answers(s, False, theta, height, plane, ok, touch, 1, ai, av)
    line_touches = nl > 0 and touch[li[0]]
    if na and not touch[ai[0]] and not line_touches:  # 1.
        return alphas[ai[0]].copy(), ai[0]
    if line_touches and nl < most and na and touch[ai[0]]:  # 2.
        other_h = av[0]
        ts, diff, c = np.empty(nl), np.empty((nl, links)), 0
        for q in range(nl):
            o = -1
            for i in range(s):  # the latest accepted answer at (other_h, θ_q)
                if ok[i] and plane[i] == plane[s] and height[i] == other_h \
                        and theta[i] == lv[q]:
                    o = i
            if o < 0 or not touch[o]:
                break
            ts[c] = lv[q]
            diff[c] = alphas[li[q]] - alphas[o]
            c += 1
        if c:
            ps = extrapolations(theta[s], ts, diff, c)
            return alphas[ai[0]] + ps[c - 1], li[0]
    if nl:  # 3.
        vals = np.empty((nl, links))
        for q in range(nl):
            vals[q] = alphas[li[q]]
        ps = extrapolations(theta[s], lv, vals, nl)
        return (best_degree(ps, nl) if adaptive else ps[nl - 1]).copy(), li[0]
    if na:  # 4.
        return alphas[ai[0]].copy(), ai[0]
    i = nearest_kin(s, kin, where, ok)  # 5.
    if i >= 0:
        return alphas[i].copy(), i
    return none, -1


@njit(cache=True)
def nearest_kin(s, kin, where, ok):
    """Rule 5 of :func:`predict_start`: the accepted answer before ``s`` of its kin (``kin``:
    each row's, −1 none; scenes the same but for θ, h and the walls' stiffness) nearest
    to it in the coordinates ``where`` (a row each, Euclidean), the first of equals; −1
    where the scene has no kin or none is solved."""
    if kin[s] < 0:
        return -1
    best, at = np.inf, -1
    for i in range(s):
        if not ok[i] or kin[i] != kin[s]:
            continue
        d = 0.0
        for c in range(where.shape[1]):
            d += (where[i, c] - where[s, c]) ** 2
        if d < best:
            best, at = d, i
    return at
