"""The default solve compiled: assembly, dual active set, line search, outer loop.

numba (``@njit(cache=True)``) versions of the numpy reference, line for line:
:func:`lcpbench.model.step.assemble_step` (the banded step of eqs. 20-31),
:func:`lcpbench.solvers.banded.solve_banded_qp` with ``method="dual"`` (the walk, its
refinement, :func:`~lcpbench.solvers.banded.step_certificate`), the judge's natural
residual (:func:`lcpbench.model.step_solver.step_residuals`) and the globalised driver
of :mod:`lcpbench.model.driver` (Armijo search on the exact energy of
:mod:`lcpbench.model.chain`). The numpy modules are the readable reference and document
the algorithm; this file repeats their arithmetic in the same order where that is cheap
(sums, the band products), so both take the same path and agree to round-off
(``tests/model/test_compiled.py``).

One file on purpose: numba's on-disk cache of a function is invalidated only when *its
own* file changes (a kernel split over files could run stale code).

Nothing here decides "converged": the Python side builds the DriverOutput and judges it
(:mod:`lcpbench.model.judge_compiled`). What the kernel cannot do as the reference does
(the primal safeguard, a face not positive definite, a step rejected) it reports with a
code, and the caller runs the numpy reference.
"""

from __future__ import annotations

import numpy as np
from numba import njit

EPS = np.finfo(np.float64).eps
TINY = np.finfo(np.float64).tiny
TIE = 1e-6  # solvers.banded.TIE
RTOL = 1e-9  # solvers.banded.solve_banded_qp(rtol=)
FLOOR_ULPS = 256.0  # solvers.judge.FLOOR_ULPS

# outcome codes of solve_chain (the Python side turns them into reasons)
CONVERGED, MAX_OUTER, LINE_SEARCH, NO_FIT = 0, 1, 2, 3
# the step left the path of the reference: the caller runs the numpy driver
BAIL_PRIMAL, BAIL_NOT_PD, BAIL_REPEAT, BAIL_LIMIT, BAIL_CERT, BAIL_JUDGE = 10, 11, 12, 13, 14, 15


# -- the chain (model.chain) ----------------------------------------------------
@njit(cache=True)
def _node_heights(alpha, a):
    y = np.zeros(alpha.size + 1)
    acc = 0.0
    for i in range(alpha.size):
        acc += a * np.sin(alpha[i])
        y[i + 1] = acc
    return y


@njit(cache=True)
def _energy(alpha, a, jl, jr, k, rest, link_load):
    """chain.energy: ½Σk(φ−φ*)² − Σ P·(centre height)."""
    s = 0.0
    for j in range(jr.size):
        left = alpha[jl[j]] if jl[j] >= 0 else 0.0
        d = (alpha[jr[j]] - left) - rest[j]
        s += k[j] * (d * d)
    y = _node_heights(alpha, a)
    w = 0.0
    for i in range(alpha.size):
        w += link_load[i] * (0.5 * (y[i] + y[i + 1]))
    return 0.5 * s - w


@njit(cache=True)
def _alpha_from_heights(u, reference, a, fs, links):
    """chain.alpha_from_heights: (ok, α); not ok when some |Δy| >= a."""
    y = np.zeros(links + 1)
    y[fs - 1:fs - 1 + u.size] = u
    out = np.empty(links)
    for i in range(links):
        s = (y[i + 1] - y[i]) / a
        if not np.isfinite(s) or abs(s) >= 1.0:
            return False, out
        base = np.arcsin(s)
        if np.cos(reference[i]) < 0.0:
            base = np.pi - base
        out[i] = base + 2 * np.pi * np.rint((reference[i] - base) / (2 * np.pi))
    return True, out


