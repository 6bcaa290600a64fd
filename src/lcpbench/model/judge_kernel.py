"""The result judge's exact steps, compiled: the judge's own contact steps and the force
error bound (check 7 of :mod:`lcpbench.model.judge`).

:func:`judge_walls` (:func:`judge_answer` on flat walls) and :func:`judge_in_increments`,
entries of one body (:func:`_judge_numbers`), take every number of
:func:`lcpbench.model.judge.judge` for a converged driver answer: the judge's own
contact step at the final α, solved exactly from the answer's contact set, the
round-off of the reactions, the certificate and checks 3-6 and 8
(:mod:`lcpbench.model.judge_checks`), and, where the one-step estimate of the force
error exceeds τ, the judge's second exact step at α₁, where its first moves the chain,
from the first's contact set; the force error bound from the two
(:mod:`lcpbench.model.judge_bound`). Its steps are in one of two formulations:

- in node heights (here): assembled from the energy of the chain, solved by block
  principal pivoting (Júdice–Pires, then Murty's least index; the rule in
  :mod:`lcpbench.model.judge_pivot`) on the Cholesky of H, whose round-off grows as N⁴;
- in increments d = u − u₀ (:func:`judge_in_increments`: from ``LARGE_N`` links or on a
  chain marked ``increments``), :func:`lcpbench.model.judge_exact_kernel.increments_step`:
  assembled by :func:`lcpbench.model.large_kernel.assemble_into` (the large-N driver's
  assembly), solved on its twisted tridiagonal factor by the primal active set (rigid
  walls) or block principal pivoting (elastic walls).

:mod:`lcpbench.model.judge` turns the numbers returned here into the
:class:`~lcpbench.model.judge.Judgement` and its reasons; ``NUMBA_DISABLE_JIT=1`` runs
the same functions as plain Python.

Independent of the solve kernel (:mod:`lcpbench.model.compiled_kernel`): the judge
step is block principal pivoting or the primal active set, not the dual active set;
in heights on its own assembly; nothing here is imported from that file and nothing
there from here. The banded factorisation below is textbook arithmetic (LDLᵀ for
bandwidth 2, no square roots). Its work arrays are one allocation per call (rows
:data:`~.judge_checks.ROWS`).

The chain must have consecutive joints and contiguous free nodes (the layouts the
solve kernel takes, :func:`lcpbench.model.kernel_call.applies`); in increments also
joint j joining links j, j + 1 with both ends pinned
(:func:`lcpbench.model.large_n.layout_fits`).
"""
from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.extending import overload

from ..thresholds import (  # the rule's numbers, as model.judge reads them
    EPS,
    FLOOR_ULPS,
    PIVOT_ROUNDS,
    ROUNDOFF_ULPS,
)
from .chain_kernel import predict_alpha  # eq. (21), the kinematics' (not the step's)
from .judge_bound import contraction, force_error_bound, judge_contraction, profile_rows
from .judge_checks import (
    ALPHA0,
    C0,
    C1,
    C2,
    COS,
    DIAG,
    FREE,
    HG,
    HGA,
    HY,
    INV,
    JLO,
    JU,
    LIN,
    LINEAR,
    LO,
    NET,
    NOISE,
    NOT_SETTLED,
    OFF1,
    OFF2,
    ORIGIN,
    PHI0,
    RHS,
    ROUNDOFF,
    ROWS,
    SCALE,
    SETTLED,
    SIZE,
    STATS,
    UP,
    YC,
    U,
    V,
    certify_checks,
    positions,
    units,
    without_noise,
)
from .judge_exact_kernel import increments_step
from .judge_pivot import NO_SIZES, pivot_exchange, pivot_settled, pivot_test, term_sizes
from .wall_kernel import split_by_wall

TINY = np.finfo(np.float64).tiny


