"""The O(N) parts of a large-N outer step, compiled: assembly, factored gradient, trial.

At N = 10⁵ each of these was a dozen or more full-length numpy passes
(temporaries of 0.8 MB each) and together about half of a solve outside the
dual walk. Here each is one loop with the same arithmetic, in the same order
where a sum is involved, as the numpy code it replaced:

- :func:`assemble_into` — :func:`lcpbench.model.compiled_driver.assemble_step` moved to
  increments (:class:`lcpbench.model.large_n.IncrementStep`: the step in increments
  d = u − u₀, its linear term the factored gradient at u₀) for a chain of the
  large-N layout (:func:`lcpbench.model.large_n.layout_fits`: joint j joins
  links j, j + 1 and bends at free node j + 1; in free-node indices it touches
  nodes j − 1, j, j + 1 with the coefficients ``coef[j]``);
- :func:`gradient` / :func:`gradient_scale` — :meth:`ContactStep.gradient`
  Jᵀ k (φ̂(u) − φ*) − f and the size of its terms;
- :func:`trial_energy` — :func:`lcpbench.model.large_n.trial_of`
  and the chain's energy (:func:`lcpbench.model.chain_kernel.energy`, rigid walls,
  its sums compensated) in one pass.

Loaded only through :func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..linalg.face_kernel import face_solve as _top_face_solve
from ..linalg.twisted_kernel import face_solve as _face_solve
from ..linalg.twisted_kernel import resolve as _resolve
from ..solvers.dual_kernel import EPS
from ..thresholds import ROUNDOFF_ULPS  # a residual below it stays where the heights are
from .chain_kernel import add_compensated, energy, link_angle  # once (numba_cache)
from .compiled_dual import wall_residuals


@njit(cache=True)
def tangent_terms(alpha, v, phi0):
    """The fields ``v`` = tan α − α and ``phi0`` of the step at α (the height form's
    φ̂(0); the steps in increments never read them, so :func:`assemble_into` leaves
    them to this, called on first use)."""
    for i in range(alpha.size):
        v[i] = math.tan(alpha[i]) - alpha[i]
    for j in range(phi0.size):
        phi0[j] = -v[j + 1] + v[j]


@njit(cache=True)
def assemble_into(alpha, a, k, sk, rest, load, lower, upper, inv_a_cos, coef, origin,
                  alpha0, phi_origin, bands, linear, lo, hi, rows, rrows, sin_alpha, work):
    """Writes the step at α in increments (all arrays preallocated; n = alpha.size − 1
    free nodes, n joints): the fields of the ContactStep, its walls ``lo``/``hi`` about
    u₀, the rows of A = diag(√k) J and their mirror ``rrows`` (the twisted factor's);
    √k given (``sk``, the chain's), sin α kept (``sin_alpha``, for
    :func:`trial_energy_at`) and ``v``, ``phi0`` left to :func:`tangent_terms`;
    ``work``: (n,)."""
    nl = alpha.size
    n = nl - 1
    y = lost = 0.0
    for i in range(nl):
        c = math.cos(alpha[i])
        inv_a_cos[i] = 1.0 / (a * c)
        alpha0[i] = alpha[i]
        sa = math.sin(alpha[i])
        sin_alpha[i] = sa
        y, lost = add_compensated(y, lost, a * sa)  # the node heights, compensated
        if i < n:
            origin[i] = y + lost  # the height of free node i + 1
    alpha0[nl - 1] += -(y + lost) * inv_a_cos[nl - 1]  # the closure error of the pinned end
    for j in range(n):
        wl, wr = inv_a_cos[j], inv_a_cos[j + 1]
        coef[j, 0] = wl
        coef[j, 1] = -wl - wr
        coef[j, 2] = wr
        phi_origin[j] = alpha0[j + 1] - alpha0[j]
        for m in range(3):
            rows[j, m] = coef[j, m] * sk[j]
    rows[0, 0] = 0.0
    rows[n - 1, 2] = 0.0
    for j in range(n):
        for m in range(3):
            rrows[n - 1 - j, 2 - m] = rows[j, m]
    for i in range(n):
        # H[i, i], H[i + 1, i], H[i + 2, i]: the joints i + 1, i, i − 1 (in this order,
        # as the reference adds them)
        d = 0.0
        o1 = 0.0
        if i + 1 < n:
            d += k[i + 1] * (coef[i + 1, 0] * coef[i + 1, 0])
        d += k[i] * (coef[i, 1] * coef[i, 1])
        if i >= 1:
            d += k[i - 1] * (coef[i - 1, 2] * coef[i - 1, 2])
        bands[0, i] = d
        if i + 1 < n:
            o1 += k[i + 1] * coef[i + 1, 0] * coef[i + 1, 1]
            o1 += k[i] * coef[i, 1] * coef[i, 2]
        bands[1, i] = o1
        bands[2, i] = k[i + 1] * coef[i + 1, 0] * coef[i + 1, 2] if i + 2 < n else 0.0
        lo[i] = lower[i] - origin[i]
        hi[i] = upper[i] - origin[i]
    # the linear term: the factored gradient at u₀ (φ̂(u₀) = φ̂ at the origin exactly)
    for j in range(n):
        work[j] = phi_origin[j]
    _gradient_at(coef, k, work, rest, load, linear)


@njit(cache=True)
def _gradient_at(coef, k, phi, rest, load, g):
    """g = Jᵀ k (phi − φ*) − f for joint angles ``phi`` (overwritten by the moments)."""
    n = g.size
    for j in range(n):
        phi[j] = (phi[j] - rest[j]) * k[j]
    for i in range(n):
        s = 0.0
        if i + 1 < n:
            s += coef[i + 1, 0] * phi[i + 1]
        s += coef[i, 1] * phi[i]
        if i >= 1:
            s += coef[i - 1, 2] * phi[i - 1]
        g[i] = s - load[i]


@njit(cache=True)
def gradient(coef, k, phi_origin, rest, load, origin, u, g, m):
    """g = H u + c in factored form, Jᵀ k (φ̂(u₀) + J (u − u₀) − φ*) − f
    (:meth:`lcpbench.model.step.ContactStep.gradient`); ``m``: work (n,)."""
    n = u.size
    for j in range(n):
        s = coef[j, 0] * (u[j - 1] - origin[j - 1]) if j >= 1 else 0.0
        s += coef[j, 1] * (u[j] - origin[j])
        if j + 1 < n:
            s += coef[j, 2] * (u[j + 1] - origin[j + 1])
        m[j] = s + phi_origin[j]
    _gradient_at(coef, k, m, rest, load, g)


@njit(cache=True)
def gradient_scale(coef, k, phi_origin, rest, load, origin, u, g, m):
    """The size of the terms of :func:`gradient` (|J| |u − u₀| + |φ̂(u₀)| + |φ*|, times
    k, through |J|ᵀ, plus |f| + tiny), as :meth:`ContactStep.gradient_scale`."""
    n = u.size
    for j in range(n):
        s = abs(coef[j, 0]) * abs(u[j - 1] - origin[j - 1]) if j >= 1 else 0.0
        s += abs(coef[j, 1]) * abs(u[j] - origin[j])
        if j + 1 < n:
            s += abs(coef[j, 2]) * abs(u[j + 1] - origin[j + 1])
        m[j] = (s + (abs(phi_origin[j]) + abs(rest[j]))) * k[j]
    tiny = 2.2250738585072014e-308
    for i in range(n):
        s = 0.0
        if i + 1 < n:
            s += abs(coef[i + 1, 0]) * m[i + 1]
        s += abs(coef[i, 1]) * m[i]
        if i >= 1:
            s += abs(coef[i - 1, 2]) * m[i - 1]
        g[i] = s + (abs(load[i]) + tiny)


@njit(cache=True)
def trial_energy(alpha, du, t, a, jl, jr, k, rest, link_load, out):
    """Writes α moved by the increments t·du (exact inverse kinematics, each link keeping
    its branch and winding) into ``out`` and returns its energy; NaN where some link
    would need |sin α'| ≥ 1 (:func:`trial_energy_at` with sin α and cos α of ``alpha``)."""
    return trial_energy_at(alpha, np.sin(alpha), np.cos(alpha), du, t, a, jl, jr, k, rest,
                           link_load, out)


@njit(cache=True)
def trial_energy_at(alpha, sin_alpha, inv_a_cos, du, t, a, jl, jr, k, rest, link_load, out):
    """:func:`trial_energy` given sin α and an array with the sign of cos α: a step's
    from :func:`assemble_into` (1/(a cos α), a > 0), so the assembly's numbers are
    reused. The energy is :func:`lcpbench.model.chain_kernel.energy` (joints ``jl``,
    ``jr``), at sin α' of the moved angles."""
    nl = alpha.size
    n = nl - 1
    prev = 0.0
    sines = np.empty(nl)
    for i in range(nl):
        nxt = t * du[i] if i < n else 0.0
        s = sin_alpha[i] + (nxt - prev) / a
        prev = nxt
        if not (abs(s) < 1.0):  # also NaN
            return math.nan
        out[i] = link_angle(s, alpha[i], inv_a_cos[i] < 0.0)
        sines[i] = math.sin(out[i])
    return energy(out, a, jl, jr, k, rest, link_load, sines)


@njit(cache=True)
def block_solve(rows, idx, a, b, grad, u2):
    """u2[idx[a:b]] −= H[block]⁻¹ grad there, one block of :func:`descend`: the rows
    that touch it, the nodes beside it held, on a fresh twisted factor of those rows
    (below five rows, no twist: the QR from the top, as
    :class:`~lcpbench.linalg.saddle.TridiagonalFactor` takes it). False on a zero
    pivot."""
    n = rows.shape[0]
    r0, r1 = max(idx[a] - 1, 0), min(idx[b - 1] + 1, n - 1)
    nb = r1 + 1 - r0
    sub = rows[r0:r1 + 1].copy()
    sub[0, 0] = 0.0
    sub[nb - 1, 2] = 0.0
    fixed = np.ones(nb, np.bool_)
    full = np.zeros(nb)
    for q in range(a, b):
        fixed[idx[q] - r0] = False
        full[idx[q] - r0] = grad[idx[q]]
    x = np.empty(nb)
    R, filled, snap, inv = np.empty((3, nb)), np.empty(nb, np.bool_), np.empty((nb, 4)), \
        np.empty(nb)
    if nb < 5:
        ok = _top_face_solve(sub, fixed, R, filled, snap, inv, 0, full, x)
    else:
        rsub = np.empty((nb, 3))
        for j in range(nb):
            for c in range(3):
                rsub[nb - 1 - j, 2 - c] = sub[j, c]
        ok = _face_solve(sub, rsub, fixed, fixed[::-1].copy(), x[:0], x[:0], R, filled, snap,
                         np.empty((3, nb)), np.empty(nb, np.bool_), np.empty((nb, 4)),
                         np.zeros(3), inv, np.empty(nb), 0, 0, nb // 2, full, x)
    if not ok:
        return False
    for q in range(a, b):
        u2[idx[q]] -= x[idx[q] - r0]
    return True


@njit(cache=True)
def descend(rows, idx, grad, u2):
    """u2[idx] −= H[idx, idx]⁻¹ grad[idx] (``idx`` sorted; H = AᵀA from the rows of A):
    a row of A touches three consecutive nodes, so runs of ``idx`` two or more nodes
    apart are independent blocks, each solved on the rows that touch it
    (:func:`block_solve`): O(|idx|), not O(n). False on a zero pivot."""
    a = 0
    for q in range(1, idx.size + 1):
        if q == idx.size or idx[q] - idx[q - 1] > 2:
            if not block_solve(rows, idx, a, q, grad, u2):
                return False
            a = q
    return True


@njit(cache=True)
def residuals(u, coef, k, phi_origin, rest, load, origin, rows, bands, linear, lo, hi, cu,
              cl, L, F):
    """:func:`lcpbench.model.step_solver.step_residuals` of a large-N step in increments:
    ``(ok, [natural, min_gap, min_reaction, complementarity, term_size], R)``, at elastic
    walls of compliances ``cu``, ``cl`` (1/k; empty: rigid walls) with the compliant
    gaps g + R/k (:func:`~.compiled_dual.wall_residuals`, every step's). Not ok where
    the heights are not finite, or the nodes with no wall row are more than half (the
    reference re-solves them on the whole factor) or meet a zero pivot: the caller runs
    the numpy reference. The same sums as the reference, except Σ g·r
    (complementarity, reported, not judged) summed in order, and at elastic walls R/k
    for the reference's ((R/F)·F)/k."""
    n = u.size
    for i in range(n):
        if not np.isfinite(u[i]):
            return False, np.zeros(5), np.full(n, np.nan)
    u2 = u.copy()
    m = np.empty(n)
    nfree = 0
    for i in range(n):
        if not (np.isfinite(hi[i]) or np.isfinite(lo[i])):
            nfree += 1
    if nfree:  # _complete_heights: the nodes with no wall row, re-solved exactly
        if nfree * 2 > n:
            return False, np.zeros(5), np.full(n, np.nan)
        idx = np.empty(nfree, np.int64)
        q = 0
        for i in range(n):
            if not (np.isfinite(hi[i]) or np.isfinite(lo[i])):
                idx[q] = i
                q += 1
        grad, scale = np.empty(n), np.empty(n)
        gradient(coef, k, phi_origin, rest, load, origin, u2, grad, m)
        gradient_scale(coef, k, phi_origin, rest, load, origin, u2, scale, m)
        for i in range(n):  # a residual at round-off stays (see the reference)
            if abs(grad[i]) <= ROUNDOFF_ULPS * EPS * scale[i]:
                grad[i] = 0.0
        if not descend(rows, idx, grad, u2):  # the nodes with no wall row, by blocks
            return False, np.zeros(5), np.full(n, np.nan)
    R = np.empty(n)
    gradient(coef, k, phi_origin, rest, load, origin, u2, R, m)
    for i in range(n):
        R[i] = -R[i]
    return True, wall_residuals(u2, R, bands, linear, lo, hi, cu, cl, L, F), R


@njit(cache=True)
def _free_residual(coef, k, phi_origin, rest, load, origin, S, u, g, r, m):
    """g = the gradient at u, r = g off S (0 on S); returns max|r|."""
    gradient(coef, k, phi_origin, rest, load, origin, u, g, m)
    size = 0.0
    bad = False
    for i in range(u.size):
        r[i] = 0.0 if S[i] else g[i]
        a = abs(r[i])
        if a > size:
            size = a
        elif a != a:  # NaN: np.max's answer
            bad = True
    return np.nan if bad else size


@njit(cache=True)
def walk_refine(coef, k, phi_origin, rest, load, origin, R, B, tri, invR, invB, m, S, u,
                rounds):
    """The dual walk's refinement at an optimum it found
    (:func:`lcpbench.solvers.compiled_walk.dual_walk`): one step with the exact gradient
    on the face last factored, then :func:`lcpbench.solvers.compiled_walk.refine_on_face` (more
    while the free nodes' residual halves, at most ``rounds``), the same arithmetic.
    ``u`` on the walls on S; returns (u, g)."""
    n = u.size
    g, r, w = np.empty(n), np.empty(n), np.empty(n)
    _free_residual(coef, k, phi_origin, rest, load, origin, S, u, g, r, w)
    _resolve(R, B, tri, invR, invB, m, r)
    u = u - r
    size = _free_residual(coef, k, phi_origin, rest, load, origin, S, u, g, r, w)
    g_v, r_v = np.empty(n), np.empty(n)
    for _ in range(rounds):
        _resolve(R, B, tri, invR, invB, m, r)
        v = u - r
        size_v = _free_residual(coef, k, phi_origin, rest, load, origin, S, v, g_v, r_v, w)
        if not size_v < 0.5 * size:
            break
        u, g, size = v, g_v, size_v
        r, r_v, g_v = r_v, r, np.empty(n)
    return u, g
