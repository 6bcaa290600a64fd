"""The O(N) parts of a large-N outer step, compiled: assembly, factored gradient, energy.

At N = 10⁵ each of these was a dozen or more full-length numpy passes
(temporaries of 0.8 MB each) and together about half of a solve outside the
dual walk. Here each is one loop with the same arithmetic, in the same order
where a sum is involved, as the numpy reference it replaces:

- :func:`assemble` — :func:`lcpbench.model.step.assemble_step` followed by
  :func:`lcpbench.model.large_n.increment_step` (the step in increments
  d = u − u₀, its linear term the factored gradient at u₀) for a chain of the
  large-N layout (:func:`lcpbench.model.large_n.layout_fits`: joint j joins
  links j, j + 1 and bends at free node j + 1; in free-node indices it touches
  nodes j − 1, j, j + 1 with the coefficients ``coef[j]``);
- :func:`gradient` / :func:`gradient_scale` — :meth:`ContactStep.gradient`
  Jᵀ k (φ̂(u) − φ*) − f and the size of its terms;
- :func:`trial_energy` — :func:`lcpbench.model.large_n.alpha_from_increments`
  and :func:`lcpbench.model.chain.energy` (rigid walls) in one pass, its two
  sums compensated (Neumaier), since the Armijo test compares energies of
  ~10⁵ terms to 1e-12 of their size.

Loaded only through :func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def assemble(alpha, a, k, rest, load, lower, upper, inv_a_cos, v, coef, phi0, origin,
             alpha0, phi_origin, bands, linear, lo, hi, rows, rrows):
    """Writes the step at α in increments (all arrays preallocated; n = alpha.size − 1
    free nodes, n joints): the fields of the ContactStep, its walls ``lo``/``hi`` about
    u₀, the rows of A = diag(√k) J and their mirror ``rrows`` (the twisted factor's)."""
    sk = np.empty(k.size)
    for j in range(k.size):
        sk[j] = math.sqrt(k[j])
    assemble_into(alpha, a, k, sk, rest, load, lower, upper, inv_a_cos, v, coef, phi0,
                  origin, alpha0, phi_origin, bands, linear, lo, hi, rows, rrows,
                  np.empty(alpha.size), np.empty(k.size))


@njit(cache=True)
def assemble_into(alpha, a, k, sk, rest, load, lower, upper, inv_a_cos, v, coef, phi0,
                  origin, alpha0, phi_origin, bands, linear, lo, hi, rows, rrows, sin_alpha,
                  work):
    """:func:`assemble` with √k given (``sk``, the chain's) and sin α kept (``sin_alpha``,
    for :func:`trial_energy_at`); ``work``: (n,)."""
    nl = alpha.size
    n = nl - 1
    y = 0.0
    for i in range(nl):
        c = math.cos(alpha[i])
        inv_a_cos[i] = 1.0 / (a * c)
        v[i] = math.tan(alpha[i]) - alpha[i]
        alpha0[i] = alpha[i]
        sa = math.sin(alpha[i])
        sin_alpha[i] = sa
        y += a * sa
        if i < n:
            origin[i] = y  # the height of free node i + 1
    alpha0[nl - 1] += -y * inv_a_cos[nl - 1]  # the closure error of the pinned end
    for j in range(n):
        wl, wr = inv_a_cos[j], inv_a_cos[j + 1]
        coef[j, 0] = wl
        coef[j, 1] = -wl - wr
        coef[j, 2] = wr
        phi0[j] = -v[j + 1] + v[j]
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
def _add(total, comp, x):
    """Neumaier's compensated sum: (total, compensation) after adding x."""
    t = total + x
    if abs(total) >= abs(x):
        comp += (total - t) + x
    else:
        comp += (x - t) + total
    return t, comp


@njit(cache=True)
def energy(alpha, a, k, rest, link_load):
    """½ Σ k (φ − φ*)² − Σ w_i ȳ_i of the chain at α (rigid walls), compensated sums."""
    nl = alpha.size
    s, cs = 0.0, 0.0
    for j in range(nl - 1):
        dphi = (alpha[j + 1] - alpha[j]) - rest[j]
        s, cs = _add(s, cs, k[j] * dphi * dphi)
    w, cw = 0.0, 0.0
    y = 0.0
    for i in range(nl):
        y1 = y + a * math.sin(alpha[i])
        w, cw = _add(w, cw, link_load[i] * (0.5 * (y + y1)))
        y = y1
    return 0.5 * (s + cs) - (w + cw)


@njit(cache=True)
def trial_energy(alpha, du, t, a, k, rest, link_load, out):
    """Writes α moved by the increments t·du (exact inverse kinematics, each link keeping
    its branch and winding) into ``out`` and returns its energy; NaN where some link
    would need |sin α'| ≥ 1."""
    nl = alpha.size
    n = nl - 1
    prev = 0.0
    for i in range(nl):
        nxt = t * du[i] if i < n else 0.0
        s = math.sin(alpha[i]) + (nxt - prev) / a
        prev = nxt
        if not (abs(s) < 1.0):  # also NaN
            return math.nan
        base = math.asin(s)
        if math.cos(alpha[i]) < 0.0:
            base = math.pi - base
        out[i] = base + 2 * math.pi * round((alpha[i] - base) / (2 * math.pi))
    return energy(out, a, k, rest, link_load)


@njit(cache=True)
def trial_energy_at(alpha, sin_alpha, inv_a_cos, du, t, a, k, rest, link_load, out):
    """:func:`trial_energy` at the α of a step assembled by :func:`assemble_into`, its
    sin α and the sign of cos α (that of 1/(a cos α), a > 0) taken from the assembly:
    the same numbers."""
    nl = alpha.size
    n = nl - 1
    prev = 0.0
    for i in range(nl):
        nxt = t * du[i] if i < n else 0.0
        s = sin_alpha[i] + (nxt - prev) / a
        prev = nxt
        if not (abs(s) < 1.0):  # also NaN
            return math.nan
        base = math.asin(s)
        if inv_a_cos[i] < 0.0:
            base = math.pi - base
        out[i] = base + 2 * math.pi * round((alpha[i] - base) / (2 * math.pi))
    return energy(out, a, k, rest, link_load)
