"""The compiled kernel's certificate and step residuals (:mod:`lcpbench.model.compiled_kernel`).

numba versions of :func:`~lcpbench.solvers.banded.step_certificate` and of the judge's
natural residual (:func:`lcpbench.model.step_solver.step_residuals`) on the step's bands
H (the banded step of eqs. 20-31) and its linear term c, in the same order of
operations as the reference where that is cheap; the gradient with its term sizes
(:func:`grad_and_scale`). The dual walk they certify is
:func:`lcpbench.solvers.dual_kernel.dual_active_set`. Every pass writes into work
arrays that :func:`lcpbench.model.compiled_kernel.solve_chain` allocates once.
Loaded only through :func:`lcpbench.numba_cache.kernel_module` (see there).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.ldl_kernel import refactor, resolve  # the faces' LDLᵀ
from ..solvers.dual_kernel import TINY, grad_into, matvec_row, max_abs  # the walk's module

# rows of ``wa`` (links): 1 / (a cos α), α₀, the iterate α, the trial α, their sines
# and cosines
INV, ALPHA0, ALPHA, TRIAL, SIN_A, SIN_T, COS_A, COS_T = range(8)


@njit(cache=True)
def grad_and_scale(out, size, m, ms, u, gp, T):
    """:func:`grad_into` at u without and with ``scale`` (into ``out`` and ``size``),
    in one pass over the joints and one over the nodes: the same operations on the
    same numbers, so the same bits as the two calls (the certificate's pair)."""
    coef, b0, fs, links, origin, phi_origin, k, rest, load = gp
    n, nj = u.size, coef.shape[0]
    for j in range(nj):
        s = sa = 0.0
        for c in range(3):
            i = b0 + c + j - fs
            du = u[i] - origin[i] if 0 <= i < n else 0.0
            w = coef[j, c]
            if c == 0:
                s, sa = w * du, abs(w) * abs(du)
            else:
                s, sa = s + w * du, sa + abs(w) * abs(du)
        m[j] = ((s + phi_origin[j]) - rest[j]) * k[j]
        ms[j] = (sa + (abs(phi_origin[j]) + abs(rest[j]))) * k[j]
    for i in range(n):
        s = sa = 0.0
        for c in range(3):
            j = fs + i - b0 - c
            if 0 <= j < nj:
                s += coef[j, c] * m[j]
                sa += abs(coef[j, c]) * ms[j]
        out[i] = s - load[i]
        size[i] = sa + (abs(load[i]) + TINY)
        if T.shape[1]:  # (no columns: no T, as grad_into)
            d0 = u[i] - origin[i]
            t = T[0, i] * d0
            ta = abs(T[0, i]) * abs(d0)
            if i >= 1:
                d1 = u[i - 1] - origin[i - 1]
                t += T[1, i - 1] * d1
                ta += abs(T[1, i - 1]) * abs(d1)
            if i + 1 < n:
                d2 = u[i + 1] - origin[i + 1]
                t += T[1, i] * d2
                ta += abs(T[1, i]) * abs(d2)
            out[i] += t
            size[i] += ta


@njit(cache=True)
def certify(u, ru, rl, lo, hi, cu, cl, gp, grad, size, m, ms, T):
    """The certificate's residual; ``grad``: the gradient at u (when finite); ``cu``,
    ``cl``: the walls' compliances (empty: rigid), whose gap is g + c R."""
    n = u.size
    for i in range(n):
        if not (np.isfinite(u[i]) and np.isfinite(ru[i]) and np.isfinite(rl[i])):
            return np.inf
    if n == 0:
        return 0.0
    grad_and_scale(grad, size, m, ms, u, gp, T)
    force, span = TINY, 1.0 + max_abs(u)
    stat = feas = neg = comp = 0.0
    soft = cu.size == n
    for i in range(n):
        force = max(force, size[i] + ru[i] + rl[i])
    for i in range(n):
        stat = max(stat, abs(grad[i] + ru[i] - rl[i]))
        gu, gl = hi[i] - u[i], u[i] - lo[i]
        if soft:
            gu, gl = gu + cu[i] * ru[i], gl + cl[i] * rl[i]
        feas = max(feas, -gu, -gl)
        neg = max(neg, -ru[i], -rl[i])
        if np.isfinite(hi[i]):
            comp = max(comp, abs(gu * ru[i]))
        if np.isfinite(lo[i]):
            comp = max(comp, abs(gl * rl[i]))
    return max(stat / force, feas / span, neg / force, comp / (force * span))


@njit(cache=True)
def _wall_terms(hi, lo, u, R, cu, cl, L, F, nat, min_gap, min_r, comp_up, comp_lo):
    """One node's terms of step_residuals (gap g and reaction r of each wall row,
    scaled by L and F): the accumulators (natural residual max|min(g, r)|, least
    gap, least reaction, Σ g·r of each wall) updated; at an elastic wall of
    compliance ``cu``/``cl`` (0: rigid) the gap is the compliant one, g + c R.
    Shared by :func:`judge_step` and :func:`wall_residuals`."""
    up, low = np.isfinite(hi), np.isfinite(lo)
    if up:
        g = ((hi - u) + cu * max(R, 0.0)) / L
        r = (max(R, 0.0) if low else R) / F
        nat = max(nat, abs(min(g, r)))
        min_gap, min_r = min(min_gap, g), min(min_r, r)
        comp_up += g * r
    if low:
        g = ((u - lo) + cl * max(-R, 0.0)) / L
        r = (max(-R, 0.0) if up else -R) / F
        nat = max(nat, abs(min(g, r)))
        min_gap, min_r = min(min_gap, g), min(min_r, r)
        comp_lo += g * r
    return nat, min_gap, min_r, comp_up, comp_lo


@njit(cache=True)
def wall_residuals(u2, R, bands, linear, lo, hi, cu, cl, L, F):
    """The verdict terms of step_residuals over the nodes (heights ``u2`` and reactions
    ``R`` given; ``cu``, ``cl``: the walls' compliances 1/k, empty for rigid walls):
    [natural residual, least gap, least reaction, |Σ g·r| of both walls, term size / F],
    the term size max(|H| |u| + |c|) over the wall rows in banded_matvec's order
    (large_kernel's judge; every other step's is :func:`judge_step`)."""
    n = u2.size
    soft = cu.size == n
    nat, min_gap, min_r, comp_up, comp_lo, term = 0.0, np.inf, np.inf, 0.0, 0.0, 0.0
    for i in range(n):
        nat, min_gap, min_r, comp_up, comp_lo = _wall_terms(
            hi[i], lo[i], u2[i], R[i], cu[i] if soft else 0.0, cl[i] if soft else 0.0, L,
            F, nat, min_gap, min_r, comp_up, comp_lo)
        if np.isfinite(hi[i]) or np.isfinite(lo[i]):  # banded_matvec(|H|, |u|) + |c|
            s = abs(bands[0, i]) * abs(u2[i])
            for kk in (1, 2):
                if i - kk >= 0:
                    s += abs(bands[kk, i - kk]) * abs(u2[i - kk])
                if i + kk < n:
                    s += abs(bands[kk, i]) * abs(u2[i + kk])
            term = max(term, s + abs(linear[i]))
    return np.array([nat, min_gap, min_r, abs(comp_up) + abs(comp_lo), term / F])


@njit(cache=True)
def judge_step(u, bands, linear, lo, hi, cu, cl, gp, L, F, out, R, u2, rows, fac, m, T, g0):
    """step_residuals into ``out`` and ``R`` (u2, rows, fac, m: work arrays); ``g0``: the
    gradient at u where the caller has it (the certificate's), else empty; ``cu``,
    ``cl``: the walls' compliances (empty: rigid)."""
    n = u.size
    some_free = False
    for i in range(n):
        rows[i] = np.isfinite(hi[i]) or np.isfinite(lo[i])
        some_free = some_free or not rows[i]
        u2[i] = u[i]
    if some_free:  # the nodes with no wall row, re-solved exactly
        if g0.size == n:
            R[:] = g0
        else:
            grad_into(R, m, u2, gp, T)
        if not refactor(fac, bands, rows, cu[:0], 0, n):
            out[:] = 0.0
            return False
        for i in range(n):
            if rows[i]:
                R[i] = 0.0
        resolve(fac, R)
        for i in range(n):
            if not rows[i]:
                u2[i] -= R[i]
    grad_into(R, m, u2, gp, T)
    nat, min_gap, min_r, comp_up, comp_lo, term = 0.0, np.inf, np.inf, 0.0, 0.0, 0.0
    soft = cu.size == n
    for i in range(n):
        R[i] = -R[i]
        up, low = np.isfinite(hi[i]), np.isfinite(lo[i])
        nat, min_gap, min_r, comp_up, comp_lo = _wall_terms(
            hi[i], lo[i], u2[i], R[i], cu[i] if soft else 0.0, cl[i] if soft else 0.0, L, F,
            nat, min_gap, min_r, comp_up, comp_lo)
        if up or low:
            term = max(term, matvec_row(bands, u2, i, n, True) + abs(linear[i]))
    out[0], out[1], out[2], out[3], out[4] = nat, min_gap, min_r, abs(comp_up) + abs(comp_lo), \
        term / F
    return True