# -- the judge's contact step (compiled_kernel.banded_step, written for the judge) -------
@njit(cache=True)
def _step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, w, bands):
    """The step at α: its bands, and (rows) linear, coef, inv, origin, alpha0, phi_origin."""
    links = alpha.size
    nj = jr.size
    cs, inv, v = w[COS], w[INV], w[V]
    for i in range(links):
        inv[i] = 1.0 / (a * cs[i])
    diag, off1, off2, lin = w[DIAG], w[OFF1], w[OFF2], w[LIN]
    for p in range(links + 2):
        diag[p] = off1[p] = off2[p] = lin[p] = 0.0
    c0s, c1s, c2s = w[C0], w[C1], w[C2]
    b0 = jr[0]
    for j in range(nj):
        wl = inv[jl[j]] if jl[j] >= 0 else 0.0
        wr = inv[jr[j]]
        c0, c1, c2 = wl, -wl - wr, wr
        c0s[j], c1s[j], c2s[j] = c0, c1, c2
        t = k[j] * ((-v[jr[j]] + (v[jl[j]] if jl[j] >= 0 else 0.0)) - rest[j])
        p = b0 + j
        diag[p] += k[j] * c0 * c0
        diag[p + 1] += k[j] * c1 * c1
        diag[p + 2] += k[j] * c2 * c2
        off1[p] += k[j] * c0 * c1
        off1[p + 1] += k[j] * c1 * c2
        off2[p] += k[j] * c0 * c2
        lin[p] += c0 * t
        lin[p + 1] += c1 * t
        lin[p + 2] += c2 * t
    y, origin, alpha0, phi_origin, linear = w[YC], w[ORIGIN], w[ALPHA0], w[PHI0], w[LINEAR]
    for i in range(n):
        origin[i] = y[fs - 1 + i]
    for i in range(links):
        alpha0[i] = alpha[i]
    if fs - 1 + n - 1 < links:  # pinned right end: the last link closes the chain
        alpha0[links - 1] += -y[links] * inv[links - 1]
    for j in range(nj):
        phi_origin[j] = alpha0[jr[j]] - (alpha0[jl[j]] if jl[j] >= 0 else 0.0)
    for i in range(n):
        bands[0, i] = diag[fs + i]
        bands[1, i] = off1[fs + i] if i < n - 1 else 0.0
        bands[2, i] = off2[fs + i] if i < n - 2 else 0.0
        linear[i] = lin[fs + i] - nodal_load[i]


@njit(cache=True)
def _grad(u, w, out, with_scale, n, fs, b0, nj, k, rest, nodal_load):
    """ContactStep.gradient at u into ``out``, and with ``with_scale`` its
    .gradient_scale at u into row SCALE, in one pass."""
    origin, phi_origin = w[ORIGIN], w[PHI0]
    c0s, c1s, c2s = w[C0], w[C1], w[C2]
    y, g, ga = w[HY], w[HG], w[HGA]
    for p in range(y.size):
        y[p] = g[p] = ga[p] = 0.0
    for i in range(n):
        y[fs + i] = u[i] - origin[i]
    for j in range(nj):
        c0, c1, c2 = c0s[j], c1s[j], c2s[j]
        y0, y1, y2 = y[b0 + j], y[b0 + 1 + j], y[b0 + 2 + j]
        m = ((c0 * y0 + c1 * y1 + c2 * y2 + phi_origin[j]) - rest[j]) * k[j]
        g[b0 + j] += c0 * m
        g[b0 + 1 + j] += c1 * m
        g[b0 + 2 + j] += c2 * m
        if with_scale:
            a0, a1, a2 = abs(c0), abs(c1), abs(c2)
            ma = (a0 * abs(y0) + a1 * abs(y1) + a2 * abs(y2)
                  + (abs(phi_origin[j]) + abs(rest[j]))) * k[j]
            ga[b0 + j] += a0 * ma
            ga[b0 + 1 + j] += a1 * ma
            ga[b0 + 2 + j] += a2 * ma
    for i in range(n):
        out[i] = g[fs + i] - nodal_load[i]
    if with_scale:
        scale = w[SCALE]
        for i in range(n):
            scale[i] = ga[fs + i] + (abs(nodal_load[i]) + TINY)


@njit(cache=True)
def _factor(bands, free, m, fac, spring):
    """H[free, free] + diag(spring) = L D Lᵀ (bandwidth 2, no square roots) into fac:
    the unit L's sub-diagonals in rows 1-2, 1 / D in row 3; False if it is not
    positive definite (a pivot d ≤ 0, where Cholesky's square root fails).
    ``spring``: the elastic walls' k per node holding it (empty: none)."""
    for p in range(m):
        fac[0, p] = bands[0, free[p]]
        if spring.size:
            fac[0, p] += spring[free[p]]
        fac[1, p] = fac[2, p] = 0.0
        if p + 1 < m:
            gap = free[p + 1] - free[p]
            if gap <= 2:
                fac[1, p] = bands[gap, free[p]]
        if p + 2 < m and free[p + 2] - free[p] == 2:
            fac[2, p] = bands[2, free[p]]
    for j in range(m):  # one division per column on the dependency chain
        d = fac[0, j]
        if not d > 0.0:
            return False
        fac[3, j] = 1.0 / d
        if j + 2 < m:
            a1, a2 = fac[1, j], fac[2, j]
            l1, l2 = a1 / d, a2 / d
            fac[0, j + 1] -= l1 * a1
            fac[1, j + 1] -= l2 * a1
            fac[0, j + 2] -= l2 * a2
            fac[1, j], fac[2, j] = l1, l2
        elif j + 1 < m:
            a1 = fac[1, j]
            l1 = a1 / d
            fac[0, j + 1] -= l1 * a1
            fac[1, j] = l1
    return True


