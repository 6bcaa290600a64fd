"""The default solve compiled: assembly, dual active set, line search, outer loop.

The outer loop (:func:`outer_loop`) is one, on flat walls (:func:`solve_chain`) and on
walls of any profile (:func:`solve_profile_chain`, with the merit, start and stop of
:mod:`lcpbench.model.profile_kernel`).

Compiled (``@njit(cache=True)``): :func:`banded_step` (the banded step of eqs. 20-31,
the one assembly: every driver's, :func:`lcpbench.model.compiled_driver.assemble_step`),
the step solved by the dual walk (:func:`lcpbench.solvers.dual_kernel.dual_active_set`,
the one walk: every back-end "active-set" call's too), its certificate and the judge's
natural residual (:mod:`lcpbench.model.compiled_dual`), and the globalised outer loop
(the Armijo rule on the exact energy, :mod:`.chain_kernel`'s; the compiled driver of
:mod:`lcpbench.model.compiled_driver` runs the same pieces around another back-end).

Three files hold the solve: this one (the chain, the assembly, the outer loop),
:mod:`lcpbench.model.compiled_dual` (the certificate and the judge's residual) and
:mod:`lcpbench.solvers.dual_kernel` (the walk). numba's on-disk cache of a function is
invalidated only when *its own* file changes, so
:func:`lcpbench.numba_cache.kernel_module` keeps the cache of every kernel under a hash
of all their sources (a split kernel never runs stale code); import this module
through it.

Nothing here decides "converged": the Python side builds the DriverOutput and judges it
(:mod:`lcpbench.model.judge`). What the kernel cannot do (the primal safeguard, a face
not positive definite, a step rejected, a cold solve whose line searches stall:
:data:`BAIL_STALL`) it reports with a code, and the caller falls back to compiled code
(:func:`lcpbench.model.compiled.reference`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.ldl_kernel import refactor
from ..solvers.dual_kernel import (  # the walk, its work rows, the step's gradient
    BAIL_CERT,
    BAIL_JUDGE,
    BAIL_LIMIT,
    BAIL_NOT_PD,
    BAIL_PRIMAL,
    BAIL_REPEAT,
    DIR,
    ELIM,
    EPS,
    FACT,
    GF,
    LIN,
    NET,
    ORIG,
    OUT_U,
    PREV_LO,
    PREV_UP,
    RATIO,
    RLO,
    ROWS,
    RUP,
    SIG,
    TRY,
    U2,
    WLO,
    WU,
    WUP,
    G,
    U,
    dual_active_set,
    grad_into,
)
from ..thresholds import (
    FLOOR_ULPS,
    GEOMETRY_SLACK,
    NEWTON_SWITCH,
    STALL_RUN,
    STALL_STEP,
    WALK_RTOL,
)
from .chain_kernel import (  # once (numba_cache)
    add_compensated,
    energy,
    energy_noise,
    energy_search,
    fit_heights,
    free_heights,
    predict_alpha,
    wall_penalty,
)
from .compiled_dual import (
    ALPHA,
    ALPHA0,
    COS_A,
    COS_T,
    INV,
    SIN_A,
    SIN_T,
    TRIAL,
    certify,
    judge_step,
)
from .profile_kernel import clipped_start, merit_search, penetration  # a profile's, once
from .wall_kernel import lagged_load, split_by_wall, walls_at

# outcome codes of solve_chain (the Python side turns them into reasons)
CONVERGED, MAX_OUTER, LINE_SEARCH, NO_FIT = 0, 1, 2, 3
#: bail code of a cold solve whose line searches cut the step to STALL_STEP or less
#: STALL_RUN outer steps running (kernel_call.BAIL_REASONS; the Python side treats it as
#: the step refusals it stands in for, model.compiled.REFUSED_STEPS)
BAIL_STALL = 16
#: a wall without a table of cubic pieces (flat walls: :func:`solve_chain`)
_NO_TABLE = np.empty((4, 0))
__all__ = ["BAIL_CERT", "BAIL_JUDGE", "BAIL_LIMIT", "BAIL_NOT_PD", "BAIL_PRIMAL", "BAIL_REPEAT",
           "BAIL_STALL", "CONVERGED", "LINE_SEARCH", "MAX_OUTER", "NO_FIT", "outer_loop",
           "solve_chain", "solve_profile_chain", "solve_step"]


@njit(cache=True)
def workspace(n, links, nj, max_iter):
    """The solve's work arrays, uninitialised: every entry is written before it is
    read (each pass sets its rows; the walk its lists and the hashes it compares),
    so nothing is zeroed that is not read (``seen`` alone holds 20 n + 50 hashes)."""
    return (np.empty((21, n)), np.empty((10, n), np.bool_), np.empty((4, nj)),
            np.empty((8, links)), np.empty((5, links + 2)), np.empty((4, n)),
            np.empty((3, n)), np.empty((nj, 3)),
            np.empty(min(max_iter, 20 * n + 50) + 2, np.uint64), np.empty(5), np.empty((2, n)),
            np.empty((3, n), np.int64))


# -- the banded step (model.step) -------------------------------------------------
@njit(cache=True)
def assemble_into(alpha, a, jl, jr, k, rest, fs, n, nodal_load, bands, linear, inv, coef,
                   origin, alpha0, phi_origin, t, wl, sines, cosines, tangent):
    """``sines``, ``cosines``: sin α and cos α (the solve kernel's from :func:`fit_heights`).
    ``tangent``: v = tan α − α as the reference (the compiled driver's assembly);
    else with tan α = sin α / cos α (equal to round-off, one transcendental call
    less per link: the solve kernel's)."""
    links = alpha.size
    nj = jr.size
    v = wl[0]
    for i in range(links):
        c = cosines[i]
        inv[i] = 1.0 / (a * c)
        v[i] = (np.tan(alpha[i]) if tangent else sines[i] / c) - alpha[i]
    for j in range(nj):
        wlj = inv[jl[j]] if jl[j] >= 0 else 0.0
        wr = inv[jr[j]]
        coef[j, 0] = wlj
        coef[j, 1] = -wlj - wr
        coef[j, 2] = wr
        phi0 = -v[jr[j]] + (v[jl[j]] if jl[j] >= 0 else 0.0)
        t[j] = k[j] * (phi0 - rest[j])
    b0 = jr[0]
    for i in range(n):  # H and c row by row: each sum in the order of the reference's passes
        x = fs + i  # (one pass over the joints per stencil column m, then the next m)
        dg = o1 = o2 = ln = 0.0
        for m in range(3):
            j = x - b0 - m
            if 0 <= j < nj:
                dg += k[j] * coef[j, m] ** 2
                ln += coef[j, m] * t[j]
                if m < 2:
                    o1 += k[j] * coef[j, m] * coef[j, m + 1]
                if m == 0:
                    o2 += k[j] * coef[j, 0] * coef[j, 2]
        bands[0, i] = dg
        bands[1, i] = o1 if i < n - 1 else 0.0
        bands[2, i] = o2 if i < n - 2 else 0.0
        linear[i] = ln - nodal_load[i]
    y = lost = 0.0  # the node heights, compensated (chain_kernel.add_compensated);
    if fs == 1:  # the free ones are the origin
        origin[0] = 0.0
    for i in range(links):
        y, lost = add_compensated(y, lost, a * sines[i])
        if fs - 1 <= i + 1 < fs - 1 + n:
            origin[i + 1 - (fs - 1)] = y + lost
    alpha0[:] = alpha
    if fs - 1 + n - 1 < links:  # the right end is pinned: close the chain
        alpha0[links - 1] += -(y + lost) * inv[links - 1]
    for j in range(nj):
        phi_origin[j] = alpha0[jr[j]] - (alpha0[jl[j]] if jl[j] >= 0 else 0.0)


@njit(cache=True)
def banded_step(alpha, a, jl, jr, k, rest, fs, n, nodal_load):
    """The contact step at α (eqs. 20-31; model.step.ContactStep's arrays): bands, c, the
    stencils of J and the linearisation point."""
    links, nj = alpha.size, jr.size
    bands, linear, inv, coef = np.zeros((3, n)), np.empty(n), np.empty(links), np.empty((nj, 3))
    origin, alpha0, phi_origin = np.empty(n), np.empty(links), np.empty(nj)
    assemble_into(alpha, a, jl, jr, k, rest, fs, n, nodal_load, bands, linear, inv, coef,
                   origin, alpha0, phi_origin, np.empty(nj), np.empty((5, links + 2)),
                   np.sin(alpha), np.cos(alpha), True)
    return bands, linear, inv, coef, origin, alpha0, phi_origin


@njit(cache=True)
def _newton(alpha, a, jl, jr, k, rest, fs, n, bands, linear, origin, T, fac, none, mu, sines,
            cosines):
    """model.newton.newton_step: T (the geometric bands) into ``T``, and H + T,
    c − T u₀ into the step where H + T is positive definite (True); else T = 0
    and the Gauss–Newton step stands (False)."""
    geometric_bands(alpha, a, jl, jr, k, rest, fs, n, T, mu, sines, cosines)
    if not positive_with(bands, T, fac, none, n):
        T[:] = 0.0
        return False
    for i in range(n):
        s = T[0, i] * origin[i]
        if i >= 1:
            s += T[1, i - 1] * origin[i - 1]
        if i + 1 < n:
            s += T[1, i] * origin[i + 1]
        linear[i] -= s
    for i in range(n):
        bands[0, i] += T[0, i]
        bands[1, i] += T[1, i]
    return True


@njit(cache=True)
def positive_with(bands, T, fac, none, n):
    """Whether H + T is positive definite (H in ``bands``, T's diagonal and
    sub-diagonal): its LDLᵀ into ``fac`` (LAPACK's dpbtrf in the reference); ``none``
    a scratch row. The Newton steps' test, the solve kernel's and the frictional
    step's."""
    for i in range(n):
        fac[0, i], fac[1, i], fac[2, i] = bands[0, i] + T[0, i], bands[1, i] + T[1, i], bands[2, i]
        none[i] = False
    return refactor(fac, fac, none, fac[0, :0], 0, n)


@njit(cache=True)
def geometric_bands(alpha, a, jl, jr, k, rest, fs, n, T, mu, sines, cosines):
    """model.newton.geometric_bands into ``T`` (diagonal, sub-diagonal): the curvature
    of the link angles in the heights times the links' net spring moments."""
    links = alpha.size
    mu[:] = 0.0
    for j in range(jr.size):  # the net spring moment on each link (np.add.at's order)
        mu[jr[j]] += k[j] * ((alpha[jr[j]] - (alpha[jl[j]] if jl[j] >= 0 else 0.0)) - rest[j])
    for j in range(jr.size):
        if jl[j] >= 0:
            mu[jl[j]] -= k[j] * ((alpha[jr[j]] - alpha[jl[j]]) - rest[j])
    for i in range(n):  # w = μ sin α / (a² cos³ α) on each link, to its two nodes
        node = fs - 1 + i
        T[0, i] = T[1, i] = 0.0
        if node < links:
            w = mu[node] * (sines[node] / (a * a * cosines[node] ** 3))
            T[0, i] += w
            T[1, i] = -w if i + 1 < n else 0.0
        if node >= 1:
            T[0, i] += mu[node - 1] * (sines[node - 1] / (a * a * cosines[node - 1] ** 3))


@njit(cache=True)
def _step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, lo, hi, L, F, cu, cl, warm_u, warm_up,
          warm_lo, warm_flags, max_iter, request, ws, gp, sines, cosines, newton):
    """One contact step at α (``sines``, ``cosines``: sin α, cos α) into the work
    arrays: assemble, dual walk, certificate, judge; (code, face solves), code 0:
    solved. ``cu``, ``cl``: the walls' compliances (empty: rigid walls)."""
    wn, wb, wj, wa = ws[0], ws[1], ws[2], ws[3]
    assemble_into(alpha, a, jl, jr, k, rest, fs, n, nodal_load, ws[6], wn[LIN], wa[INV], ws[7],
                   wn[ORIG], wa[ALPHA0], wj[0], wj[1], ws[4], sines, cosines, False)
    T = ws[10]
    T[:] = 0.0
    if newton:  # T = 0 where H + T is not positive definite
        _newton(alpha, a, jl, jr, k, rest, fs, n, ws[6], wn[LIN], wn[ORIG], T, ws[5],
                wb[FACT], ws[4][0], sines, cosines)
    return solve_assembled(n, lo, hi, L, F, cu, cl, warm_u, warm_up, warm_lo, warm_flags,
                            max_iter, request, ws, gp, T)


@njit(cache=True)
def solve_assembled(n, lo, hi, L, F, cu, cl, warm_u, warm_up, warm_lo, warm_flags, max_iter,
                     request, ws, gp, T):
    """The contact step assembled in the work arrays (H in ``ws[6]``, c in row LIN, the
    stencils and u₀ in ``gp``, the Newton bands in ``T``): dual walk from the warm
    sets, certificate, judge; (code, face solves), code 0: solved."""
    wn, wb, wj = ws[0], ws[1], ws[2]
    W_up, W_lo, bad = wb[WUP], wb[WLO], False
    for i in range(n):
        bad = bad or lo[i] > hi[i]
        W_up[i] = W_lo[i] = False
        if warm_flags & 1 and not np.isnan(warm_u[i]):  # the walls the last answer is on
            ui = min(max(warm_u[i], lo[i]), hi[i])
            W_up[i] = np.isfinite(hi[i]) and ui >= hi[i]
            W_lo[i] = np.isfinite(lo[i]) and ui <= lo[i]
        if warm_flags & 2:
            W_up[i] = W_up[i] or (warm_up[i] and np.isfinite(hi[i]))
        if warm_flags & 4:
            W_lo[i] = W_lo[i] or (warm_lo[i] and np.isfinite(lo[i]))
        W_lo[i] = W_lo[i] and not W_up[i]
    if bad:  # crossed walls: the reference hands this to the primal method
        return BAIL_PRIMAL, 0
    code, it = dual_active_set(ws[6], wn[LIN], lo, hi, cu, cl, W_up, W_lo, max_iter, gp, ws)
    if code != 0:
        return code, it
    u, grad, sigma, r_up, r_lo = wn[U], wn[G], wn[SIG], wn[RUP], wn[RLO]
    held_on = ws[1][ELIM]  # (written by the walk where a wall yields)
    soft = cu.size == n
    for i in range(n):
        if not soft or sigma[i] == 0.0 or held_on[i]:  # a spring's node indents its wall
            u[i] = min(max(u[i], lo[i]), hi[i])
        r_up[i] = max(-grad[i], 0.0) if sigma[i] > 0 else 0.0
        r_lo[i] = max(grad[i], 0.0) if sigma[i] < 0 else 0.0
    if not certify(u, r_up, r_lo, lo, hi, cu, cl, gp, wn[GF], wn[RATIO], wj[2], wj[3],
                    T) <= WALK_RTOL:
        return BAIL_CERT, it
    res = ws[9]
    ok = judge_step(u, ws[6], wn[LIN], lo, hi, cu, cl, gp, L, F, res, wn[NET], wn[U2], wb[ROWS],
                ws[5], wj[2], T, wn[GF])
    if not (ok and res[0] <= max(10.0 * request, FLOOR_ULPS * EPS * res[4])):
        return BAIL_JUDGE, it
    return 0, it


@njit(cache=True)
def contact_step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, lo, hi, L, F, cu, cl,
                  warm_u, warm_up, warm_lo, warm_flags, max_iter, request):
    """One cold contact step at α, its work arrays allocated: (code, u, r_up, r_lo,
    sigma, face solves, inv, α₀, origin, gp, residuals, R), code 0: solved (other codes:
    the arrays after the code are work rows, some never written, not an answer)."""
    ws = workspace(n, alpha.size, jr.size, max_iter)
    wn, wa = ws[0], ws[3]
    gp = (ws[7], jr[0], fs, alpha.size, wn[ORIG], ws[2][0], k, rest, nodal_load)
    code, it = _step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, lo, hi, L, F, cu, cl, warm_u,
                     warm_up, warm_lo, warm_flags, max_iter, request, ws, gp, np.sin(alpha),
                     np.cos(alpha), False)
    return (code, wn[U], wn[RUP], wn[RLO], wn[SIG], it, wa[INV], wa[ALPHA0], wn[ORIG], gp, ws[9],
            wn[NET])