# -- the banded step (model.step) -------------------------------------------------
@njit(cache=True)
def _assemble(alpha, a, jl, jr, k, rest, fs, n, nodal_load):
    """model.step.assemble_step: bands, c, the stencils of J and the linearisation point."""
    links = alpha.size
    nj = jr.size
    inv = np.empty(links)
    v = np.empty(links)
    for i in range(links):
        inv[i] = 1.0 / (a * np.cos(alpha[i]))
        v[i] = np.tan(alpha[i]) - alpha[i]
    coef = np.empty((nj, 3))
    t = np.empty(nj)
    for j in range(nj):
        wl = inv[jl[j]] if jl[j] >= 0 else 0.0
        wr = inv[jr[j]]
        coef[j, 0] = wl
        coef[j, 1] = -wl - wr
        coef[j, 2] = wr
        phi0 = -v[jr[j]] + (v[jl[j]] if jl[j] >= 0 else 0.0)
        t[j] = k[j] * (phi0 - rest[j])
    b0 = jr[0]
    size = links + 2
    diag, off1, off2, lin = np.zeros(size), np.zeros(size), np.zeros(size), np.zeros(size)
    for m in range(3):
        for j in range(nj):
            diag[b0 + m + j] += k[j] * coef[j, m] ** 2
        for j in range(nj):
            lin[b0 + m + j] += coef[j, m] * t[j]
    for m in range(2):
        for j in range(nj):
            off1[b0 + m + j] += k[j] * coef[j, m] * coef[j, m + 1]
    for j in range(nj):
        off2[b0 + j] += k[j] * coef[j, 0] * coef[j, 2]
    y = _node_heights(alpha, a)
    origin = y[fs - 1:fs - 1 + n].copy()
    alpha0 = alpha.copy()
    if fs - 1 + n - 1 < links:  # the right end is pinned: close the chain
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
    return bands, linear, inv, coef, origin, alpha0, phi_origin


@njit(cache=True)
def _J(du, coef, b0, fs, links):
    y = np.zeros(links + 2)
    y[fs:fs + du.size] = du
    out = np.empty(coef.shape[0])
    for j in range(coef.shape[0]):
        s = coef[j, 0] * y[b0 + j]
        s += coef[j, 1] * y[b0 + 1 + j]
        s += coef[j, 2] * y[b0 + 2 + j]
        out[j] = s
    return out


@njit(cache=True)
def _JT(m, coef, b0, fs, n, links):
    g = np.zeros(links + 2)
    for kk in range(3):
        for j in range(m.size):
            g[b0 + kk + j] += coef[j, kk] * m[j]
    return g[fs:fs + n].copy()


@njit(cache=True)
def _gradient(u, coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load):
    """ContactStep.gradient: Jᵀ k (φ̂(u) − φ*) − f, about the linearisation point."""
    m = _J(u - origin, coef, b0, fs, links)
    for j in range(m.size):
        m[j] = ((m[j] + phi_origin[j]) - rest[j]) * k[j]
    g = _JT(m, coef, b0, fs, u.size, links)
    return g - nodal_load


@njit(cache=True)
def _gradient_scale(u, coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load):
    """ContactStep.gradient_scale: the size of the terms of the gradient."""
    ac = np.abs(coef)
    m = _J(np.abs(u - origin), ac, b0, fs, links)
    for j in range(m.size):
        m[j] = (m[j] + (abs(phi_origin[j]) + abs(rest[j]))) * k[j]
    g = _JT(m, ac, b0, fs, u.size, links)
    return g + (np.abs(nodal_load) + TINY)


@njit(cache=True)
def _grad(u, gp):
    """The exact gradient at u; ``gp`` = (coef, b0, fs, links, origin, phi_origin, k,
    rest, nodal_load) of the step."""
    return _gradient(u, gp[0], gp[1], gp[2], gp[3], gp[4], gp[5], gp[6], gp[7], gp[8])


@njit(cache=True)
def _grad_scale(u, gp):
    return _gradient_scale(u, gp[0], gp[1], gp[2], gp[3], gp[4], gp[5], gp[6], gp[7], gp[8])


@njit(cache=True)
def _matvec(bands, x):
    """H x on the bands, summed in the order of solvers.banded._Banded.matvec."""
    n = x.size
    out = np.empty(n)
    for i in range(n):
        s = bands[2, i - 2] * x[i - 2] if i >= 2 else 0.0
        s += bands[1, i - 1] * x[i - 1] if i >= 1 else 0.0
        s += bands[0, i] * x[i]
        s += bands[1, i] * x[i + 1] if i + 1 < n else 0.0
        s += bands[2, i] * x[i + 2] if i + 2 < n else 0.0
        out[i] = s
    return out