@njit(cache=True)
def _solve(fac, free, m, rhs, x):
    """x = H[free, free]⁻¹ rhs[free] on the factor of :func:`_factor`."""
    for p in range(m):
        x[p] = rhs[free[p]]
    for j in range(m):  # L z = rhs, then D y = z
        xj = x[j]
        if j + 1 < m:
            x[j + 1] -= xj * fac[1, j]
        if j + 2 < m:
            x[j + 2] -= xj * fac[2, j]
        x[j] = xj * fac[3, j]
    for j in range(m - 1, -1, -1):  # Lᵀ x = y
        t = x[j]
        if j + 1 < m:
            t -= fac[1, j] * x[j + 1]
        if j + 2 < m:
            t -= fac[2, j] * x[j + 2]
        x[j] = t


@njit(cache=True)
def _heights_step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, w, bands, fac, iw, lo, hi, cu,
                  cl, L, eps_R, profiled, forces_upper, forces_lower):
    """The judge step at α in node heights (on the Cholesky of H), from the answer's
    contact set: the nodes within reach of a wall (``eps_R`` of force, or 1e3 ulps of the
    length L), and (``profiled``) the nodes whose reaction exceeds ``eps_R``; row NOISE
    the round-off of an answer's R = K g + z per node. Returns :func:`_pivot`'s."""
    nj = jr.size
    b0 = jr[0]
    _step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, w, bands)
    origin, linear, noise, state = w[ORIGIN], w[LINEAR], w[NOISE], iw[0]
    _grad(origin, w, w[RHS], True, n, fs, b0, nj, k, rest, nodal_load)  # scale at u₀
    term_sizes(bands, linear, origin, n, w[SIZE])
    scale0, size0 = w[SCALE], w[SIZE]
    for i in range(n):
        touch = max(eps_R / bands[0, i], 1e3 * EPS * L)
        on_up = hi[i] - origin[i] <= touch
        on_lo = origin[i] - lo[i] <= touch
        noise[i] = ROUNDOFF_ULPS * EPS * (scale0[i] if on_up or on_lo else size0[i])
        if profiled:  # on the wall at the x of its last step: its loaded nodes start on it
            on_up = on_up or (forces_upper[i] > eps_R and np.isfinite(hi[i]))
            on_lo = on_lo or (forces_lower[i] > eps_R and np.isfinite(lo[i]))
        up = on_up and (not on_lo or hi[i] - origin[i] <= origin[i] - lo[i])
        state[i] = UP if up else (LO if on_lo else FREE)
    return _pivot(bands, fac, iw, lo, hi, cu, cl, L, eps_R, w, fs, b0, nj, k, rest, nodal_load)


