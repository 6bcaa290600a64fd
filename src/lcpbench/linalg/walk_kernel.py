"""One move of the dual walk on a twisted factor, compiled (large N).

:func:`lcpbench.solvers.banded._dual` moves from ``u`` (gradient ``g``) to the
minimiser on the face S: the held nodes onto their walls, d₀ = (wall − u) on S,
then Newton on the free nodes, d = d₀ − H_S⁻¹ r with r = g + H d₀ zeroed on S,
and the gradient there, g + H d. In numpy that is a face solve and two products
with H plus a dozen full-length array passes (~1.7 ms at N = 10⁵ besides the
face solve). Here it is one call: the same arithmetic (H x as Aᵀ(A x), never
the rounded H; the face solve of :mod:`.twisted_kernel`), with the face solve's
refinement optional: the walk carries g by exact products, so an unrefined face
solve leaves a residual on the free nodes that the next move's r takes up,
and every optimum the walk finds is refined to round-off before it is accepted
(:func:`lcpbench.solvers.compiled_walk.refine_on_face`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .face_kernel import matvec_into as _matvec
from .twisted_kernel import factor, resolve


@njit(cache=True)
def _held_product(A, fixed, x, out):
    """out += Aᵀ (A x) for x zero off the ``fixed`` nodes: O(held nodes), the same
    terms as :func:`_matvec` (column i of A lives in rows i − 1 .. i + 1)."""
    n = x.size
    for i in range(n):
        if not fixed[i] or x[i] == 0.0:
            continue
        for j in range(max(i - 1, 0), min(i + 2, n)):
            yj = A[j, i - j + 1] * x[i]
            for k in range(max(j - 1, 0), min(j + 2, n)):
                out[k] += A[j, k - j + 1] * yj


@njit(cache=True)
def face_move(rows, rrows, fixed, rfixed, R, filled, snap, B, bfilled, bsnap, tri,
              invR, invB, j0, k0, m, wall, u, g, refine, d, g_face, r, x, y):
    """Writes the move ``d`` to the face minimiser and the gradient there ``g_face``;
    False on a zero pivot (``fixed`` = S). ``r``, ``x``, ``y``: work arrays (n,)."""
    if not factor(rows, rrows, fixed, rfixed, R, filled, snap, B, bfilled, bsnap, tri,
                  invR, invB, j0, k0, m):
        return False
    n = u.size
    for i in range(n):
        d[i] = (wall[i] - u[i]) if fixed[i] else 0.0
        g_face[i] = 0.0
    _held_product(rows, fixed, d, g_face)  # H d₀: d₀ lives on the held nodes only
    for i in range(n):
        r[i] = 0.0 if fixed[i] else g[i] + g_face[i]
        x[i] = r[i]
    resolve(R, B, tri, invR, invB, m, x)
    if refine:  # the corrected seminormal equations, as twisted_kernel.face_solve
        for i in range(n):
            d[i] = 0.0 if fixed[i] else x[i]  # d as a work array until below
        _matvec(rows, d, g_face, y)
        for i in range(n):
            r[i] = r[i] - (x[i] if fixed[i] else g_face[i])
        resolve(R, B, tri, invR, invB, m, r)
        for i in range(n):
            x[i] += r[i]
        for i in range(n):
            d[i] = (wall[i] - u[i]) if fixed[i] else 0.0
    for i in range(n):
        d[i] -= x[i]
    _matvec(rows, d, g_face, y)
    for i in range(n):
        g_face[i] += g[i]
    return True


@njit(cache=True)
def violation(u, wall, S, side, i):
    """The violation of node i's wall (``side`` +1: u − upper, −1: lower − u); −inf on
    held nodes (as the numpy walk's v)."""
    if S[i]:
        return -np.inf
    return u[i] - wall[i] if side > 0 else wall[i] - u[i]


@njit(cache=True)
def _picks(u, wall, side, slack, S, reach, picks, npick):
    """Append to ``picks`` (node index; ``side`` in the sign) the nodes the walk adds on
    this wall: :func:`lcpbench.solvers.gallop.gallop_picks` when ``reach`` > 0, else
    :func:`lcpbench.solvers.banded._run_maxima`, in one pass without the v array.
    Returns the new count."""
    return picks_in(u, wall, side, slack, S, reach, picks, npick, 0, u.size - 1)


@njit(cache=True)
def picks_in(u, wall, side, slack, S, reach, picks, npick, start, stop):
    """:func:`_picks` scanning nodes ``start`` .. ``stop`` only (the fused walk of
    :mod:`lcpbench.linalg.twisted_walk_kernel` passes the violated range: every
    violated node lies there, so the same runs and the same picks)."""
    n = u.size
    i = start
    while i <= stop:
        if not violation(u, wall, S, side, i) > slack[i]:
            i += 1
            continue
        a = i
        while i + 1 < n and violation(u, wall, S, side, i + 1) > slack[i + 1]:
            i += 1
        b = i
        if reach > 0:
            left = a >= 1 and S[a - 1]
            right = b + 1 < n and S[b + 1]
            if (left or right) and b - a + 1 > reach:
                if left:
                    picks[npick] = side * (a + reach - 1 + 1)
                    npick += 1
                if right and not (left and b - reach + 1 == a + reach - 1):
                    picks[npick] = side * (b - reach + 1 + 1)
                    npick += 1
                i += 1
                continue
            best = a  # the run's deepest node (the first of equal ones)
            for k in range(a + 1, b + 1):
                if violation(u, wall, S, side, k) > violation(u, wall, S, side, best):
                    best = k
            picks[npick] = side * (best + 1)
            npick += 1
        else:  # every local maximum of the run (v_i >= v_{i-1}, v_i > v_{i+1})
            for k in range(a, b + 1):
                vk = violation(u, wall, S, side, k)
                lft = violation(u, wall, S, side, k - 1) if k >= 1 else -np.inf
                rgt = violation(u, wall, S, side, k + 1) if k + 1 < n else -np.inf
                if vk >= lft and vk > rgt:
                    picks[npick] = side * (k + 1)
                    npick += 1
        i += 1
    return npick


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
    m0 = ctl[0]
    if last >= 0:
        j0 = max(min(first - 1, m0), 0)
        k0 = max(min(n - 2 - last, n - m0), 0)
        return j0, k0, min(max((j0 + n - k0) // 2, 2), n - 2)
    return m0, n - m0, m0


@njit(cache=True)
def mix_key(i, side):
    """A 64-bit mix of (node, side) (splitmix64); the working set's key is their sum."""
    z = np.uint64(2 * i + (1 if side > 0 else 0)) + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@njit(cache=True)
def set_node(i, side, value, sigma, wall, S, rfixed, chg, ctl, key):
    """Node i onto its wall (side ±1, wall height ``value``) or off it (side 0);
    returns the working set's key after the change."""
    n = S.size
    if sigma[i] != 0.0:
        key -= mix_key(i, sigma[i])
    sigma[i] = side
    if side != 0.0:
        wall[i] = value
        key += mix_key(i, side)
    S[i] = side != 0.0
    rfixed[n - 1 - i] = S[i]
    chg[ctl[6]] = i
    ctl[6] += 1
    return key


@njit(cache=True)
def walk(rows, rrows, R, filled, snap, B, bfilled, bsnap, tri, invR, invB, prev, ctl,
         lo, hi, has_lo, slack, u, g, sigma, wall, warm_up, warm_lo, tie, max_iter, seen,
         d, g_face, r, x, y, S, rfixed, picks, chg, held, ratio):
    """The dual walk of :func:`lcpbench.solvers.banded._dual` on a twisted factor (large
    N), from a face minimiser (u, g, sigma, wall) to the next point where no wall is
    violated beyond ``slack``, every move one :func:`face_move` (unrefined). Returns
    0 there (the caller refines), 1 when a working set repeats, 2 at ``max_iter`` face
    solves, 3 on a zero pivot. ``prev``: the face of the last factorisation (the walk's
    face on entry); ``ctl`` = [twist m, face solves, reach, warm, refined, seen count,
    (work)] (in and out); ``seen``: the working sets' keys (a collision only hands over
    to the primal method). Work: d, g_face, r, x, y (n floats), S, rfixed (n bools),
    picks (2n ints), chg (3n ints), held (n ints), ratio (n floats).

    The bookkeeping is incremental (the numpy walk's ~20 full-length passes per face
    were as costly as the face solve's own): violations are computed where they are
    scanned, the working set's key is a sum of per-node hashes, the twist comes from
    the nodes changed since the last factorisation."""
    n = u.size
    key = np.uint64(0)
    for i in range(n):
        S[i] = sigma[i] != 0.0
        rfixed[n - 1 - i] = S[i]
        if S[i]:
            key += mix_key(i, sigma[i])
    ctl[6] = 0
    at_minimiser = True
    while True:
        if at_minimiser:
            npick = 0
            if ctl[3]:  # first, the warm contact set, where it is violated
                ctl[3] = 0
                for i in range(n):
                    if warm_up[i] and violation(u, hi, S, 1, i) > slack[i]:
                        picks[npick] = i + 1
                        npick += 1
                    elif has_lo and warm_lo[i] and violation(u, lo, S, -1, i) > slack[i]:
                        picks[npick] = -(i + 1)
                        npick += 1
            if npick == 0:
                npick = _picks(u, hi, 1, slack, S, ctl[2], picks, 0)
                if has_lo:
                    npick = _picks(u, lo, -1, slack, S, ctl[2], picks, npick)
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
        if not face_move(rows, rrows, S, rfixed, R, filled, snap, B, bfilled, bsnap, tri,
                         invR, invB, j0, k0, m, wall, u, g, False, d, g_face, r, x, y):
            return 3
        for k in range(ctl[6]):
            prev[chg[k]] = S[chg[k]]
        ctl[6] = 0
        ctl[0] = m
        # the reactions there are −σ g_face; move towards it until one turns negative
        # (each falling reaction's step fraction from g before the move)
        step = 1.0
        nfall = 0
        for i in range(n):
            if S[i]:
                sg = sigma[i] * g_face[i]
                if sg > 0.0:
                    lam = max(-sigma[i] * g[i], 0.0)
                    held[nfall] = i
                    ratio[nfall] = lam / (lam + sg)
                    if ratio[nfall] < step:
                        step = ratio[nfall]
                    nfall += 1
        if step < 1.0:
            for i in range(n):
                u[i] = u[i] + step * d[i]
                g[i] = g[i] + step * (g_face[i] - g[i])
            # release every wall whose reaction reaches zero here, ties within
            # round-off included (a symmetric chain has its contacts in mirror pairs)
            for k in range(nfall):
                if ratio[k] <= step + tie:
                    key = set_node(held[k], 0.0, 0.0, sigma, wall, S, rfixed, chg, ctl, key)
            at_minimiser = False
            continue
        for i in range(n):
            u[i] = u[i] + d[i]
            g[i] = g_face[i]
        at_minimiser = True
        ctl[4] = 0