# -- banded Cholesky (LAPACK dpbtf2 / dpbtrs, lower, bandwidth 2) ------------------
@njit(cache=True)
def _factor(ab, start=0):
    """In place on rows 0-2 (the bands); row 3 gets 1 / L_jj, so that the solves
    multiply instead of divide. Columns before ``start`` are already factored
    (and their updates applied). False when a leading minor is not positive
    definite."""
    n = ab.shape[1]
    for j in range(start, n):
        ajj = ab[0, j]
        if not ajj > 0.0:
            return False
        ajj = np.sqrt(ajj)
        ab[0, j] = ajj
        kn = min(2, n - 1 - j)
        r = 1.0 / ajj
        ab[3, j] = r
        for p in range(1, kn + 1):
            ab[p, j] *= r
        for q in range(1, kn + 1):  # the trailing rank-1 update (dsyr)
            tq = -ab[q, j]
            for p in range(q, kn + 1):
                ab[p - q, j + q] += ab[p, j] * tq
    return True


@njit(cache=True)
def _resolve(ab, x):
    """Overwrites x with the solution of L Lᵀ x = x."""
    n = x.size
    for j in range(n):
        x[j] = x[j] * ab[3, j]
        t = x[j]
        for p in range(1, min(2, n - 1 - j) + 1):
            x[j + p] -= t * ab[p, j]
    for j in range(n - 1, -1, -1):
        t = x[j]
        for p in range(min(2, n - 1 - j), 0, -1):
            t -= ab[p, j] * x[j + p]
        x[j] = t * ab[3, j]
    return x


@njit(cache=True)
def _refactor(fac, bands, fixed, c0):
    """Factor H with the rows and columns of the ``fixed`` nodes replaced by the
    identity, from column ``c0`` on (``c0 = 0``: all of it). ``fac`` holds the
    factor of a face that differs from ``fixed`` only at nodes >= c0 + 2, so its
    columns before c0 stand (a column reads the nodes up to two below it); the
    same operations in the same order as a full factorisation, so the same bits."""
    n = fixed.size
    for kk in range(3):
        for i in range(c0, n):
            keep = (not fixed[i]) and (i + kk < n) and (not fixed[i + kk])
            fac[kk, i] = bands[kk, i] * (1.0 if keep else 0.0)
    for i in range(c0, n):
        if fixed[i]:
            fac[0, i] += 1.0
    for j in range(max(0, c0 - 2), c0):  # the updates of the factored columns
        kn = min(2, n - 1 - j)
        for q in range(1, kn + 1):
            if j + q < c0:
                continue
            tq = -fac[q, j]
            for p in range(q, kn + 1):
                fac[p - q, j + q] += fac[p, j] * tq
    return _factor(fac, c0)


@njit(cache=True)
def _max_abs(x):  # max|x| and the slope's dot product are loops: loading the cache then
    m = 0.0  # needs neither numba's array reductions nor its BLAS (which import scipy)
    for v in x:
        m = max(m, abs(v))
    return m


@njit(cache=True)
def _run_maxima(v, slack):
    """The deepest violation v > slack of every run of consecutive violated nodes."""
    n = v.size
    out = np.zeros(n, np.bool_)
    for i in range(n):
        if v[i] > slack:
            left = v[i - 1] if i > 0 else -np.inf
            right = v[i + 1] if i + 1 < n else -np.inf
            out[i] = v[i] >= left and v[i] > right
    return out