@njit(cache=True)
def _pivot(bands, fac, iw, lo, hi, cu, cl, L, pull, w, fs, b0, nj, k, rest, nodal_load):
    """The judge step in heights by block principal pivoting (the rule of
    :func:`pivot_test` and :func:`pivot_exchange`) from the contact set ``iw[0]`` (FREE,
    UP, LO): (rounds or 0 if it did not settle, worst round-off, term size S); u, the net reaction and
    the round-off per wall node in rows U, NET, ROUNDOFF. ``cu``, ``cl``: the walls'
    compliances 1/k (0: rigid; empty: no wall yields); a node in contact with an
    elastic wall stays free, held by the wall's spring k (u − h)."""
    n = lo.size
    soft = cu.size == n
    spring = np.zeros(n if soft else 0)
    state, change, free = iw[0], iw[1], iw[2]  # change: 1 release up, 2 release lo,
    origin, linear, u, net = w[ORIGIN], w[LINEAR], w[U], w[NET]  # 3 join up, 4 join lo
    scale, roundoff, x, sizes = w[SCALE], w[ROUNDOFF], w[RHS], w[SIZE]
    best, stall = n + 1, 0
    for rounds in range(1, PIVOT_ROUNDS + 2 * n + 1):
        nfree = 0
        for i in range(n):
            c = 0.0
            if soft:
                c = cu[i] if state[i] == UP else (cl[i] if state[i] == LO else 0.0)
                spring[i] = 1.0 / c if c > 0.0 else 0.0
            if state[i] == UP and not c > 0.0:
                u[i] = hi[i]
            elif state[i] == LO and not c > 0.0:
                u[i] = lo[i]
            else:
                u[i] = origin[i]
                free[nfree] = i
                nfree += 1
        if nfree:
            if not _factor(bands, free, nfree, fac, spring):
                return 0, 0.0, 0.0
            for _ in range(2):  # solve, then refine with the factored gradient
                _grad(u, w, net, False, n, fs, b0, nj, k, rest, nodal_load)
                for i in range(spring.size):  # + the springs' k (u − h)
                    if spring[i] > 0.0:
                        net[i] += spring[i] * (u[i] - (hi[i] if state[i] == UP else lo[i]))
                _solve(fac, free, nfree, net, x)
                for p in range(nfree):
                    u[free[p]] -= x[p]
        _grad(u, w, net, True, n, fs, b0, nj, k, rest, nodal_load)
        term_sizes(bands, linear, u, n, sizes)
        count, first, worst, S = pivot_test(state, change, u, net, scale, sizes, hi, lo,
                                            bands[0], L, NO_SIZES, pull, roundoff)
        if count == 0:
            return pivot_settled(state, roundoff, rounds, worst, S)
        best, stall = pivot_exchange(state, change, n, count, first, best, stall)
    return 0, 0.0, 0.0


@njit(cache=True)
def judge_answer(alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F, cu, cl,
                 wall, channel, forces_upper, forces_lower, tol, step_sizes):
    """:func:`judge_walls` on flat walls (no table)."""
    no_table = (np.empty(0), np.empty((4, 0)))
    return judge_walls(alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F, cu,
                       cl, wall, channel, *no_table, *no_table, forces_upper, forces_lower, tol,
                       step_sizes)


@njit(cache=True)
def judge_walls(alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F, cu, cl,
                wall, channel, ku, cu_, kl, cl_, forces_upper, forces_lower, tol, step_sizes):
    """:func:`_judge_numbers`, the judge's steps in node heights."""
    return _judge_numbers(alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                          cu, cl, wall, channel, ku, cu_, kl, cl_, forces_upper, forces_lower,
                          tol, step_sizes, False)


@njit(cache=True)
def judge_in_increments(alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                        cu, cl, wall, channel, ku, cu_, kl, cl_, forces_upper, forces_lower,
                        tol, step_sizes):
    """:func:`_judge_numbers`, the judge's steps in increments (from ``LARGE_N`` links or on
    a chain marked ``increments``)."""
    return _judge_numbers(alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                          cu, cl, wall, channel, ku, cu_, kl, cl_, forces_upper, forces_lower,
                          tol, step_sizes, True)


