"""The dual active-set walk, compiled: :func:`dual_active_set`, and its entry for any
box QP, :func:`box_qp`.

The walk of :func:`lcpbench.solvers.banded.solve_banded_qp` with ``method="dual"``
(its module docstring: Goldfarb & Idnani specialised to bounds; the walk with block
additions, its refinement), on a QP's bands H (the banded step of eqs. 20-31 for the
contact step) and its linear term c. Its faces are solved by the
banded LDLᵀ of :mod:`lcpbench.linalg.ldl_kernel`, restarted at the first node a change
reaches; those of a QP with a few more sub-diagonals by the banded Cholesky of the
whole face, and of a wide one (a dense LCP's M) by LAPACK's Cholesky of the free
block (:func:`face_factor`: the choice is made by the factor's type when numba
compiles, so the contact step's walk holds neither a LAPACK call nor an extra call). The refinement at
an optimum takes the contact step's exact gradient (:func:`grad_into`,
ContactStep.gradient, from the step's joint stencil), a QP's H u + c.

The solve kernel (:mod:`lcpbench.model.compiled_kernel`) runs it inside its outer
loop; :func:`lcpbench.model.step_solver.solve_step` on one step; the back-end
"active-set" (:mod:`lcpbench.solvers.banded`) on any other QP, and so
``lcpbench.solvers.solve_lcp(M, q, solver="active-set")``, through :func:`box_qp`.
Every pass writes into work arrays the caller allocates once (the rows below). Loaded only through
:func:`lcpbench.numba_cache.kernel_module` (see there).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba.extending import overload

from ..linalg.ldl_kernel import refactor as _refactor  # the faces' LDLᵀ (one dependent
from ..linalg.ldl_kernel import resolve as _resolve  # chain: a division, not a square root)
from ..linalg.walk_key import walk_key  # the working set's key (both walks')
from ..linalg.walk_picks import picks_in, warm_picks  # the pick rule (both walks')
from ..linalg.wide_face_kernel import free_block_factor, free_block_resolve  # wider H's faces
from ..thresholds import TIE

EPS = np.finfo(np.float64).eps
TINY = np.finfo(np.float64).tiny
# the step stopped: the caller falls back (model.compiled.reference; banded: the primal)
BAIL_PRIMAL, BAIL_NOT_PD, BAIL_REPEAT, BAIL_LIMIT, BAIL_CERT, BAIL_JUDGE = 10, 11, 12, 13, 14, 15

# Work arrays, allocated once per solve (model.compiled_kernel.workspace); no loop
# allocates but the free block of the dense faces (box_qp). Rows of ``wn`` (free nodes):
U, G, SIG, WALL, D, RES, GF, RATIO, LIN, ORIG, RUP, RLO, NET, U2, OUT_U, DIR, TRY, WU, SHIFT, \
    FSHIFT, SLACK = range(21)
# rows of ``wb``: the working set S, the face factored, the additions, the warm walls, the
# nodes of S held *on* their wall (a rigid one; the others are held by its spring)
S_, FACT, JUP, JLO, WUP, WLO, ROWS, PREV_UP, PREV_LO, ELIM = range(10)


@njit(cache=True)
def grad_into(out, m, u, gp, T):
    """ContactStep.gradient, Jᵀ k (φ̂(u) − φ*) − f + T (u − u₀) about the
    linearisation point u₀, into ``out``; ``gp`` = (coef, b0, fs, links, origin,
    phi_origin, k, rest, nodal_load); T: the Newton step's geometric bands (zero for
    a Gauss–Newton step: adding them changes nothing but the sign of a zero; with no
    columns, not added: :meth:`~lcpbench.model.step.ContactStep.gradient`'s). Joint
    j's three columns are the nodes j + b0 − fs + (0, 1, 2); the interior rows are
    summed without the end tests, in the same order as the ends (three passes)."""
    coef, b0, fs, links, origin, phi_origin, k, rest, load = gp
    n, nj = u.size, coef.shape[0]
    off = b0 - fs
    for j in range(nj):  # J (u − u₀), then the moments
        i = off + j
        if i >= 0 and i + 2 < n:
            s = ((coef[j, 0] * (u[i] - origin[i]) + coef[j, 1] * (u[i + 1] - origin[i + 1]))
                 + coef[j, 2] * (u[i + 2] - origin[i + 2]))
        else:
            s = 0.0
            for c in range(3):
                du = u[i + c] - origin[i + c] if 0 <= i + c < n else 0.0
                s = coef[j, c] * du if c == 0 else s + coef[j, c] * du
        m[j] = ((s + phi_origin[j]) - rest[j]) * k[j]
    for i in range(n):  # Jᵀ m, then + T (u − u₀) summed as linalg.banded_matvec
        j = i - off
        if j - 2 >= 0 and j < nj:
            s = ((0.0 + coef[j, 0] * m[j]) + coef[j - 1, 1] * m[j - 1]) + coef[j - 2, 2] * m[j - 2]
        else:
            s = 0.0
            for c in range(3):
                if 0 <= j - c < nj:
                    s += coef[j - c, c] * m[j - c]
        out[i] = s - load[i]
        if T.shape[1]:  # (no columns: no T, ContactStep.gradient's Gauss–Newton step)
            t = T[0, i] * (u[i] - origin[i])
            if i >= 1:
                t += T[1, i - 1] * (u[i - 1] - origin[i - 1])
            if i + 1 < n:
                t += T[1, i] * (u[i + 1] - origin[i + 1])
            out[i] += t
    return out


@njit(cache=True)
def matvec_row(bands, x, i, n, absolute):
    """Row i of H x (of |H| |x| when ``absolute``), H with two sub-diagonals in lower
    band storage (the contact step's), its entries from the left
    (:func:`_matvec_row_wide`: any bandwidth)."""
    if absolute:
        s = abs(bands[2, i - 2]) * abs(x[i - 2]) if i >= 2 else 0.0
        s += abs(bands[1, i - 1]) * abs(x[i - 1]) if i >= 1 else 0.0
        s += abs(bands[0, i]) * abs(x[i])
        s += abs(bands[1, i]) * abs(x[i + 1]) if i + 1 < n else 0.0
        s += abs(bands[2, i]) * abs(x[i + 2]) if i + 2 < n else 0.0
        return s
    s = bands[2, i - 2] * x[i - 2] if i >= 2 else 0.0
    s += bands[1, i - 1] * x[i - 1] if i >= 1 else 0.0
    s += bands[0, i] * x[i]
    s += bands[1, i] * x[i + 1] if i + 1 < n else 0.0
    s += bands[2, i] * x[i + 2] if i + 2 < n else 0.0
    return s


@njit(cache=True)
def _matvec_row_wide(bands, x, i, n, absolute):
    """:func:`matvec_row` for any bandwidth b: the sub-diagonals from the farthest, the
    diagonal, the super-diagonals from the nearest."""
    b = bands.shape[0] - 1
    s = 0.0
    for k in range(min(b, i), 0, -1):
        s += abs(bands[k, i - k]) * abs(x[i - k]) if absolute else bands[k, i - k] * x[i - k]
    s += abs(bands[0, i]) * abs(x[i]) if absolute else bands[0, i] * x[i]
    for k in range(1, min(b, n - 1 - i) + 1):
        s += abs(bands[k, i]) * abs(x[i + k]) if absolute else bands[k, i] * x[i + k]
    return s


@njit(cache=True)
def max_abs(x):  # max|x| and the slope's dot product are loops: loading the cache then
    m = 0.0  # needs neither numba's array reductions nor its BLAS (which import scipy)
    for v in x:
        m = max(m, abs(v))
    return m


@njit(cache=True)
def _move(bands, d, u, g, s, n):
    """u + s d and the gradient carried, g + s (g_face − g) with g_face = g + H d
    (s = 1: u + d and g_face), in one pass, H d row by row as :func:`matvec_row` sums it
    (the interior rows without its end tests); d is zeroed behind (the next face's
    d₀ is zero off its held nodes)."""
    full = s >= 1.0
    for i in range(n):
        if 2 <= i < n - 2:
            hd = (((bands[2, i - 2] * d[i - 2] + bands[1, i - 1] * d[i - 1]) + bands[0, i] * d[i])
                  + bands[1, i] * d[i + 1]) + bands[2, i] * d[i + 2]
        else:
            hd = matvec_row(bands, d, i, n, False)
        gf = g[i] + hd
        if full:
            u[i] = u[i] + d[i]
            g[i] = gf
        else:
            u[i] = u[i] + s * d[i]
            g[i] = g[i] + s * (gf - g[i])
        if i >= 2:
            d[i - 2] = 0.0
    for i in range(max(n - 2, 0), n):
        d[i] = 0.0


@njit(cache=True)
def _move_wide(bands, d, u, g, s, n):
    """:func:`_move` for any bandwidth (every row of H d read before d is zeroed)."""
    full = s >= 1.0
    for i in range(n):
        gf = g[i] + _matvec_row_wide(bands, d, i, n, False)
        if full:
            u[i] = u[i] + d[i]
            g[i] = gf
        else:
            u[i] = u[i] + s * d[i]
            g[i] = g[i] + s * (gf - g[i])
    for i in range(n):
        d[i] = 0.0


@njit(cache=True)
def dense_faces(fac):
    """Whether the faces are a wider H's (a 3-D ``fac``, any bandwidth:
    :mod:`lcpbench.linalg.wide_face_kernel`), not the banded LDLᵀ (2-D: two
    sub-diagonals). A constant of each
    compiled version of the walk, so its other branches drop out of the code."""
    return fac.ndim == 3


def face_factor(fac, bands, fixed, shift, c0, c1):
    """Factor the face ``fixed`` of H: the banded LDLᵀ restarted at column ``c0``
    (:func:`lcpbench.linalg.ldl_kernel.refactor`; a 2-D ``fac``, two sub-diagonals, the
    contact step's) or a wider H's face (a 3-D ``fac``, any bandwidth:
    :func:`lcpbench.linalg.wide_face_kernel.free_block_factor`). Compiled, the choice is
    made by ``fac``'s type and the one branch inlined into the walk
    (:func:`_face_factor_typed`): the banded walk's code holds neither a LAPACK call nor
    an extra call."""
    if fac.ndim == 3:
        return free_block_factor(fac, bands, fixed, shift)
    return _refactor(fac, bands, fixed, shift, c0, c1)


def face_resolve(fac, x):
    """x ← the last factored face's solve of x (:func:`face_factor`)."""
    if fac.ndim == 3:
        free_block_resolve(fac, x)
    else:
        _resolve(fac, x)


@overload(face_factor, inline="always")
def _face_factor_typed(fac, bands, fixed, shift, c0, c1):
    """numba's :func:`face_factor`: the branch of ``fac``'s type."""
    if fac.ndim == 3:
        return lambda fac, bands, fixed, shift, c0, c1: free_block_factor(fac, bands, fixed,
                                                                           shift)
    return lambda fac, bands, fixed, shift, c0, c1: _refactor(fac, bands, fixed, shift, c0, c1)


@overload(face_resolve, inline="always")
def _face_resolve_typed(fac, x):
    """numba's :func:`face_resolve`: the branch of ``fac``'s type."""
    if fac.ndim == 3:
        return lambda fac, x: free_block_resolve(fac, x)
    return lambda fac, x: _resolve(fac, x)


@njit(cache=True)
def dual_active_set(bands, linear, lo, hi, cu, cl, warm_up, warm_lo, max_iter, gp, ws):
    """(code, face solves): code 0 at the optimum (after refinement); u, g and sigma
    in the rows U, G, SIG of the work array ``ws[0]``.

    ``bands``: H in lower band storage. Its faces are factored as ``ws[5]`` says
    (:func:`face_factor`): the contact step's banded LDLᵀ (two sub-diagonals), or a
    wider H's (any bandwidth, :func:`box_qp`'s QPs: :mod:`lcpbench.linalg.wide_face_kernel`). ``gp``: the
    contact step's joint stencil, whose exact gradient (:func:`grad_into`) the
    refinement takes; with no joints (a QP) the refinement takes H u + c.

    ``cu``, ``cl``: the compliance 1/k (mm/N) of the upper and lower wall per node (0:
    rigid), or empty where no wall yields. A node on an elastic wall is held by the
    wall's spring, not on it: the face minimises Q(u) + ½ (u_i − h_i)² / c_i over it,
    factored in the compliance form (:func:`lcpbench.linalg.ldl_kernel.refactor`), so
    the walk is the rigid one's as c → 0 (the wall's reaction is −∂Q/∂u_i, never
    (u_i − h_i)/c_i). A working set met before
    (its hash in ``ws[8]``; a collision, at odds of 2⁻⁶⁴, only hands the solve to
    the caller's fall-back) stops the walk.

    Its bookkeeping is incremental: the held
    nodes, the walls picked and the nodes changed since the last factorisation as
    lists (``ws[11]``), r = g + H d₀ computed where d₀ reaches (d₀ lives on the held
    nodes), the ratio test on the held nodes, the move in one pass."""
    wn, wb, m, fac, seen, wi = ws[0], ws[1], ws[2][2], ws[5], ws[8], ws[11]
    u, g, sigma, wall, d, r, gf, ratio = wn[U], wn[G], wn[SIG], wn[WALL], wn[D], wn[RES], wn[GF], \
        wn[RATIO]
    S, factored = wb[S_], wb[FACT]
    held, picks, chg = wi[0], wi[1], wi[2]
    n = linear.size
    wide = dense_faces(fac)  # H of any bandwidth (else two sub-diagonals)
    exact = gp[0].shape[0] > 0  # the contact step's exact gradient (else a QP's H u + c)
    soft = cu.size == n and n > 0  # some wall yields: E (held on a wall) is not all of S
    E = wb[ELIM] if soft else S
    shift, fshift = wn[SHIFT], wn[FSHIFT]
    cshift = shift if soft else shift[:0]
    has_lo = warm = False
    for i in range(n):
        has_lo = has_lo or np.isfinite(lo[i])
        warm = warm or warm_up[i] or warm_lo[i]
        factored[i] = S[i] = E[i] = False  # the face ``fac`` holds (none fixed: H itself)
        g[i] = sigma[i] = wall[i] = d[i] = shift[i] = fshift[i] = 0.0
        u[i] = -linear[i]
    if not face_factor(fac, bands, factored, cshift, 0, n):
        return BAIL_NOT_PD, 0
    face_resolve(fac, u)
    slack = wn[SLACK]  # the picks' slack, the same for every node (walk_picks: one per node)
    slack[:] = 32 * EPS * (1.0 + max_abs(u))
    h, count, at_face_minimiser, it, refined = np.uint64(0), 0, True, 0, False
    nheld = nchg = 0
    while True:
        if at_face_minimiser:
            npick = 0
            if warm:  # first, the warm contact set, where it is violated (S is empty)
                warm = False
                npick = warm_picks(u, hi, lo, has_lo, S, slack, warm_up, warm_lo, picks)
            if npick == 0:  # then every run's local maxima (no galloping: reach 0)
                npick = picks_in(u, hi, 1, slack, S, 0, picks, 0, 0, n - 1)
                if has_lo:
                    npick = picks_in(u, lo, -1, slack, S, 0, picks, npick, 0, n - 1)
                if npick == 0 and refined:  # no wall crossed by the refinement
                    return 0, it
                if npick == 0:  # the optimum: one refinement on the face just factored
                    for i in range(n):
                        if E[i]:
                            u[i] = wall[i]
                    if exact:  # the contact step's gradient from its joint stencil
                        grad_into(g, m, u, gp, ws[10])
                    else:  # a QP's: H u + c
                        for i in range(n):
                            g[i] = linear[i] + (_matvec_row_wide(bands, u, i, n, False) if wide
                                                else matvec_row(bands, u, i, n, False))
                    for i in range(n):
                        r[i] = 0.0 if E[i] else g[i]
                        if S[i] and not E[i]:  # the spring's pull on a node it holds
                            r[i] += (u[i] - wall[i]) / shift[i]
                    face_resolve(fac, r)
                    for i in range(n):
                        gf[i] = g[i] - (_matvec_row_wide(bands, r, i, n, False) if wide
                                        else matvec_row(bands, r, i, n, False))
                    for i in range(n):
                        u[i] = u[i] - r[i]
                        g[i] = gf[i]
                    refined = True  # then the walls once more (solvers.banded._dual)
                    continue
            for q in range(count):
                if seen[q] == h:  # the same working set
                    return BAIL_REPEAT, it
            if count == seen.size:  # a limit of face solves far above 20 n + 50: the
                return BAIL_LIMIT, it  # caller's fall-back goes on (the history is not grown)
            seen[count] = h
            count += 1
            for q in range(npick):  # (a node violates one wall at a time; the upper first)
                i = abs(picks[q]) - 1
                if S[i]:
                    continue
                sigma[i] = 1.0 if picks[q] > 0 else -1.0
                wall[i] = hi[i] if picks[q] > 0 else lo[i]
                h ^= walk_key(i, sigma[i])
                S[i] = True
                if soft:
                    shift[i] = cu[i] if picks[q] > 0 else cl[i]
                    E[i] = not shift[i] > 0.0
                held[nheld] = i
                nheld += 1
                chg[nchg] = i
                nchg += 1
        if it >= max_iter:
            return BAIL_LIMIT, it
        it += 1
        # d₀: the held nodes onto their walls (d is zero elsewhere); r = g + H d₀ off S,
        # where d₀ reaches it, else g
        # (a node held by a spring keeps its row: r = g + H d₀ there, the spring's pull
        # being zero at d₀)
        for i in range(n):
            r[i] = 0.0 if E[i] else g[i]
        for q in range(nheld):
            j = held[q]
            d[j] = wall[j] - u[j]
        if wide:  # every row once, where d₀ moved a held node
            moved = False
            for q in range(nheld):
                moved = moved or d[held[q]] != 0.0
            for i in range(n):
                if moved and not E[i]:
                    r[i] = g[i] + _matvec_row_wide(bands, d, i, n, False)
        else:  # the rows d₀ reaches, node by node
            for q in range(nheld):
                j = held[q]
                if d[j] != 0.0:
                    for i in range(max(j - 2, 0), min(j + 3, n)):
                        if not E[i]:
                            r[i] = g[i] + matvec_row(bands, d, i, n, False)
        first, last = n, -1  # the nodes whose wall changed since the last factorisation
        for q in range(nchg):
            i = chg[q]
            if S[i] != factored[i] or shift[i] != fshift[i]:
                first, last = min(first, i), max(last, i)
                factored[i] = S[i]
                fshift[i] = shift[i]
        nchg = 0
        if first < n:
            stop = last + 1  # after the change, the first two fixed nodes in a row
            while stop + 1 < n and not (E[stop] and E[stop + 1]):
                stop += 1
            stop = min(stop + 2, n)
            if not face_factor(fac, bands, E, cshift, max(0, first - 2), stop):
                return BAIL_NOT_PD, it
        face_resolve(fac, r)
        for i in range(n):
            d[i] -= r[i]
        s = np.inf  # the ratio test, on the held nodes (g_face = g + H d there)
        for q in range(nheld):
            j = held[q]
            sg = sigma[j] * (g[j] + (_matvec_row_wide(bands, d, j, n, False) if wide
                                     else matvec_row(bands, d, j, n, False)))
            ratio[j] = np.inf
            if sg > 0.0:
                lam = max(-sigma[j] * g[j], 0.0)
                ratio[j] = lam / (lam + sg)
                s = min(s, ratio[j])
        if wide:
            _move_wide(bands, d, u, g, s, n)
        else:
            _move(bands, d, u, g, s, n)
        if s < 1.0:
            kept = 0
            for q in range(nheld):
                j = held[q]
                if ratio[j] <= s + TIE:  # ties within round-off go together
                    h ^= walk_key(j, sigma[j])
                    sigma[j] = 0.0
                    S[j] = E[j] = False
                    shift[j] = 0.0
                    chg[nchg] = j
                    nchg += 1
                else:
                    held[kept] = j
                    kept += 1
            nheld = kept
            at_face_minimiser = False
            continue
        at_face_minimiser = True
        refined = False


@njit(cache=True)
def box_qp(bands, linear, lo, hi, warm_up, warm_lo, max_iter, fac, coef, b0, fs, links,
           origin, phi_origin, k, rest, load, T):
    """The walk on min ½ uᵀHu + cᵀu over lo <= u <= hi: H positive definite in lower
    band storage ``bands`` (any bandwidth), c ``linear``; ``warm_up``, ``warm_lo``: a
    contact set to start from (nodes put on their walls first where they are violated).
    ``fac``: the faces' factor (:func:`face_factor`), 2-D (4, n) for H with two
    sub-diagonals (the banded LDLᵀ), 3-D (2, b + 1, n) with b + 1 < n for H with b
    sub-diagonals (the banded Cholesky of the whole face), 3-D (2, max(n, 2), n) for the
    Cholesky of the free block (H wide, a dense LCP's M). ``coef`` ..
    ``load``: a contact step's joint stencil (:func:`grad_into`'s ``gp``), ``T`` its
    curvature (no columns: none), whose exact gradient the refinement takes; no rows in
    ``coef``: a QP, refined with H u + c. Returns (code, face solves, u, the gradient
    there, σ): code 0 at the optimum, else a bail code (BAIL_NOT_PD, BAIL_REPEAT,
    BAIL_LIMIT)."""
    n = linear.size
    z = np.empty(0)
    ws = (np.empty((21, n)), np.empty((10, n), np.bool_), np.empty((4, coef.shape[0])), z, z,
          fac, z, z, np.empty(min(max_iter, 20 * n + 50) + 2, np.uint64), z, T,
          np.empty((3, n), np.int64))
    gp = (coef, b0, fs, links, origin, phi_origin, k, rest, load)
    code, it = dual_active_set(bands, linear, lo, hi, z, z, warm_up, warm_lo, max_iter, gp,
                               ws)
    wn = ws[0]
    return code, it, wn[U].copy(), wn[G].copy(), wn[SIG].copy()