# -- the dual active set (solvers.banded._dual, _finish, step_certificate) ----------
@njit(cache=True)
def _dual(bands, linear, lo, hi, warm_up, warm_lo, max_iter, gp):
    """(code, u, g, sigma, face solves): code 0 at the optimum (after refinement)."""
    n = linear.size
    has_lo = False
    for i in range(n):
        has_lo = has_lo or np.isfinite(lo[i])
    fac = np.empty((4, n))
    factored = np.zeros(n, np.bool_)  # the face ``fac`` holds (none fixed: H itself)
    if not _refactor(fac, bands, factored, 0):
        return BAIL_NOT_PD, linear, linear, linear, 0
    u = _resolve(fac, -linear)
    g = np.zeros(n)
    slack = 32 * EPS * (1.0 + _max_abs(u))
    sigma, wall, S = np.zeros(n), np.zeros(n), np.zeros(n, np.bool_)
    warm = False
    for i in range(n):
        warm = warm or warm_up[i] or warm_lo[i]
    seen = [sigma.copy()]
    seen.pop()
    at_face_minimiser = True
    it = 0
    while True:
        if at_face_minimiser:
            v_up = u - hi
            v_lo = lo - u
            for i in range(n):
                if S[i]:
                    v_up[i] = -np.inf
                    v_lo[i] = -np.inf
            found = False
            J_up = np.zeros(n, np.bool_)
            J_lo = np.zeros(n, np.bool_)
            if warm:
                warm = False
                for i in range(n):
                    J_up[i] = warm_up[i] and v_up[i] > slack
                    J_lo[i] = has_lo and warm_lo[i] and v_lo[i] > slack
                    found = found or J_up[i] or J_lo[i]
            if not found:
                J_up = _run_maxima(v_up, slack)
                J_lo = _run_maxima(v_lo, slack) if has_lo else np.zeros(n, np.bool_)
                for i in range(n):
                    found = found or J_up[i] or J_lo[i]
                if not found:  # the optimum: one refinement on the face just factored
                    for i in range(n):
                        if S[i]:
                            u[i] = wall[i]
                    g = _grad(u, gp)
                    r = g.copy()
                    for i in range(n):
                        if S[i]:
                            r[i] = 0.0
                    p = _resolve(fac, r)
                    return 0, u - p, g - _matvec(bands, p), sigma, it
            for old in seen:
                if _max_abs(old - sigma) == 0.0:  # the same working set
                    return BAIL_REPEAT, u, g, sigma, it
            seen.append(sigma.copy())
            for i in range(n):
                if J_up[i]:
                    sigma[i] = 1.0
                    wall[i] = hi[i]
                elif J_lo[i]:
                    sigma[i] = -1.0
                    wall[i] = lo[i]
                S[i] = sigma[i] != 0.0
        if it >= max_iter:
            return BAIL_LIMIT, u, g, sigma, it
        it += 1
        d = np.empty(n)
        for i in range(n):
            d[i] = (wall[i] - u[i]) * (1.0 if S[i] else 0.0)
        r = g + _matvec(bands, d)
        for i in range(n):
            if S[i]:
                r[i] = 0.0
        first = n  # the first node whose wall changed since the last factorisation
        for i in range(n):
            if S[i] != factored[i]:
                first = i
                break
        if first < n:
            if not _refactor(fac, bands, S, max(0, first - 2)):
                return BAIL_NOT_PD, u, g, sigma, it
            factored[:] = S
        d -= _resolve(fac, r)
        g_face = g + _matvec(bands, d)
        s = np.inf
        ratio = np.full(n, np.inf)
        for i in range(n):
            sg = sigma[i] * g_face[i]
            if sg > 0.0:
                lam = max(-sigma[i] * g[i], 0.0)
                ratio[i] = lam / (lam + sg)
                s = min(s, ratio[i])
        if s < 1.0:
            u = u + s * d
            g = g + s * (g_face - g)
            for i in range(n):
                if ratio[i] <= s + TIE:  # ties within round-off go together
                    sigma[i] = 0.0
                    S[i] = False
            at_face_minimiser = False
            continue
        u, g, at_face_minimiser = u + d, g_face, True


@njit(cache=True)
def _certificate(u, ru, rl, lo, hi, gp):
    """solvers.banded.step_certificate: the scaled KKT residual of a step answer."""
    n = u.size
    for i in range(n):
        if not (np.isfinite(u[i]) and np.isfinite(ru[i]) and np.isfinite(rl[i])):
            return np.inf
    if n == 0:
        return 0.0
    grad = _grad(u, gp)
    size = _grad_scale(u, gp)
    force, span = TINY, 1.0 + _max_abs(u)
    stat = feas = neg = comp = 0.0
    for i in range(n):
        force = max(force, size[i] + ru[i] + rl[i])
    for i in range(n):
        stat = max(stat, abs(grad[i] + ru[i] - rl[i]))
        feas = max(feas, u[i] - hi[i], lo[i] - u[i])
        neg = max(neg, -ru[i], -rl[i])
        if np.isfinite(hi[i]):
            comp = max(comp, abs((hi[i] - u[i]) * ru[i]))
        if np.isfinite(lo[i]):
            comp = max(comp, abs((u[i] - lo[i]) * rl[i]))
    return max(stat / force, feas / span, neg / force, comp / (force * span))


