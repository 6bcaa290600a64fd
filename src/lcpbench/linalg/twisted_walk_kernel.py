"""The dual walk on a twisted factor, compiled, each face move fused into three passes (large N).

The walk of :func:`lcpbench.solvers.banded._dual` moves from a face minimiser
to the next: the held nodes onto their walls, d₀ = (wall − u) on S, then Newton
on the free nodes, d = d₀ − H_S⁻¹ r with r = g + H d₀ zeroed on S, and the
gradient there, g + H d. Written as numpy passes that is the face's twisted
factor (local: the rows between the first and last change), then about a dozen
full-length passes (d₀, H d₀, r, the two sweeps of the solve, d, the two
halves of H d, g_face, the ratio test, the update of u and g). At N = 10⁵ the
walk has 2–6 held nodes and the arrays (~20 of 0.8 MB) do not fit in the
cache: a move costs its memory traffic, ~2.3 ms, and the walk ~half of a solve.

Here the same move (H x as Aᵀ(A x), never the rounded H; the face solve of
:mod:`.twisted_kernel`, unrefined: the walk carries g by exact products, so the
face solve's residual on the free nodes is taken up by the next move's r, and
every optimum the walk finds is refined to round-off before it is accepted,
:func:`lcpbench.solvers.compiled_walk.refine_on_face`), in three passes:

1. the forward sweeps of M y = r from both ends, r = g + H d₀ (zero on S)
   formed on the fly (H d₀ lives next to the held nodes: :func:`_held_product`
   over the held nodes only);
2. the back-substitution M x = y from the twist outwards;
3. d = d₀ − x, H d = Aᵀ(A d) and the update of u and g in one pass, with A d
   and d in a sliding window of registers; the ratio test before it needs
   g_face = g + H d on the held nodes only (:func:`_hd_at`, the same sums).

Loaded only through :func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .twisted_kernel import factor, twist, twist_middle
from .walk_key import walk_key  # the working set's key (both walks')
from .walk_picks import picks_in, warm_picks  # the pick rule (both walks')

# the walk's bookkeeping: picks, working-set keys, the twist window

@njit(cache=True)
def add_picks(picks, npick, seen, key, hi, lo, sigma, wall, S, rfixed, chg, ctl):
    """The walk's step to its next working set: ``(True, key)`` where the set ``key``
    was met before (the walk stops), else the set recorded in ``seen`` and the picks
    fixed on their walls: ``(False, the new set's key)``."""
    for k in range(ctl[5]):
        if seen[k] == key:
            return True, key
    if ctl[5] < seen.size:
        seen[ctl[5]] = key
        ctl[5] += 1
    for k in range(npick):
        i = abs(picks[k]) - 1
        if S[i]:  # (a node violates one wall at a time; the upper first)
            continue
        if picks[k] > 0:
            key = set_node(i, 1.0, hi[i], sigma, wall, S, rfixed, chg, ctl, key)
        else:
            key = set_node(i, -1.0, lo[i], sigma, wall, S, rfixed, chg, ctl, key)
    return False, key


@njit(cache=True)
def twist_window(chg, ctl, S, prev, n):
    """(j0, k0, m) of this face's factor against the last one (TwistedFactor._twist),
    from the nodes changed since (``chg``, the first ``ctl[6]``) and the last twist
    ``ctl[0]``."""
    first, last = n, -1
    for k in range(ctl[6]):
        i = chg[k]
        if S[i] != prev[i]:
            first = min(first, i)
            last = max(last, i)
    return twist(first, last, ctl[0], n)


@njit(cache=True)
def set_node(i, side, value, sigma, wall, S, rfixed, chg, ctl, key):
    """Node i onto its wall (side ±1, wall height ``value``) or off it (side 0);
    returns the working set's key after the change."""
    n = S.size
    if sigma[i] != 0.0:
        key ^= walk_key(i, sigma[i])
    sigma[i] = side
    if side != 0.0:
        wall[i] = value
        key ^= walk_key(i, side)
    S[i] = side != 0.0
    rfixed[n - 1 - i] = S[i]
    chg[ctl[6]] = i
    ctl[6] += 1
    return key


@njit(cache=True)
def _held_product(A, hl, nh, wall, u, hd):
    """hd += Aᵀ (A d₀), d₀ = wall − u on the held nodes ``hl[:nh]`` (ascending), zero
    elsewhere: O(held nodes), the terms of :func:`lcpbench.linalg.face_kernel.matvec_into`
    (column i of A lives in rows i − 1 .. i + 1; hd is zero outside ±2 of the held
    nodes)."""
    n = u.size
    for h in range(nh):
        i = hl[h]
        xi = wall[i] - u[i]
        if xi == 0.0:
            continue
        for j in range(max(i - 1, 0), min(i + 2, n)):
            yj = A[j, i - j + 1] * xi
            for k in range(max(j - 1, 0), min(j + 2, n)):
                hd[k] += A[j, k - j + 1] * yj


@njit(cache=True)
def _d(S, wall, u, x, i):
    """d_i = d₀_i − x_i, the move to the face minimiser."""
    return ((wall[i] - u[i]) if S[i] else 0.0) - x[i]


@njit(cache=True)
def _ad(A, S, wall, u, x, j):
    """(A d)_j, as :func:`lcpbench.linalg.face_kernel.matvec_into` sums it."""
    n = u.size
    s = A[j, 1] * _d(S, wall, u, x, j)
    if j >= 1:
        s += A[j, 0] * _d(S, wall, u, x, j - 1)
    if j + 1 < n:
        s += A[j, 2] * _d(S, wall, u, x, j + 1)
    return s


@njit(cache=True)
def _hd_at(A, S, wall, u, x, i):
    """(Aᵀ A d)_i, as :func:`lcpbench.linalg.face_kernel.matvec_into` sums it."""
    n = u.size
    s = A[i, 1] * _ad(A, S, wall, u, x, i)
    if i + 1 < n:
        s += A[i + 1, 0] * _ad(A, S, wall, u, x, i + 1)
    if i >= 1:
        s += A[i - 1, 2] * _ad(A, S, wall, u, x, i - 1)
    return s


@njit(cache=True)
def _r(S, g, hd, i):
    """r_i = g_i + (H d₀)_i off S, 0 on S."""
    return 0.0 if S[i] else g[i] + hd[i]


@njit(cache=True)
def _solve(R, B, tri, invR, invB, m, S, g, hd, x):
    """x = (MᵀM)⁻¹ r (:func:`lcpbench.linalg.twisted_kernel.resolve` of r, r formed where
    the sweep reads it)."""
    n = x.size
    mb = n - m
    x[0] = _r(S, g, hd, 0) * invR[0]
    x[n - 1] = _r(S, g, hd, n - 1) * invB[0]
    if m - 1 > 1:
        x[1] = (_r(S, g, hd, 1) - R[1, 0] * x[0]) * invR[1]
    if mb - 1 > 1:
        x[n - 2] = (_r(S, g, hd, n - 2) - B[1, 0] * x[n - 1]) * invB[1]
    both = min(m - 1, mb - 1)
    for i in range(2, both):  # the two sweeps together (two dependency chains in flight)
        x[i] = (_r(S, g, hd, i) - R[1, i - 1] * x[i - 1] - R[2, i - 2] * x[i - 2]) * invR[i]
        j = n - 1 - i
        x[j] = (_r(S, g, hd, j) - B[1, i - 1] * x[j + 1] - B[2, i - 2] * x[j + 2]) * invB[i]
    for i in range(max(both, 2), m - 1):
        x[i] = (_r(S, g, hd, i) - R[1, i - 1] * x[i - 1] - R[2, i - 2] * x[i - 2]) * invR[i]
    for i in range(max(both, 2), mb - 1):
        j = n - 1 - i
        x[j] = (_r(S, g, hd, j) - B[1, i - 1] * x[j + 1] - B[2, i - 2] * x[j + 2]) * invB[i]
    twist_middle(R, B, tri, m, mb, _r(S, g, hd, m - 1), _r(S, g, hd, m), x)
    for s in range(min(m - 1, mb - 1)):  # top row m − 2 − s, bottom row mb − 2 − s
        i = m - 2 - s
        x[i] = (x[i] - R[1, i] * x[i + 1] - R[2, i] * x[i + 2]) * invR[i]
        k = mb - 2 - s
        j = n - 1 - k
        x[j] = (x[j] - B[1, k] * x[j - 1] - B[2, k] * x[j - 2]) * invB[k]
    for i in range(m - 2 - min(m - 1, mb - 1), -1, -1):
        x[i] = (x[i] - R[1, i] * x[i + 1] - R[2, i] * x[i + 2]) * invR[i]
    for k in range(mb - 2 - min(m - 1, mb - 1), -1, -1):
        j = n - 1 - k
        x[j] = (x[j] - B[1, k] * x[j - 1] - B[2, k] * x[j - 2]) * invB[k]


@njit(cache=True)
def _update(A, S, wall, u, g, x, step, hi, lo, has_lo, slack):
    """u += step d and g += step (g_face − g) (step 1: g = g_face), g_face = g + Aᵀ(A d),
    d = d₀ − x, in one pass (d and A d in registers). Returns the first and last node
    (−1 when none) off S whose wall the new u violates beyond ``slack`` (at step 1:
    the range the next picks scan; :func:`lcpbench.linalg.walk_picks.picks_in`)."""
    n = u.size
    first, last = n, -1
    # window: d at i, i + 1 (d0, d1); A d at i − 1, i (ym, y0)
    d0 = _d(S, wall, u, x, 0)
    d1 = _d(S, wall, u, x, 1) if n > 1 else 0.0
    ym = 0.0
    y0 = A[0, 1] * d0
    if n > 1:
        y0 += A[0, 2] * d1
    for i in range(n):
        y1 = 0.0
        d2 = 0.0
        if i + 1 < n:  # (A d)_{i+1}
            if i + 2 < n:
                d2 = _d(S, wall, u, x, i + 2)
            y1 = A[i + 1, 1] * d1
            y1 += A[i + 1, 0] * d0
            if i + 2 < n:
                y1 += A[i + 1, 2] * d2
        s = A[i, 1] * y0
        if i + 1 < n:
            s += A[i + 1, 0] * y1
        if i >= 1:
            s += A[i - 1, 2] * ym
        gf = s + g[i]
        if step < 1.0:
            u[i] = u[i] + step * d0
            g[i] = g[i] + step * (gf - g[i])
        else:
            u[i] = u[i] + d0
            g[i] = gf
            if not S[i] and (u[i] - hi[i] > slack[i] or (has_lo and lo[i] - u[i] > slack[i])):
                if first == n:
                    first = i
                last = i
        d0, d1 = d1, d2
        ym, y0 = y0, y1
    return first, last


@njit(cache=True)
def walk(rows, rrows, R, filled, snap, B, bfilled, bsnap, tri, invR, invB, prev, ctl,
         lo, hi, has_lo, slack, u, g, sigma, wall, warm_up, warm_lo, tie, max_iter, seen,
         x, hd, S, rfixed, picks, chg, held, ratio, hl):
    """The dual walk of :func:`lcpbench.solvers.banded._dual` on a twisted factor (large
    N), from a face minimiser (u, g, sigma, wall) to the next point where no wall is
    violated beyond ``slack``, each face move fused (see the module). Returns 0 there
    (the caller refines), 1 when a working set repeats, 2 at ``max_iter`` face solves,
    3 on a zero pivot. ``prev``: the face of the last factorisation (the walk's face on
    entry); ``ctl`` = [twist m, face solves, reach, warm, refined, seen count, (work)]
    (in and out); ``seen``: the working sets' keys (a collision only hands over to the
    primal method). Work: x, hd (n floats), S, rfixed (n bools), picks (2n ints), chg
    (3n ints), held, hl (n ints), ratio (n floats).

    The bookkeeping is incremental (~20 full-length numpy passes per face were
    as costly as the face solve's own): violations are computed where they are
    scanned, the working set's key is the XOR of per-node keys, the twist comes from
    the nodes changed since the last factorisation."""
    n = u.size
    key = np.uint64(0)
    for i in range(n):
        S[i] = sigma[i] != 0.0
        rfixed[n - 1 - i] = S[i]
        if S[i]:
            key ^= walk_key(i, sigma[i])
        hd[i] = 0.0
    ctl[6] = 0
    at_minimiser = True
    vfirst, vlast = 0, n - 1  # where the walls may be violated (at entry: anywhere)
    while True:
        if at_minimiser:
            npick = 0
            if ctl[3]:  # first, the warm contact set, where it is violated
                ctl[3] = 0
                npick = warm_picks(u, hi, lo, has_lo, S, slack, warm_up, warm_lo, picks)
            if npick == 0:
                if vlast >= 0:  # the violated nodes lie in vfirst .. vlast
                    npick = picks_in(u, hi, 1, slack, S, ctl[2], picks, 0, vfirst, vlast)
                    if has_lo:
                        npick = picks_in(u, lo, -1, slack, S, ctl[2], picks, npick,
                                          vfirst, vlast)
                if ctl[2] > 0:
                    ctl[2] *= 2
                if npick == 0:
                    for k in range(ctl[6]):
                        prev[chg[k]] = S[chg[k]]
                    return 0
            repeat, key = add_picks(picks, npick, seen, key, hi, lo, sigma, wall, S, rfixed,
                                     chg, ctl)
            if repeat:
                return 1
        if ctl[1] >= max_iter:
            return 2
        ctl[1] += 1
        j0, k0, m = twist_window(chg, ctl, S, prev, n)
        # the walk holds nodes on rigid walls only: no spring rows (x[:0], empty)
        if not factor(rows, rrows, S, rfixed, x[:0], x[:0], R, filled, snap, B, bfilled,
                      bsnap, tri, invR, invB, j0, k0, m):
            return 3
        for k in range(ctl[6]):
            prev[chg[k]] = S[chg[k]]
        ctl[6] = 0
        ctl[0] = m
        nh = 0
        for i in range(n):  # the held nodes, ascending (a pass over n bytes)
            if S[i]:
                hl[nh] = i
                nh += 1
        _held_product(rows, hl, nh, wall, u, hd)
        _solve(R, B, tri, invR, invB, m, S, g, hd, x)
        for h in range(nh):  # hd back to zero
            i = hl[h]
            for k in range(max(i - 2, 0), min(i + 3, n)):
                hd[k] = 0.0
        # the reactions there are −σ g_face; move towards it until one turns negative
        step = 1.0
        nfall = 0
        for h in range(nh):
            i = hl[h]
            sg = sigma[i] * (_hd_at(rows, S, wall, u, x, i) + g[i])
            if sg > 0.0:
                lam = max(-sigma[i] * g[i], 0.0)
                held[nfall] = i
                ratio[nfall] = lam / (lam + sg)
                if ratio[nfall] < step:
                    step = ratio[nfall]
                nfall += 1
        vfirst, vlast = _update(rows, S, wall, u, g, x, step, hi, lo, has_lo, slack)
        if step < 1.0:
            for k in range(nfall):
                if ratio[k] <= step + tie:
                    key = set_node(held[k], 0.0, 0.0, sigma, wall, S, rfixed, chg, ctl, key)
            at_minimiser = False
            continue
        at_minimiser = True
        ctl[4] = 0
