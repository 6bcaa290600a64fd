"""Walls of any profile in the compiled solve: the lagged-slope outer loop in numba.

The scheme of :mod:`lcpbench.model.profile` (each contact step the paper's
banded box QP, its bounds the wall heights h(x_k) at the nodes' current x, the
slope of the wall entering the linear term through the last step's reactions
μ̄, ν̄ as the nodal load s = J_xᵀ(μ̄ h'(x) − ν̄ l'(x))), and its outer loop: an
Armijo search on the merit (:func:`merit_search`)

    P(u) = E(u) − Σ μ̄_k h(x_k(u)) + Σ ν̄_k l(x_k(u)) + σ Σ (penetration of the walls)

σ = PENALTY × the largest reaction, a full step near the answer where the
merit would cut it below LOCAL_CUT, and the stop at max|Δα| < tol with every
node on its side of the exact walls to GEOMETRY_SLACK ℓ. Each step is the
solve kernel's (:func:`lcpbench.model.compiled_kernel.solve_assembled`: the
dual active set, its certificate and the step judge). The compiled driver around
any other back-end and scheme (:mod:`lcpbench.model.compiled_driver`) calls the same
start (:func:`clipped_start`), search (:func:`merit_search`) and stop
(:func:`penetration`) through :mod:`lcpbench.model.driver_kernel`.

A wall is a table of cubic pieces (:mod:`lcpbench.problems.profile_table`):
breakpoints ``knots`` and coefficients ``coef`` (4 × pieces, scipy's PPoly
layout), continued flat outside; an empty table is a flat wall whose rows
(``hi_rows``, ``lo_rows``) stand as they are. Rigid walls only (a profile and
an elastic wall do not combine, :class:`lcpbench.problems.scenes.ActuatorScene`).

Nothing here decides "converged": the caller judges the answer
(:mod:`lcpbench.model.judge`). A step the kernel cannot take as the
reference does ends the solve with its bail code, and the caller runs its
compiled fall-back (:func:`lcpbench.model.compiled.reference`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..thresholds import (
    ARMIJO_SHORTEST,
    GEOMETRY_SLACK,
    LOCAL_CUT,
    NEWTON_SWITCH,
    PENALTY,
    START_PASSES,
)
from .chain_kernel import (  # once (numba_cache)
    armijo,
    energy,
    energy_noise,
    fit_heights,
    predict_alpha,
)
from .compiled_dual import (
    ALPHA,
    ALPHA0,
    COS_A,
    COS_T,
    DIR,
    GF,
    INV,
    LIN,
    NET,
    ORIG,
    RLO,
    RUP,
    SIG,
    SIN_A,
    SIN_T,
    TRIAL,
    TRY,
    U,
    grad_into,
)
from .compiled_kernel import (
    CONVERGED,
    LINE_SEARCH,
    MAX_OUTER,
    NO_FIT,
    assemble_into,
    record_step,
    solve_assembled,
    workspace,
)
from .wall_kernel import lagged_load, split_by_wall, walls_at

__all__ = ["CONVERGED", "LINE_SEARCH", "MAX_OUTER", "NO_FIT", "solve_profile_chain"]


@njit(cache=True)
def merit_parts(alpha, sines, cosines, chain, walls, mu_up, mu_lo, at):
    """(E − Σ μ̄ h(x) + Σ ν̄ l(x), the penetration of the exact walls summed) at α: the
    merit P's two parts (P = first + σ second).
    ``chain`` = (a, jl, jr, k, rest, link_load, fs); ``walls`` = (hi_rows, lo_rows, ku,
    cu_, kl, cl_); ``at``: the scratch rows of :func:`walls_at` (written)."""
    a, jl, jr, k, rest, link_load, fs = chain
    walls_at(sines, cosines, a, fs, *walls, *at)
    E = energy(alpha, a, jl, jr, k, rest, link_load, sines)
    return merit_at(E, walls, mu_up, mu_lo, at[1], at[2], at[3])


@njit(cache=True)
def merit_at(E, walls, mu_up, mu_lo, yf, hi, lo):
    """:func:`merit_parts` from the energy E and the walls ``hi``, ``lo`` at the nodes'
    heights ``yf``, already evaluated."""
    hi_rows, lo_rows, ku, _, kl, _ = walls
    total, pen = E, 0.0
    for i in range(hi.size):
        if ku.size and mu_up[i] > 0 and np.isfinite(hi_rows[i]):  # (a reaction: a row)
            total -= mu_up[i] * hi[i]
        if kl.size and mu_lo[i] > 0 and np.isfinite(lo_rows[i]):
            total += mu_lo[i] * lo[i]
        if np.isfinite(hi_rows[i]):
            pen += max(yf[i] - hi[i], 0.0)
        if np.isfinite(lo_rows[i]):
            pen += max(lo[i] - yf[i], 0.0)
    return total, pen


@njit(cache=True)
def _clipped(alpha0, a, fs, walls, alpha, u, sin_a, cos_a, at):
    """Into ``alpha``, ``u``: the heights clipped to the
    walls at the nodes' x, START_PASSES times; False where the chain tears. A pass is a
    function of α and its sines and cosines alone (``u`` and ``at`` it writes before it
    reads them): once a pass leaves all three as they were, bit for bit, every later
    pass would too, and the passes stop there (the same α, ``u`` and ``at``)."""
    links = alpha.size
    alpha[:] = alpha0
    for i in range(links):
        cos_a[i], sin_a[i] = np.cos(alpha0[i]), np.sin(alpha0[i])
    yf, hi, lo = at[1], at[2], at[3]
    before = np.empty((3, links))  # α, sin α, cos α before the pass
    for _ in range(START_PASSES):
        walls_at(sin_a, cos_a, a, fs, *walls, *at)
        for i in range(u.size):
            u[i] = min(max(yf[i], lo[i]), hi[i])
        before[0], before[1], before[2] = alpha, sin_a, cos_a
        if not fit_heights(alpha, u, before[0], a, fs, links, np.empty(0), sin_a, cos_a):
            return False
        if _same_bits(before[0], alpha) and _same_bits(before[1], sin_a) \
                and _same_bits(before[2], cos_a):
            break
    return True


@njit(cache=True)
def _same_bits(x, y):
    """Whether the arrays ``x`` and ``y`` hold the same numbers, bit for bit (a zero's sign
    too; NaN never: a pass that gives one is not repeated the same)."""
    for i in range(x.size):
        if x[i] != y[i] or math.copysign(1.0, x[i]) != math.copysign(1.0, y[i]):
            return False
    return True


@njit(cache=True)
def clipped_start(start_alpha, rest_alpha, a, fs, walls, alpha, u, sin_a, cos_a, at):
    """The start of a solve against walls of any profile into ``alpha``, ``u``: the shape
    ``start_alpha`` (empty: none) clipped to the walls (:func:`_clipped`), else the
    unconstrained arc flattened by halves until its clipped shape is a chain (the arc's
    angles scaled by 2^-k: a symmetric arc stays closed on the right pin). (fits, cold):
    cold where the start was not used (its lagged reactions are then zero)."""
    ok = start_alpha.size == alpha.size and _clipped(start_alpha, a, fs, walls, alpha, u,
                                                      sin_a, cos_a, at)
    if ok:
        return True, False
    scale = 1.0
    while not ok and scale > 1e-6:
        ok = _clipped(scale * rest_alpha, a, fs, walls, alpha, u, sin_a, cos_a, at)
        scale *= 0.5
    return ok, True


@njit(cache=True)
def merit_search(E, u, su, g_u, d, ut, alpha, trial, sin_t, cos_t, inv, dalpha, big, noise_k,
                 chain, walls, mu_up, mu_lo, at, yf, hs, ls):
    """The Armijo search on the merit P = E − Σ μ̄ h(x) + Σ ν̄ l(x) + σ Σ(penetration),
    σ = PENALTY · ``big`` (the largest reaction, at least EI/ℓ²), along u + t(su − u)
    from the heights ``u`` at α (energy E, the model's gradient ``g_u`` there, the
    walls ``hs``, ``ls`` at the nodes' heights ``yf``); near the answer (max|Δα| =
    ``dalpha`` < NEWTON_SWITCH) a step the merit would cut below LOCAL_CUT is taken in
    full. Writes ``d`` = su − u, ``ut`` (the last heights tried), ``trial`` (α there),
    ``sin_t``, ``cos_t`` and the scratch ``at``. (t, full): t = 0 where no t >=
    ARMIJO_SHORTEST decreases P; full: the step ``su`` taken in full."""
    a, fs, links, n = chain[0], chain[6], alpha.size, u.size
    pen_weight = PENALTY * big
    slope = 0.0
    for i in range(n):
        d[i] = su[i] - u[i]
        slope += g_u[i] * d[i]
    part, pen = merit_at(E, walls, mu_up, mu_lo, yf, hs, ls)  # (the step's walls: at α)
    phi = part + pen_weight * pen
    slope -= pen_weight * pen
    noise = energy_noise(phi, noise_k)
    t = 1.0
    while True:
        for i in range(n):
            ut[i] = u[i] + t * d[i]
        phi_t = np.nan
        if fit_heights(trial, ut, alpha, a, fs, links, inv, sin_t, cos_t):
            part, pen = merit_parts(trial, sin_t, cos_t, chain, walls, mu_up, mu_lo, at)
            phi_t = part + pen_weight * pen
        step = armijo(t, phi_t, phi, slope, noise, ARMIJO_SHORTEST)
        if step == t:
            return t, False
        if step == 0.0:
            return 0.0, False
        t = step
        if t < LOCAL_CUT and dalpha < NEWTON_SWITCH:  # near the answer: the full step
            if fit_heights(trial, su, alpha, a, fs, links, inv, sin_t, cos_t):
                return 1.0, True


@njit(cache=True)
def penetration(sines, cosines, a, fs, walls, at):
    """How far the chain at α (its ``sines``, ``cosines``) crosses the exact walls (mm,
    the largest over the rows, 0 where it crosses none); the walls at the nodes' x left
    in ``at`` (:func:`walls_at`'s rows)."""
    walls_at(sines, cosines, a, fs, *walls, *at)
    hi_rows, lo_rows = walls[0], walls[1]
    yf, hi, lo = at[1], at[2], at[3]
    worst = 0.0
    for i in range(hi_rows.size):
        if np.isfinite(hi_rows[i]):
            worst = max(worst, yf[i] - hi[i])
        if np.isfinite(lo_rows[i]):
            worst = max(worst, lo[i] - yf[i])
    return worst


@njit(cache=True)
def solve_profile_chain(rest_alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo_rows,
                        hi_rows, L, F, ku, cu_, kl, cl_, channel, tol, max_outer, start_alpha,
                        mu_up, mu_lo, max_iter, request):
    """The globalised outer loop against walls of any profile around the solve
    kernel's step. ``ku``, ``cu_`` (``kl``, ``cl_``): the upper (lower)
    wall's table, empty for a flat wall; ``hi_rows``, ``lo_rows``: the chain's rows
    (±inf: no wall at that node); ``channel``: reactions split between two walls;
    ``start_alpha`` empty for a cold start; ``mu_up``, ``mu_lo``: the starting lagged
    reactions (zeros cold; written).

    Returns ``(code, alpha, forces_upper, forces_lower, u, sigma, records, count,
    residuals, forces_net, upper, lower)``, the last two the walls at the answer's
    nodes (as :func:`lcpbench.model.compiled_kernel.solve_chain`, plus the walls).
    """
    n, links = lo_rows.size, rest_alpha.size
    ws = workspace(n, links, jr.size, max_iter)
    wn, wa, m = ws[0], ws[3], ws[2][2]
    rec = np.empty((4, min(max_outer, 64)))
    count, zero, none = 0, np.zeros(n), np.zeros(5)
    chain = (a, jl, jr, k, rest, link_load, fs)
    walls = (hi_rows, lo_rows, ku, cu_, kl, cl_)
    at = (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
          np.empty(n), np.empty(n))  # x, y, upper, lower, h', l', h'', l'' (the merit's)
    step_at = (at[0], at[1], np.empty(n), np.empty(n), at[4], at[5], at[6], at[7])
    yf, hi, lo, hs, ls, h1, l1 = at[1], at[2], at[3], step_at[2], step_at[3], at[4], at[5]
    nl, s, w, w_u = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    w_up, w_lo = np.zeros(n, np.bool_), np.zeros(n, np.bool_)
    alpha, trial, u = wa[ALPHA], wa[TRIAL], np.empty(n)
    sin_a, sin_t, cos_a, cos_t = wa[SIN_A], wa[SIN_T], wa[COS_A], wa[COS_T]
    ok, cold = clipped_start(start_alpha, rest_alpha, a, fs, walls, alpha, u, sin_a, cos_a, at)
    if cold:
        mu_up[:] = 0.0
        mu_lo[:] = 0.0
    if not ok:
        return (NO_FIT, rest_alpha.copy(), zero, zero, zero, zero, rec, count, none, zero,
                zero, zero)
    noise_k = 0.0
    for j in range(k.size):
        noise_k += abs(k[j])
    su, sigma, inv, alpha0, origin = wn[U], wn[SIG], wa[INV], wa[ALPHA0], wn[ORIG]
    d, ut, g_u, T = wn[DIR], wn[TRY], wn[GF], ws[10]
    T[:] = 0.0
    gp = (ws[7], jr[0], fs, links, origin, ws[2][0], k, rest, nl)
    flags, no_c = 0, np.empty(0)
    for _ in range(max_outer):
        E = energy(alpha, a, jl, jr, k, rest, link_load, sin_a)
        walls_at(sin_a, cos_a, a, fs, *walls, *step_at)
        lagged_load(alpha, cos_a, sin_a, fs, mu_up, mu_lo, h1, l1, nodal_load, w, s, nl)
        assemble_into(alpha, a, jl, jr, k, rest, fs, n, nl, ws[6], wn[LIN], inv, ws[7], origin,
                      alpha0, ws[2][0], ws[2][1], ws[4], sin_a, cos_a, False)
        code, it = solve_assembled(n, ls, hs, L, F, no_c, no_c, w_u, w_up, w_lo, flags,
                                   max_iter, request, ws, gp, T)
        if code != 0:
            return (code, alpha.copy(), zero, zero, u.copy(), zero, rec, count, none, zero, zero,
                    zero)
        dalpha = predict_alpha(su, n, origin, alpha0, inv, fs, alpha, alpha[:0])
        net = wn[NET]
        big = F
        for i in range(n):
            big = max(big, max(abs(net[i]), max(mu_up[i], mu_lo[i])))
        grad_into(g_u, m, u, gp, T)
        t, full = merit_search(E, u, su, g_u, d, ut, alpha, trial, sin_t, cos_t, inv, dalpha,
                               big, noise_k, chain, walls, mu_up, mu_lo, at, yf, hs, ls)
        if t == 0.0:
            rec, count = record_step(rec, count, it, 0.0, dalpha, E)
            return (LINE_SEARCH, alpha.copy(), zero, zero, u.copy(), sigma.copy(), rec,
                    count, none, zero, zero, zero)
        for i in range(n):
            u[i] = su[i] if full else ut[i]
        alpha, trial, sin_a, sin_t = trial, alpha, sin_t, sin_a
        cos_a, cos_t = cos_t, cos_a
        rec, count = record_step(rec, count, it, t, dalpha,
                                 energy(alpha, a, jl, jr, k, rest, link_load, sin_a))
        for i in range(n):  # the warm sets
            w_u[i], w_up[i], w_lo[i] = su[i], sigma[i] > 0, sigma[i] < 0
        split_by_wall(net, su, hs, ls, channel, mu_up, mu_lo)  # the lagged μ̄, ν̄
        flags = 7
        if dalpha < tol:
            if penetration(sin_a, cos_a, a, fs, walls, at) <= GEOMETRY_SLACK * L:
                return (CONVERGED, alpha.copy(), wn[RUP].copy(), wn[RLO].copy(), su.copy(),
                        sigma.copy(), rec, count, ws[9].copy(), net.copy(), hi.copy(),
                        lo.copy())
    return (MAX_OUTER, alpha.copy(), zero, zero, u.copy(), zero, rec, count, none, zero, zero,
            zero)