@njit(cache=True)
def solve_step(bands, linear, lo, hi, cu, cl, coef, b0, fs, links, origin, phi_origin, k, rest,
               nodal_load, T, L, F, warm_u, warm_up, warm_lo, warm_flags, max_iter, request):
    """A contact step already assembled (:class:`lcpbench.model.step.ContactStep`'s
    arrays: H's bands, c, the walls, the compliances, J's stencils ``coef`` from
    shifted node ``b0``, u₀ and φ̂(u₀), the Newton bands ``T`` or zeros) by the walk,
    certificate and judge of the solve kernel: (code, u, r_up, r_lo, sigma, face
    solves, residuals, R), code 0: solved (else the arrays are work rows, not an
    answer). The public step call's compiled route
    (:func:`lcpbench.model.step_solver.solve_step` with the default back-end)."""
    n, nj = linear.size, coef.shape[0]
    ws = workspace(n, links, nj, max_iter)
    wn = ws[0]
    ws[6][:] = bands
    wn[LIN][:] = linear
    wn[ORIG][:] = origin
    ws[7][:] = coef
    ws[2][0][:] = phi_origin
    ws[10][:] = T
    gp = (ws[7], b0, fs, links, wn[ORIG], ws[2][0], k, rest, nodal_load)
    code, it = solve_assembled(n, lo, hi, L, F, cu, cl, warm_u, warm_up, warm_lo, warm_flags,
                                max_iter, request, ws, gp, ws[10])
    return code, wn[U], wn[RUP], wn[RLO], wn[SIG], it, ws[9], wn[NET]