@njit(cache=True)
def _residuals(u, bands, linear, lo, hi, gp, L, F):
    """model.step_solver.step_residuals: (ok, [natural, min_gap, min_reaction,
    complementarity, term_size], R) with R = −gradient on the completed heights."""
    n = u.size
    rows = np.empty(n, np.bool_)
    some_free = False
    for i in range(n):
        rows[i] = np.isfinite(hi[i]) or np.isfinite(lo[i])
        some_free = some_free or not rows[i]
    u2 = u.copy()
    if some_free:  # the nodes with no wall row, re-solved exactly
        grad = _grad(u2, gp)
        fac = np.empty((4, n))
        if not _refactor(fac, bands, rows, 0):
            return False, np.zeros(5), grad
        for i in range(n):
            if rows[i]:
                grad[i] = 0.0
        x = _resolve(fac, grad)
        for i in range(n):
            if not rows[i]:
                u2[i] -= x[i]
    R = -_grad(u2, gp)
    size = _matvec(np.abs(bands), np.abs(u2))
    nat, min_gap, min_r, comp_up, comp_lo, term = 0.0, np.inf, np.inf, 0.0, 0.0, 0.0
    for i in range(n):
        up, low = np.isfinite(hi[i]), np.isfinite(lo[i])
        if up:
            g = (hi[i] - u2[i]) / L
            r = (max(R[i], 0.0) if low else R[i]) / F
            nat = max(nat, abs(min(g, r)))
            min_gap, min_r = min(min_gap, g), min(min_r, r)
            comp_up += g * r
        if low:
            g = (u2[i] - lo[i]) / L
            r = (max(-R[i], 0.0) if up else -R[i]) / F
            nat = max(nat, abs(min(g, r)))
            min_gap, min_r = min(min_gap, g), min(min_r, r)
            comp_lo += g * r
        if up or low:
            term = max(term, size[i] + abs(linear[i]))
    out = np.array([nat, min_gap, min_r, abs(comp_up) + abs(comp_lo), term / F])
    return True, out, R


@njit(cache=True)
def _contact_step(alpha, a, jl, jr, k, rest, fs, n, nodal_load, lo, hi, L, F,
                  warm_u, warm_up, warm_lo, warm_flags, max_iter, request):
    """One contact step at α: assemble, dual walk, certificate, judge (code 0: solved)."""
    bands, linear, inv, coef, origin, alpha0, phi_origin = _assemble(
        alpha, a, jl, jr, k, rest, fs, n, nodal_load)
    gp = (coef, jr[0], fs, alpha.size, origin, phi_origin, k, rest, nodal_load)
    W_up, W_lo, bad = np.zeros(n, np.bool_), np.zeros(n, np.bool_), False
    for i in range(n):
        bad = bad or lo[i] > hi[i]
        if warm_flags & 1 and not np.isnan(warm_u[i]):  # the walls the last answer is on
            ui = min(max(warm_u[i], lo[i]), hi[i])
            W_up[i] = np.isfinite(hi[i]) and ui >= hi[i]
            W_lo[i] = np.isfinite(lo[i]) and ui <= lo[i]
        if warm_flags & 2:
            W_up[i] = W_up[i] or (warm_up[i] and np.isfinite(hi[i]))
        if warm_flags & 4:
            W_lo[i] = W_lo[i] or (warm_lo[i] and np.isfinite(lo[i]))
        W_lo[i] = W_lo[i] and not W_up[i]
    empty = np.zeros(5)
    if bad:  # crossed walls: the reference hands this to the primal method
        return BAIL_PRIMAL, linear, linear, linear, linear, 0, inv, alpha0, origin, gp, empty, linear
    code, u, grad, sigma, it = _dual(bands, linear, lo, hi, W_up, W_lo, max_iter, gp)
    if code != 0:
        return code, u, u, u, sigma, it, inv, alpha0, origin, gp, empty, u
    r_up, r_lo = np.zeros(n), np.zeros(n)
    for i in range(n):
        u[i] = min(max(u[i], lo[i]), hi[i])
        if sigma[i] > 0:
            r_up[i] = max(-grad[i], 0.0)
        elif sigma[i] < 0:
            r_lo[i] = max(grad[i], 0.0)
    if not _certificate(u, r_up, r_lo, lo, hi, gp) <= RTOL:
        return BAIL_CERT, u, r_up, r_lo, sigma, it, inv, alpha0, origin, gp, empty, u
    ok, res, R = _residuals(u, bands, linear, lo, hi, gp, L, F)
    if not (ok and res[0] <= max(10.0 * request, FLOOR_ULPS * EPS * res[4])):
        return BAIL_JUDGE, u, r_up, r_lo, sigma, it, inv, alpha0, origin, gp, res, R
    return 0, u, r_up, r_lo, sigma, it, inv, alpha0, origin, gp, res, R