@njit(cache=True)
def _judge_numbers(alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F, cu,
                   cl, wall, channel, ku, cu_, kl, cl_, forces_upper, forces_lower, tol,
                   step_sizes, increments):
    """model.judge.judge's numbers for an answer whose driver converged.

    ``fs``: shifted index (node + 1) of the first free node; ``F`` the force
    scale EI/ℓ²; ``L`` the length ℓ; ``cu``, ``cl``: the compliance 1/k of the
    upper and lower wall per free node (0: rigid; empty: no wall yields), whose
    gap is the compliant one, g + R/k; ``wall`` the upper wall's height (inf:
    none); ``channel`` a lower wall at −wall too; ``ku``, ``cu_`` (``kl``, ``cl_``):
    the upper (lower) wall's table of cubic pieces (:mod:`lcpbench.model.wall_kernel`;
    empty: flat), whose heights at the nodes' x replace ``hi`` (``lo``) on their rows,
    and whose slope carries the answer's reactions' horizontal parts (the checks of the
    exact profile problem, model.profile); ``increments``: the judge steps in increments
    (:func:`~.judge_exact_kernel.increments_step`), else in node heights, a constant of
    each compiled version (:func:`judge_walls`, :func:`judge_in_increments`), so that it
    holds the code of one formulation (:func:`judge_step`).

    Returns ``(code, stats, forces_upper, forces_lower, torque_residual)``:
    ``code`` SETTLED or NOT_SETTLED (the judge step did not settle), ``stats``
    the numbers named in :data:`STATS`, the answer's reactions with their
    round-off set to zero and the certificate's torque residual. Its work arrays
    are allocated once per call (a row per quantity, :data:`ROWS`).
    """
    n = lo.size
    links = alpha.size
    tau, F0, eps_R = units(forces_upper, forces_lower, F, tol)
    stats = np.full(len(STATS), np.nan)
    w = np.empty((ROWS, links + 2))
    bands, fac = np.empty((3, n)), np.empty((4, n))
    iw = np.empty((3, n), np.int64)
    positions(alpha, a, w)
    profiled = ku.size > 0 or kl.size > 0
    hi0, lo0, nodal0 = hi, lo, nodal_load  # the flat rows: the second step's walls from them
    h1 = l1 = h2 = l2 = g_up = g_lo = np.empty(0)
    if profiled:  # the walls at the nodes' x; the answer's reactions load along them
        hi, lo, nodal_load, g_up, g_lo, h1, l1, h2, l2 = profile_rows(
            alpha, w[COS], a, fs, hi0, lo0, wall, ku, cu_, kl, cl_, forces_upper,
            forces_lower, nodal0)
    alpha1 = np.empty(links)  # α̂, where the judge step moves the chain (eq. 21)
    noise = w[NOISE]
    rounds, worst, S, dalpha = judge_step(increments, False, alpha, a, jl, jr, k, rest, fs,
                                          nodal_load, lo, hi, cu, cl, L, eps_R, profiled,
                                          forces_upper, forces_lower, w, bands, fac, iw, alpha1)
    settled = rounds > 0
    u, net, roundoff, ju, jlo = w[U], w[NET], w[ROUNDOFF], w[JU], w[JLO]
    fu, fl = without_noise(forces_upper, forces_lower, noise, settled)
    if settled:
        split_by_wall(net[:n], u, hi, lo, channel, ju, jlo)
    floor_R = FLOOR_ULPS * EPS * S if settled else 0.0
    has_gap = np.isfinite(wall) or ku.size > 0  # (an upper wall: a gap to measure)
    res = certify_checks(alpha, a, jl, jr, k, rest, link_load, fs, lo, hi, L, F, cu, cl, wall,
                         channel, has_gap, profiled, g_up, g_lo, h1, l1, h2, l2, fu, fl, w,
                         floor_R, tau, F0, eps_R, stats)
    if not settled:
        return NOT_SETTLED, stats, fu, fl, res
    rho = contraction(step_sizes, dalpha)
    # the second judge step, at α₁ where the first moves the chain, from its contact set
    d_up, d_lo, j1u, j1l = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    floor1, J = worst, 0.0
    for i in range(n):
        floor1 += roundoff[i]
        J += ju[i]
        d_up[i], d_lo[i], j1u[i], j1l[i] = fu[i] - ju[i], fl[i] - jlo[i], ju[i], jlo[i]
    floor1 /= F0
    e_up, e_lo = np.zeros(n), np.zeros(n)
    stats[13], stats[14] = force_error_bound(d_up, d_lo, e_up, e_lo, rho, np.nan, floor1,
                                             np.nan, F0, False)
    stats[16], stats[17], stats[18] = rho, J, rounds
    if stats[13] <= tau:  # the one-step estimate passes: the second step can only lower it
        return SETTLED, stats, fu, fl, res
    positions(alpha1, a, w)
    if profiled:  # its walls at the nodes' new x, the first step's reactions lagged
        hi, lo, nodal_load = profile_rows(alpha1, w[COS], a, fs, hi0, lo0, wall, ku, cu_,
                                          kl, cl_, j1u, j1l, nodal0)[:3]
    rounds2, worst2, _, dalpha2 = judge_step(increments, True, alpha1, a, jl, jr, k, rest, fs,
                                             nodal_load, lo, hi, cu, cl, L, eps_R, profiled,
                                             j1u, j1l, w, bands, fac, iw, np.empty(links))
    rho2, floor2 = np.nan, np.nan
    if rounds2 > 0:
        split_by_wall(net[:n], u, hi, lo, channel, ju, jlo)
        for i in range(n):
            e_up[i], e_lo[i] = j1u[i] - ju[i], j1l[i] - jlo[i]
        rho2 = judge_contraction(dalpha, dalpha2)
        floor2 = worst2
        for i in range(n):
            floor2 += roundoff[i]
        floor2 /= F0
    stats[13], stats[14] = force_error_bound(d_up, d_lo, e_up, e_lo, rho, rho2, floor1,
                                             floor2, F0, rounds2 > 0)
    stats[22] = rho2
    return SETTLED, stats, fu, fl, res


