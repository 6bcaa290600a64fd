"""The result judge compiled: the judge step and the residual checks in numba.

numba (``@njit(cache=True)``) versions of :func:`lcpbench.model.judge.judge`'s
arithmetic for a converged driver answer: the judge's own contact step at the
final α (assembled from the energy of the chain, solved exactly by block
principal pivoting from the answer's contact set, :func:`~lcpbench.model.judge._pivot_step`),
the round-off of the reactions, the exact-geometry certificate
(:func:`lcpbench.model.result.certify`: forward kinematics, closure, the
torque residual of :func:`lcpbench.model.chain.torque_residual`), the sign,
complementarity and penetration checks, the contraction estimate ρ and the
force error bound. The numpy judge is the reference; the Python side
(:mod:`lcpbench.model.judge_compiled`) turns the numbers returned here into
the same :class:`~lcpbench.model.judge.Judgement` with the same reasons
(tests compare both on the hard suite, random scenes and adversarial answers).

Independent of the solve kernel (:mod:`lcpbench.model.compiled_kernel`): the
judge step is block principal pivoting (Júdice–Pires, then Murty's least
index), not the dual active set; nothing here is imported from that file and
nothing there from here. The banded Cholesky below is textbook arithmetic
(LAPACK's dpbtrf/dpbtrs for bandwidth 2), written again in this file because
numba's on-disk cache of a function is invalidated only when *its own* file
changes.

The chain must have consecutive joints and contiguous free nodes (the
layouts the solve kernel takes, :func:`lcpbench.model.compiled.applies`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

EPS = np.finfo(np.float64).eps
TINY = np.finfo(np.float64).tiny
# model.judge's thresholds (tests check they are the same numbers)
FORCE_TOL_CAP, FORCE_TOL_PER_RAD = 1e-3, 100.0
NODE_SHARE, NODE_FACTOR, NODE_GROSS = 0.1, 10.0, 0.05
FLOOR_ULPS, ROUNDOFF_ULPS = 256.0, 64.0
RHO_MIN, RHO_MAX = 0.5, 0.99
STEP_NOISE = 1e4 * EPS
GEOMETRY_TOL = 1e-6
PIVOT_ROUNDS, STALL = 30, 3

#: names of the entries of the ``stats`` array that :func:`judge_answer` returns
STATS = ("tau", "F0", "eps_R", "comp", "comp_allowed", "min_gap", "min_force",
         "complementarity", "closure", "max_torque_residual", "relative_torque_residual",
         "floor_R", "R_min", "total", "node", "node_allowed", "rho", "judge_total_force",
         "rounds", "pen", "closure_allowed")
SETTLED, NOT_SETTLED = 0, 1


# -- the chain's exact geometry (model.chain) ------------------------------------------
@njit(cache=True)
def _positions(alpha, a):
    x = np.zeros(alpha.size + 1)
    y = np.zeros(alpha.size + 1)
    sx = sy = 0.0
    for i in range(alpha.size):
        sx += a * np.cos(alpha[i])
        sy += a * np.sin(alpha[i])
        x[i + 1], y[i + 1] = sx, sy
    return x, y


@njit(cache=True)
def _torque_residual(alpha, x, jl, jr, k, rest, link_load, fs, nodal_force, pinned_right):
    """chain.torque_residual: k(φ − φ*) minus the moment statics demands at each joint."""
    links = alpha.size
    force = np.zeros(links + 1)
    for i in range(nodal_force.size):
        force[fs - 1 + i] = nodal_force[i]
    if pinned_right:
        m = 0.0
        for i in range(links):
            m += link_load[i] * (0.5 * (x[i] + x[i + 1]))
        fx = 0.0
        for i in range(links + 1):
            fx += force[i] * x[i]
        force[links] = -(m + fx) / x[links]
    f_sum = np.zeros(links + 2)  # suffix sums Σ_{q>=p}
    fx_sum = np.zeros(links + 2)
    p_sum = np.zeros(links + 1)
    px_sum = np.zeros(links + 1)
    for p in range(links, -1, -1):
        f_sum[p] = f_sum[p + 1] + force[p]
        fx_sum[p] = fx_sum[p + 1] + force[p] * x[p]
    for p in range(links - 1, -1, -1):
        p_sum[p] = p_sum[p + 1] + link_load[p]
        px_sum[p] = px_sum[p + 1] + link_load[p] * (0.5 * (x[p] + x[p + 1]))
    res = np.empty(jr.size)
    spring_max = 0.0
    for j in range(jr.size):
        at = jr[j]
        xp = x[at]
        moment = (fx_sum[at] - xp * f_sum[at]) + (px_sum[at] - xp * p_sum[at])
        phi = alpha[jr[j]] - (alpha[jl[j]] if jl[j] >= 0 else 0.0)
        spring = k[j] * (phi - rest[j])
        res[j] = spring - moment
        spring_max = max(spring_max, k[j] * abs(phi - rest[j]))
    return res, spring_max


# -- the judge's contact step (model.step.assemble_step, written for the judge) ----------
@njit(cache=True)
def _step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, y):
    """(bands, linear, coef, inv, origin, alpha0, phi_origin) of the step at α."""
    links = alpha.size
    nj = jr.size
    inv = np.empty(links)
    v = np.empty(links)
    for i in range(links):
        inv[i] = 1.0 / (a * np.cos(alpha[i]))
        v[i] = np.tan(alpha[i]) - alpha[i]
    coef = np.empty((nj, 3))
    diag, off1, off2, lin = (np.zeros(links + 2), np.zeros(links + 2), np.zeros(links + 2),
                             np.zeros(links + 2))
    b0 = jr[0]
    for j in range(nj):
        wl = inv[jl[j]] if jl[j] >= 0 else 0.0
        wr = inv[jr[j]]
        c0, c1, c2 = wl, -wl - wr, wr
        coef[j, 0], coef[j, 1], coef[j, 2] = c0, c1, c2
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
    origin = np.empty(n)
    for i in range(n):
        origin[i] = y[fs - 1 + i]
    alpha0 = alpha.copy()
    if fs - 1 + n - 1 < links:  # pinned right end: the last link closes the chain
        alpha0[links - 1] += -y[links] * inv[links - 1]
    phi_origin = np.empty(nj)
    for j in range(nj):
        phi_origin[j] = alpha0[jr[j]] - (alpha0[jl[j]] if jl[j] >= 0 else 0.0)
    bands = np.zeros((3, n))
    linear = np.empty(n)
    for i in range(n):
        bands[0, i] = diag[fs + i]
        if i < n - 1:
            bands[1, i] = off1[fs + i]
        if i < n - 2:
            bands[2, i] = off2[fs + i]
        linear[i] = lin[fs + i] - nodal_load[i]
    return bands, linear, coef, inv, origin, alpha0, phi_origin


@njit(cache=True)
def _grad(u, absolute, coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load):
    """ContactStep.gradient (absolute False) or .gradient_scale (True) at u."""
    nj = coef.shape[0]
    y = np.zeros(links + 2)
    for i in range(u.size):
        d = u[i] - origin[i]
        y[fs + i] = abs(d) if absolute else d
    g = np.zeros(links + 2)
    for j in range(nj):
        c0, c1, c2 = coef[j, 0], coef[j, 1], coef[j, 2]
        if absolute:
            c0, c1, c2 = abs(c0), abs(c1), abs(c2)
        m = c0 * y[b0 + j] + c1 * y[b0 + 1 + j] + c2 * y[b0 + 2 + j]
        if absolute:
            m = (m + (abs(phi_origin[j]) + abs(rest[j]))) * k[j]
        else:
            m = ((m + phi_origin[j]) - rest[j]) * k[j]
        g[b0 + j] += c0 * m
        g[b0 + 1 + j] += c1 * m
        g[b0 + 2 + j] += c2 * m
    out = np.empty(u.size)
    for i in range(u.size):
        out[i] = g[fs + i] + (abs(nodal_load[i]) + TINY) if absolute else g[fs + i] - nodal_load[i]
    return out


@njit(cache=True)
def _abs_matvec(bands, x):
    """|H| |x| on the bands (a size of terms, for round-off bounds)."""
    n = x.size
    out = np.empty(n)
    for i in range(n):
        s = abs(bands[0, i]) * abs(x[i])
        for kk in (1, 2):
            if i - kk >= 0:
                s += abs(bands[kk, i - kk]) * abs(x[i - kk])
            if i + kk < n:
                s += abs(bands[kk, i]) * abs(x[i + kk])
        out[i] = s
    return out


@njit(cache=True)
def _solve_free(bands, free, rhs):
    """H[free, free]⁻¹ rhs[free] by a banded Cholesky (None-like: ok False if not PD)."""
    m = free.size
    ab = np.zeros((3, m))
    for p in range(m):
        ab[0, p] = bands[0, free[p]]
        for kk in (1, 2):
            if p + kk < m:
                gap = free[p + kk] - free[p]
                if gap <= 2:
                    ab[kk, p] = bands[gap, free[p]]
    for j in range(m):  # L Lᵀ, in place (dpbtf2)
        ajj = ab[0, j]
        if not ajj > 0.0:
            return False, rhs
        ajj = np.sqrt(ajj)
        ab[0, j] = ajj
        kn = min(2, m - 1 - j)
        for p in range(1, kn + 1):
            ab[p, j] /= ajj
        for q in range(1, kn + 1):
            for p in range(q, kn + 1):
                ab[p - q, j + q] -= ab[p, j] * ab[q, j]
    x = np.empty(m)
    for p in range(m):
        x[p] = rhs[free[p]]
    for j in range(m):
        x[j] /= ab[0, j]
        for p in range(1, min(2, m - 1 - j) + 1):
            x[j + p] -= x[j] * ab[p, j]
    for j in range(m - 1, -1, -1):
        t = x[j]
        for p in range(1, min(2, m - 1 - j) + 1):
            t -= ab[p, j] * x[j + p]
        x[j] = t / ab[0, j]
    return True, x


@njit(cache=True)
def _pivot(bands, linear, lo, hi, L, gp, up, lo_set, pull):
    """model.judge._pivot_step: (rounds or 0 if it did not settle, u, net reaction,
    round-off per wall node, worst round-off, term size S)."""
    coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load = gp
    n = linear.size
    up, lo_set = up.copy(), lo_set.copy()
    best, stall = n + 1, 0
    empty = np.zeros(n)
    for rounds in range(1, PIVOT_ROUNDS + 2 * n + 1):
        u = origin.copy()
        nfree = 0
        for i in range(n):
            if up[i]:
                u[i] = hi[i]
            elif lo_set[i]:
                u[i] = lo[i]
            else:
                nfree += 1
        if nfree:
            free = np.empty(nfree, np.int64)
            c = 0
            for i in range(n):
                if not (up[i] or lo_set[i]):
                    free[c] = i
                    c += 1
            for _ in range(2):  # solve, then refine with the factored gradient
                g = _grad(u, False, coef, b0, fs, links, origin, phi_origin, k, rest,
                          nodal_load)
                ok, x = _solve_free(bands, free, g)
                if not ok:
                    return 0, u, empty, empty, 0.0, 0.0
                for p in range(nfree):
                    u[free[p]] -= x[p]
        net = -_grad(u, False, coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load)
        scale = _grad(u, True, coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load)
        size = _abs_matvec(bands, u)
        count, first = 0, -1
        change = np.zeros(n, np.int64)  # 1 release up, 2 release lo, 3 join up, 4 join lo
        worst, S = 0.0, 0.0
        roundoff = np.empty(n)
        for i in range(n):
            roundoff[i] = ROUNDOFF_ULPS * EPS * scale[i]
            size[i] += abs(linear[i])
            worst = max(worst, roundoff[i])
            S = max(S, size[i])
            slack = max(max(roundoff[i], pull), ROUNDOFF_ULPS * EPS * size[i])
            reach = max(ROUNDOFF_ULPS * EPS * (abs(u[i]) + L), pull / bands[0, i])
            if up[i] and net[i] < -slack:
                change[i] = 1
            elif lo_set[i] and net[i] > slack:
                change[i] = 2
            elif not up[i] and not lo_set[i] and u[i] > hi[i] + reach:
                change[i] = 3
            elif not up[i] and not lo_set[i] and u[i] < lo[i] - reach:
                change[i] = 4
            if change[i]:
                count += 1
                if first < 0:
                    first = i
        if count == 0:
            for i in range(n):
                if not (up[i] or lo_set[i]):
                    roundoff[i] = 0.0
            return rounds, u, net, roundoff, worst, S
        if count < best:
            best, stall = count, 0
        else:
            stall += 1
        for i in range(n):
            if change[i] == 0 or (stall >= STALL and i != first):
                continue
            if change[i] == 1:
                up[i] = False
            elif change[i] == 2:
                lo_set[i] = False
            elif change[i] == 3:
                up[i] = True
            else:
                lo_set[i] = True
    return 0, origin, empty, empty, 0.0, 0.0


@njit(cache=True)
def _contraction(step_sizes, judge_dalpha):
    """model.judge._contraction: ρ from the last two ratios of step sizes, in [½, 0.99]."""
    sizes = np.empty(step_sizes.size + 1)
    m = 0
    for s in step_sizes:
        if np.isfinite(s) and s > STEP_NOISE:
            sizes[m] = s
            m += 1
    if np.isfinite(judge_dalpha) and judge_dalpha > STEP_NOISE:
        sizes[m] = judge_dalpha
        m += 1
    rho, seen = RHO_MIN, 0
    for i in range(m - 1, 0, -1):  # the last two ratios with a > 0
        if seen == 2:
            break
        if sizes[i - 1] > 0:
            r = sizes[i] / sizes[i - 1]
            rho = r if seen == 0 else max(rho, r)
            seen += 1
    return min(max(rho, RHO_MIN), RHO_MAX)


@njit(cache=True)
def judge_answer(alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                 wall, channel, forces_upper, forces_lower, tol, step_sizes):
    """model.judge.judge's numbers for an answer whose driver converged.

    ``fs``: shifted index (node + 1) of the first free node; ``F`` the force
    scale EI/ℓ²; ``L`` the length ℓ; ``wall`` the upper wall's height (inf:
    none); ``channel`` a lower wall at −wall too.

    Returns ``(code, stats, forces_upper, forces_lower, judge_upper,
    judge_lower, torque_residual, x, y)``: ``code`` SETTLED or NOT_SETTLED
    (the judge step did not settle), ``stats`` the numbers named in
    :data:`STATS`, the answer's reactions with their round-off set to zero,
    the judge step's reactions R', the certificate's torque residual and the
    node positions.
    """
    n = lo.size
    links = alpha.size
    tau = min(FORCE_TOL_CAP, FORCE_TOL_PER_RAD * tol)
    F_up = F_lo = 0.0
    for i in range(n):
        F_up += forces_upper[i]
        F_lo += forces_lower[i]
    F0 = max(max(abs(F_up), abs(F_lo)), F)
    eps_R = NODE_SHARE * tau * F0
    stats = np.full(len(STATS), np.nan)
    x, y = _positions(alpha, a)
    # the judge step at α, from the answer's contact set
    bands, linear, coef, inv, origin, alpha0, phi_origin = _step(
        alpha, a, jl, jr, k, rest, fs, n, nodal_load, y)
    gp = (coef, jr[0], fs, links, origin, phi_origin, k, rest, nodal_load)
    scale0 = _grad(origin, True, coef, jr[0], fs, links, origin, phi_origin, k, rest,
                   nodal_load)
    size0 = _abs_matvec(bands, origin)
    up, lo_set = np.zeros(n, np.bool_), np.zeros(n, np.bool_)
    noise = np.empty(n)
    for i in range(n):
        touch = max(eps_R / bands[0, i], 1e3 * EPS * L)
        on_up = hi[i] - origin[i] <= touch
        on_lo = origin[i] - lo[i] <= touch
        noise[i] = ROUNDOFF_ULPS * EPS * (scale0[i] if on_up or on_lo
                                          else size0[i] + abs(linear[i]))
        up[i] = on_up and (not on_lo or hi[i] - origin[i] <= origin[i] - lo[i])
        lo_set[i] = on_lo and not up[i]
    rounds, u, net, roundoff, worst, S = _pivot(bands, linear, lo, hi, L, gp, up, lo_set,
                                                eps_R)
    settled = rounds > 0
    fu, fl = forces_upper.copy(), forces_lower.copy()
    ju, jlo = np.zeros(n), np.zeros(n)
    if settled:
        for i in range(n):  # values within round-off are zero, not reactions
            if abs(fu[i]) <= noise[i]:
                fu[i] = 0.0
            if abs(fl[i]) <= noise[i]:
                fl[i] = 0.0
            if channel:  # model.judge.split_reactions
                mid = 0.5 * (hi[i] + lo[i])
                near = u[i] >= mid if np.isfinite(mid) else np.isfinite(hi[i])
                ju[i], jlo[i] = (net[i], 0.0) if near else (0.0, -net[i])
            else:
                ju[i] = net[i]
    # the certificate of the cleaned reactions (model.result.certify)
    min_gap, min_force, cmp = np.inf, 0.0, 0.0
    has_gap = np.isfinite(wall)
    for i in range(n):
        yf = y[fs - 1 + i]
        min_force = min(min_force, fu[i])
        if has_gap:
            min_gap = min(min_gap, wall - yf)
            cmp = max(cmp, abs((wall - yf) * fu[i]))
        if channel:
            min_force = min(min_force, fl[i])
            min_gap = min(min_gap, yf + wall)
            cmp = max(cmp, abs((yf + wall) * fl[i]))
    pinned_right = fs - 1 + n - 1 < links
    closure = abs(y[links]) if pinned_right else 0.0
    net_force = fl - fu
    res, spring_max = _torque_residual(alpha, x, jl, jr, k, rest, link_load, fs, net_force,
                                       pinned_right)
    worst_t = 0.0
    for j in range(res.size):
        worst_t = max(worst_t, abs(res[j]))
    rel_t = worst_t / max(spring_max, F * L)
    # complementarity and sign on the answer's heights
    comp = 0.0
    R_min = 0.0
    for i in range(n):
        yf = y[fs - 1 + i]
        comp = max(comp, min(fu[i] / F0, (hi[i] - yf) / L))
        comp = max(comp, min(fl[i] / F0, (yf - lo[i]) / L))
        R_min = min(R_min, min(fu[i], fl[i]))
    floor_R = FLOOR_ULPS * EPS * S if settled else 0.0
    stats[0], stats[1], stats[2], stats[3] = tau, F0, eps_R, comp
    stats[4] = max(NODE_SHARE * tau, floor_R / F0) if settled else NODE_SHARE * tau
    stats[5], stats[6], stats[7], stats[8] = min_gap, min_force, cmp, closure
    stats[9], stats[10], stats[11], stats[12] = worst_t, rel_t, floor_R, R_min
    stats[19] = min(GEOMETRY_TOL, NODE_SHARE * tau) * L
    stats[20] = GEOMETRY_TOL * L
    if not settled:
        return NOT_SETTLED, stats, fu, fl, ju, jlo, res, x, y
    dalpha, prev = 0.0, 0.0
    for i in range(links):  # ContactStep.predict_alpha, eq. (21), about u₀
        node = i + 1 - (fs - 1)
        cur = u[node] - origin[node] if 0 <= node < n else 0.0
        dalpha = max(dalpha, abs((alpha0[i] + (cur - prev) * inv[i]) - alpha[i]))
        prev = cur
    rho = _contraction(step_sizes, dalpha)
    kappa = 1.0 / (1.0 - rho)
    floor = 0.0
    for i in range(n):
        floor += roundoff[i]
    floor = (floor + worst) / F0
    s_up = s_lo = d_max = 0.0
    for i in range(n):
        d_up, d_lo = fu[i] - ju[i], fl[i] - jlo[i]
        s_up += d_up
        s_lo += d_lo
        d_max = max(d_max, max(abs(d_up), abs(d_lo)))
    J = 0.0
    for i in range(n):
        J += ju[i]
    stats[13] = kappa * max(abs(s_up), abs(s_lo)) / F0 + floor
    stats[14] = kappa * d_max / F0
    stats[15] = max(max(NODE_FACTOR * tau, NODE_GROSS), NODE_FACTOR * floor_R / F0)
    stats[16], stats[17], stats[18] = rho, J, rounds
    return SETTLED, stats, fu, fl, ju, jlo, res, x, y