@njit(cache=True)
def _record(rec, count, it, t, dalpha, E):
    if count == rec.shape[1]:
        bigger = np.empty((4, 2 * rec.shape[1]))
        bigger[:, :count] = rec
        rec = bigger
    rec[0, count], rec[1, count], rec[2, count], rec[3, count] = it, t, dalpha, E
    return rec, count + 1


@njit(cache=True)
def solve_chain(rest_alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                tol, max_outer, start_alpha, warm_u, warm_up, warm_lo, warm_flags,
                max_iter, request):
    """The globalised driver (model.driver._globalised) around the compiled step.

    ``fs``: shifted index (node + 1) of the first free node; ``start_alpha``
    empty for a cold start; ``warm_flags``: bit 0 ``warm_u``, bit 1 ``warm_up``,
    bit 2 ``warm_lo`` are given (a continuation's last step).

    Returns ``(code, alpha, forces_upper, forces_lower, u, sigma, records,
    count, residuals, forces_net)``; ``records`` rows: face solves, step
    length t, max|Δα|, energy; ``sigma`` +1/−1 on the upper/lower walls.
    """
    n = lo.size
    links = rest_alpha.size
    rec = np.empty((4, min(max_outer, 64)))
    count, zero, none, ok = 0, np.zeros(n), np.zeros(5), False
    alpha = rest_alpha.copy()
    u = zero
    if start_alpha.size == links:  # a neighbour's answer, clipped to the walls
        y = _node_heights(start_alpha, a)
        u = np.minimum(np.maximum(y[fs - 1:fs - 1 + n], lo), hi)
        ok, alpha = _alpha_from_heights(u, start_alpha, a, fs, links)
    if not ok:
        warm_flags = 0
        y = _node_heights(rest_alpha, a)
        u = np.minimum(np.maximum(y[fs - 1:fs - 1 + n], lo), hi)
        ok, alpha = _alpha_from_heights(u, rest_alpha, a, fs, links)
    if not ok:
        return NO_FIT, rest_alpha.copy(), zero, zero, zero, zero, rec, count, none, zero
    E = _energy(alpha, a, jl, jr, k, rest, link_load)
    noise_k = 0.0
    for j in range(k.size):
        noise_k += abs(k[j])
    trial, E_t = alpha, E
    for _ in range(max_outer):
        code, su, r_up, r_lo, sigma, it, inv, alpha0, origin, gp, res, R = _contact_step(
            alpha, a, jl, jr, k, rest, fs, n, nodal_load, lo, hi, L, F,
            warm_u, warm_up, warm_lo, warm_flags, max_iter, request)
        if code != 0:
            return code, alpha, zero, zero, u, sigma, rec, count, none, zero
        dalpha = prev = 0.0
        for i in range(links):  # predict_alpha, eq. (21), about u0
            node = i + 1 - (fs - 1)
            cur = su[node] - origin[node] if 0 <= node < n else 0.0
            dalpha = max(dalpha, abs((alpha0[i] + (cur - prev) * inv[i]) - alpha[i]))
            prev = cur
        d = su - u
        g_u, slope = _grad(u, gp), 0.0
        for i in range(n):  # the dot product, a loop (see _max_abs)
            slope += g_u[i] * d[i]
        noise = 1e-12 * (abs(E) + noise_k * 1e-6)
        t = 1.0
        while True:
            ok, trial = _alpha_from_heights(u + t * d, alpha, a, fs, links)
            if ok:
                E_t = _energy(trial, a, jl, jr, k, rest, link_load)
                if E_t <= E + 1e-4 * t * min(slope, 0.0) + noise:
                    break
            t *= 0.5
            if t < 1e-12:
                rec, count = _record(rec, count, it, 0.0, dalpha, E)
                return LINE_SEARCH, alpha, zero, zero, u, sigma, rec, count, none, zero
        u, alpha, E = u + t * d, trial, E_t
        rec, count = _record(rec, count, it, t, dalpha, E)
        warm_u, warm_up, warm_lo, warm_flags = su, sigma > 0, sigma < 0, 7
        if dalpha < tol:
            return CONVERGED, alpha, r_up, r_lo, su, sigma, rec, count, res, R
    return MAX_OUTER, alpha, zero, zero, u, zero, rec, count, none, zero