def judge_step(increments, second, alpha, a, jl, jr, k, rest, fs, nodal_load, lo, hi, cu, cl,
               L, pull, profiled, forces_upper, forces_lower, w, bands, fac, iw, alpha_next):
    """The judge's contact step at α, the first (``second`` False: from the answer's
    contact set, its reactions ``forces_upper``/``forces_lower``) or the second (from the
    first's settled set, ``iw[0]``; the forces the first step's): in node heights
    (:func:`_heights_step`, :func:`_pivot`) or ``increments``
    (:func:`~.judge_exact_kernel.increments_step`). u, the net reactions, their round-off
    and the answer's noise in the rows of ``w``, α̂ in ``alpha_next``. Returns (rounds, 0
    where it did not settle, the largest round-off, S, max|α̂ − α|).

    Compiled, ``increments`` is a constant (the overload below takes its literal value),
    so each version of :func:`_judge_numbers` holds one formulation's code; as plain Python
    (``NUMBA_DISABLE_JIT=1``) this chooses at run time."""
    return (_step_in_increments if increments else _step_in_heights)(
        increments, second, alpha, a, jl, jr, k, rest, fs, nodal_load, lo, hi, cu, cl, L,
        pull, profiled, forces_upper, forces_lower, w, bands, fac, iw, alpha_next)


@overload(judge_step)
def _judge_step_typed(increments, second, alpha, a, jl, jr, k, rest, fs, nodal_load, lo, hi,
                      cu, cl, L, pull, profiled, forces_upper, forces_lower, w, bands, fac, iw,
                      alpha_next):
    if isinstance(increments, types.BooleanLiteral):
        return _step_in_increments if increments.literal_value else _step_in_heights
    return None


def _step_in_heights(increments, second, alpha, a, jl, jr, k, rest, fs, nodal_load, lo, hi,
                     cu, cl, L, pull, profiled, forces_upper, forces_lower, w, bands, fac, iw,
                     alpha_next):
    """:func:`judge_step` in node heights (the second from the first's settled set)."""
    n = lo.size
    if second:
        _step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, w, bands)
        rounds, worst, S = _pivot(bands, fac, iw, lo, hi, cu, cl, L, pull, w, fs, jr[0],
                                  jr.size, k, rest, nodal_load)
    else:
        rounds, worst, S = _heights_step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, w,
                                         bands, fac, iw, lo, hi, cu, cl, L, pull, profiled,
                                         forces_upper, forces_lower)
    if rounds == 0:
        return rounds, worst, S, 0.0
    return rounds, worst, S, _predict(alpha, w[U], w, fs, n, alpha_next)


def _step_in_increments(increments, second, alpha, a, jl, jr, k, rest, fs, nodal_load, lo, hi,
                        cu, cl, L, pull, profiled, forces_upper, forces_lower, w, bands, fac,
                        iw, alpha_next):
    """:func:`judge_step` in increments: the second starts from the first's settled set and
    leaves the answer's noise (row NOISE) as the first wrote it."""
    n = lo.size
    noise = w[RHS, :n] if second else w[NOISE, :n]
    # (bool(second): a run-time flag there, so that the step compiles once, not once per
    # literal value of ``second``)
    return increments_step(alpha, a, k, rest, nodal_load, lo, hi, cu, cl, fs, pull,
                           forces_upper, forces_lower, profiled and not second, bool(second),
                           iw[0], w[U, :n], w[NET, :n], w[ROUNDOFF, :n], noise, alpha_next)


@njit(cache=True)
def _predict(alpha, u, w, fs, n, out):
    """:func:`~.chain_kernel.predict_alpha` of the judge step's answer ``u`` (its rows
    ORIGIN, ALPHA0, INV) into ``out``: max|α̂ − α|."""
    return predict_alpha(u, n, w[ORIGIN], w[ALPHA0], w[INV], fs, alpha, out)