@njit(cache=True)
def record_step(rec, count, it, t, dalpha, E):
    if count == rec.shape[1]:
        bigger = np.empty((4, 2 * rec.shape[1]))
        bigger[:, :count] = rec
        rec = bigger
    rec[0, count], rec[1, count], rec[2, count], rec[3, count] = it, t, dalpha, E
    return rec, count + 1


@njit(cache=True)
def _clipped_heights(u, alpha, a, fs, lo, hi):
    """The free nodes' heights of the chain at α, clipped to the walls, into u."""
    free_heights(u, alpha, a, fs)
    for i in range(u.size):
        u[i] = min(max(u[i], lo[i]), hi[i])


@njit(cache=True)
def solve_chain(rest_alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F, cu, cl,
                tol, max_outer, start_alpha, warm_u, warm_up, warm_lo, warm_flags,
                max_iter, request, newton=False):
    """:func:`outer_loop` on flat walls (the rows ``lo``, ``hi``; ``cu``, ``cl`` the
    elastic walls' compliances, empty where no wall yields). Returns ``(code, alpha,
    forces_upper, forces_lower, u, sigma, records, count, residuals, forces_net)``."""
    got = outer_loop(rest_alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                     cu, cl, tol, max_outer, start_alpha, warm_u, warm_up, warm_lo, warm_flags,
                     max_iter, request, newton, False, (hi, lo, cu[:0], _NO_TABLE, cu[:0],
                                                        _NO_TABLE), False, cu[:0], cu[:0])
    return got[0], got[1], got[2], got[3], got[4], got[5], got[6], got[7], got[8], got[9]


@njit(cache=True)
def solve_profile_chain(rest_alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo_rows,
                        hi_rows, L, F, ku, cu_, kl, cl_, channel, tol, max_outer, start_alpha,
                        mu_up, mu_lo, max_iter, request):
    """:func:`outer_loop` against walls of any profile: ``ku``, ``cu_`` (``kl``, ``cl_``)
    the upper (lower) wall's table, empty for a flat wall; ``hi_rows``, ``lo_rows`` the
    chain's rows (±inf: no wall at that node); ``channel``: reactions split between two
    walls; ``mu_up``, ``mu_lo``: the starting lagged reactions (zeros cold; written).
    Rigid walls, a cold start of the walk. Returns :func:`solve_chain`'s tuple plus the
    walls at the answer's nodes (upper, lower)."""
    n, none = lo_rows.size, np.empty(0)
    return outer_loop(rest_alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo_rows,
                      hi_rows, L, F, none, none, tol, max_outer, start_alpha, np.zeros(n),
                      np.zeros(n, np.bool_), np.zeros(n, np.bool_), 0, max_iter, request, False,
                      True, (hi_rows, lo_rows, ku, cu_, kl, cl_), channel, mu_up, mu_lo)


@njit(cache=True)
def outer_loop(rest_alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F, cu, cl,
               tol, max_outer, start_alpha, warm_u, warm_up, warm_lo, warm_flags, max_iter,
               request, newton, profiled, walls, channel, mu_up, mu_lo):
    """The globalised outer loop around the compiled step (model.compiled_driver.run, the
    default back-end's, fused), on flat walls or (``profiled``) walls of any profile.

    Flat walls (:func:`solve_chain`): each step's bounds are the rows ``lo``, ``hi``;
    the Armijo search is on the exact energy plus the elastic walls' springs
    (:func:`~.chain_kernel.energy_search`; ``cu``, ``cl``: the compliance 1/k (mm/N) of
    the upper and lower wall per free node, 0 rigid, empty where no wall yields);
    ``newton``: the Newton scheme (``method="newton"``), the exact Hessian H + T where
    positive definite once the last step moved α by less than NEWTON_SWITCH, or from a
    warm start's first step. A cold start (no ``start_alpha``, or one that does not fit
    between the walls) whose line searches cut the step length to STALL_STEP or less
    STALL_RUN outer steps running stops with BAIL_STALL, the answer not yet converged:
    its linearisation in the heights is off by more than 1/STALL_STEP in the energy at
    every step (a link near the vertical, where it divides by cos α); such a solve went
    on for 15-21 steps to a refused step (BAIL_CERT, BAIL_JUDGE) or a face the walk
    could not solve, never to an answer (thresholds.STALL_STEP). A warm start is never
    stopped so.

    Walls of any profile (:func:`solve_profile_chain`, :mod:`.profile_kernel`'s scheme;
    ``walls`` = (hi rows, lo rows, the upper wall's table, the lower's)): each step's
    bounds are the walls at the nodes' x, its load the lagged reactions' slope load
    (:func:`~.wall_kernel.lagged_load`; ``mu_up``, ``mu_lo`` written step by step), the
    search on the merit P (:func:`~.profile_kernel.merit_search`), the start clipped to
    the walls at the nodes' x (:func:`~.profile_kernel.clipped_start`), the stop also
    when the chain crosses no wall by more than GEOMETRY_SLACK ℓ; no Newton step and no
    stall rule.

    ``fs``: shifted index (node + 1) of the first free node; ``start_alpha`` empty for a
    cold start; ``warm_flags``: bit 0 ``warm_u``, bit 1 ``warm_up``, bit 2 ``warm_lo``
    are given (a continuation's last step). Returns ``(code, alpha, forces_upper,
    forces_lower, u, sigma, records, count, residuals, forces_net, upper, lower)``;
    ``records`` rows: face solves, step length t, max|Δα|, energy; ``sigma`` +1/−1 on
    the upper/lower walls; ``upper``, ``lower`` the walls at the answer's nodes (empty
    on flat walls).
    """
    n, links = lo.size, rest_alpha.size
    ws = workspace(n, links, jr.size, max_iter)
    wn, wb, wa, m = ws[0], ws[1], ws[3], ws[2][2]
    rec = np.empty((4, min(max_outer, 64)))
    count, zero, none, ok = 0, np.zeros(n), np.zeros(5), False
    alpha, trial, u = wa[ALPHA], wa[TRIAL], wn[OUT_U]
    sin_a, sin_t, cos_a, cos_t = wa[SIN_A], wa[SIN_T], wa[COS_A], wa[COS_T]
    p = n if profiled else 0  # the walls at the nodes' x: the merit's, and the step's
    rows = np.empty((13, p))  # (one allocation: the flat walls' solve pays for one)
    at = (rows[0], rows[1], rows[2], rows[3], rows[4], rows[5], rows[6],
          rows[7])  # x, y, upper, lower, h', l', h'', l''
    step_at = (at[0], at[1], rows[8], rows[9], at[4], at[5], at[6], at[7])
    yf, h1, l1, w, s = at[1], at[4], at[5], rows[10], rows[11]
    hs, ls = (step_at[2], step_at[3]) if profiled else (hi, lo)  # the step's bounds
    nl = rows[12] if profiled else nodal_load  # the step's load
    chain = (a, jl, jr, k, rest, link_load, fs)
    if profiled:
        near = False
        ok, cold = clipped_start(start_alpha, rest_alpha, a, fs, walls, alpha, u, sin_a,
                                 cos_a, at)
        if cold:
            mu_up[:] = 0.0
            mu_lo[:] = 0.0
    else:
        if start_alpha.size == links:  # a neighbour's answer, clipped to the walls
            _clipped_heights(u, start_alpha, a, fs, lo, hi)
            ok = fit_heights(alpha, u, start_alpha, a, fs, links, none[:0], sin_a, cos_a)
        near = ok and warm_flags != 0  # a neighbour's answer and its last step: near already
        cold = not ok  # (the stall rule's: cold starts only)
        if not ok:
            warm_flags = 0
            _clipped_heights(u, rest_alpha, a, fs, lo, hi)
            ok = fit_heights(alpha, u, rest_alpha, a, fs, links, none[:0], sin_a, cos_a)
    if not ok:
        return (NO_FIT, rest_alpha.copy(), zero, zero, zero, zero, rec, count, none, zero,
                zero[:p], zero[:p])
    E = energy(alpha, a, jl, jr, k, rest, link_load, sin_a)  # (+ the springs: flat walls)
    if not profiled:
        E += wall_penalty(u, lo, hi, cu, cl, none[:0])
    noise_k = 0.0
    for j in range(k.size):
        noise_k += abs(k[j])
    w_u, w_up, w_lo = wn[WU], wb[PREV_UP], wb[PREV_LO]
    w_u[:], w_up[:], w_lo[:] = warm_u, warm_up, warm_lo
    su, sigma, inv, alpha0, origin = wn[U], wn[SIG], wa[INV], wa[ALPHA0], wn[ORIG]
    d, ut, g_u = wn[DIR], wn[TRY], wn[GF]
    gp = (ws[7], jr[0], fs, links, origin, ws[2][0], k, rest, nl)
    short = 0  # outer steps running whose line search cut t to STALL_STEP or less
    for _ in range(max_outer):
        if profiled:  # the walls at the nodes' x, the lagged reactions' slope load
            walls_at(sin_a, cos_a, a, fs, *walls, *step_at)
            lagged_load(alpha, cos_a, sin_a, fs, mu_up, mu_lo, h1, l1, nodal_load, w, s, nl)
        code, it = _step(alpha, a, jl, jr, k, rest, fs, n, nl, ls, hs, L, F, cu, cl, w_u, w_up,
                         w_lo, warm_flags, max_iter, request, ws, gp, sin_a, cos_a,
                         newton and near)
        if code != 0:  # (sigma unwritten where the walk never ran: zero, as the rest)
            return (code, alpha.copy(), zero, zero, u.copy(), zero, rec, count, none, zero,
                    zero[:p], zero[:p])
        dalpha = predict_alpha(su, n, origin, alpha0, inv, fs, alpha, alpha[:0])
        grad_into(g_u, m, u, gp, ws[10])
        full, E_t = False, 0.0
        if profiled:  # the merit P, its weight σ from the largest reaction (at least F)
            net = wn[NET]
            big = F
            for i in range(n):
                big = max(big, max(abs(net[i]), max(mu_up[i], mu_lo[i])))
            t, full = merit_search(E, u, su, g_u, d, ut, alpha, trial, sin_t, cos_t, inv,
                                   dalpha, big, noise_k, chain, walls, mu_up, mu_lo, at, yf,
                                   hs, ls)
        else:  # the energy and the elastic walls' springs
            wall_penalty(u, lo, hi, cu, cl, g_u)  # (nothing where no wall yields)
            t, E_t = energy_search(E, u, su, g_u, d, ut, alpha, trial, sin_t, cos_t, inv,
                                   energy_noise(E, noise_k), chain, lo, hi, cu, cl)
        if t == 0.0:
            rec, count = record_step(rec, count, it, 0.0, dalpha, E)
            return (LINE_SEARCH, alpha.copy(), zero, zero, u.copy(), sigma.copy(), rec, count,
                    none, zero, zero[:p], zero[:p])
        for i in range(n):
            u[i] = su[i] if full else ut[i]
        alpha, trial, sin_a, sin_t = trial, alpha, sin_t, sin_a
        cos_a, cos_t = cos_t, cos_a
        # (against a profile, the chain's own energy: the merit's parts at α are the next
        # step's, at its walls)
        E = energy(alpha, a, jl, jr, k, rest, link_load, sin_a) if profiled else E_t
        rec, count = record_step(rec, count, it, t, dalpha, E)
        for i in range(n):  # the warm sets
            w_u[i], w_up[i], w_lo[i] = su[i], sigma[i] > 0, sigma[i] < 0
        if profiled:  # the lagged μ̄, ν̄
            split_by_wall(wn[NET], su, hs, ls, channel, mu_up, mu_lo)
        warm_flags, near = 7, dalpha < NEWTON_SWITCH
        if dalpha < tol and (not profiled or penetration(sin_a, cos_a, a, fs, walls, at)
                             <= GEOMETRY_SLACK * L):
            return (CONVERGED, alpha.copy(), wn[RUP].copy(), wn[RLO].copy(), su.copy(),
                    sigma.copy(), rec, count, ws[9].copy(), wn[NET].copy(), at[2].copy(),
                    at[3].copy())
        short = short + 1 if t <= STALL_STEP else 0
        if cold and short >= STALL_RUN and not profiled:
            return (BAIL_STALL, alpha.copy(), zero, zero, u.copy(), zero, rec, count, none,
                    zero, zero[:p], zero[:p])
    return (MAX_OUTER, alpha.copy(), zero, zero, u.copy(), zero, rec, count, none, zero,
            zero[:p], zero[:p])
