"""The compiled parts of the driver around any back-end (fair timing, issue 19 item 6).

numba (``@njit(cache=True)``): what the outer loop of
:func:`lcpbench.model.compiled_driver.run` does around a back-end's call, so that a full solve costs the back-end's time plus the
same small compiled overhead for every back-end:

- :func:`assemble`: the banded step of eqs. 20-31, its stencils and linearisation
  point (:func:`lcpbench.model.compiled_driver.assemble_step`, the public one);
- :func:`qp_form` / :func:`lcp_form`: the forms the back-ends take
  (:func:`lcpbench.model.formulations.step_qp`, the banded QP as CSC arrays;
  :meth:`ContactStep.lcp` with the scaling of ``step_lcp``, the condensed dense LCP);
  :func:`from_lcp`, the heights of an LCP answer;
- :func:`judge`: :func:`lcpbench.model.step_solver.step_residuals`, lcpbench's
  residuals of the back-end's answer and R = K g + z: the solve kernel's judge and
  gradient (:func:`~.compiled_dual.judge_step`, :func:`~lcpbench.solvers.dual_kernel.grad_into`), so
  every back-end is judged by the one copy;
- :func:`advance`: max|α̂ − α| (eq. 21) and the Armijo search on the exact energy
  (:func:`lcpbench.model.chain_kernel.armijo`, :func:`~lcpbench.model.chain_kernel.energy`);
- against walls of any profile, :func:`profile_start`, :func:`profile_assemble`,
  :func:`profile_advance` and :func:`profile_on_walls`: the profile kernel's start, step
  (the walls at the nodes' x, the lagged reactions' slope load), merit search and stop
  (:mod:`lcpbench.model.profile_kernel`, :mod:`lcpbench.model.wall_kernel`: one copy).

The chain's energy and the Armijo rule are :mod:`.chain_kernel`'s, its inverse
kinematics and the banded step :mod:`.compiled_kernel`'s, the step's gradient and judge
:mod:`.compiled_dual`'s (one copy each; :mod:`lcpbench.numba_cache` recompiles every
kernel when any kernel file changes, so a call across files never runs stale code).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..solvers.dual_kernel import grad_into  # the solve kernel's, once (numba_cache)
from .chain_kernel import (  # once each
    energy,
    energy_noise,
    energy_search,
    predict_alpha,
    wall_penalty,
)
from .compiled_dual import grad_and_scale, judge_step
from .compiled_kernel import banded_step  # the step
from .profile_kernel import clipped_start, merit_search, penetration  # a profile's, once
from .wall_kernel import lagged_load, walls_at


# -- the step (model.step) ----------------------------------------------------------
@njit(cache=True)
def assemble(alpha, a, jl, jr, k, rest, fs, n, nodal_load):
    """assemble_step's arrays: (bands, c, 1/(a cos α), v, φ₀, J's coefficients,
    u₀, α̂(u₀), φ̂(u₀)); ``fs`` the shifted index (node + 1) of the first free node.
    The banded step is the solve kernel's (:func:`.compiled_kernel.banded_step`);
    v = tan α − α and φ₀ = v_l − v_r are the forms' extra terms."""
    bands, linear, inv, coef, origin, alpha0, phi_origin = banded_step(
        alpha, a, jl, jr, k, rest, fs, n, nodal_load)
    links, nj = alpha.size, jr.size
    v, phi0 = np.empty(links), np.empty(nj)
    for i in range(links):
        v[i] = np.tan(alpha[i]) - alpha[i]
    for j in range(nj):
        phi0[j] = -v[jr[j]] + (v[jl[j]] if jl[j] >= 0 else 0.0)
    return bands, linear, inv, v, phi0, coef, origin, alpha0, phi_origin


@njit(cache=True)
def qp_form(bands, linear, lo, hi, L, F):
    """step_qp: P = H·(L/F) as CSC arrays (both triangles, rows sorted, the entries of
    ``scipy.sparse.diags``), c/F, lower/L, upper/L and the scaled bands."""
    n = linear.size
    b = bands * (L / F)
    indptr = np.zeros(n + 1, np.int32)
    for j in range(n):
        indptr[j + 1] = indptr[j] + min(j, 2) + min(n - 1 - j, 2) + 1
    data, indices = np.empty(indptr[n]), np.empty(indptr[n], np.int32)
    for j in range(n):
        p = indptr[j]
        for i in range(max(j - 2, 0), min(j + 3, n)):
            data[p] = b[abs(i - j), min(i, j)]
            indices[p] = i
            p += 1
    return data, indices, indptr, linear / F, lo / L, hi / L, b


@njit(cache=True)
def _dense(bands):
    """ContactStep.dense_hessian."""
    n = bands.shape[1]
    H = np.zeros((n, n))
    for i in range(n):
        H[i, i] = bands[0, i]
    for kk in (1, 2):
        for i in range(n - kk):
            H[i + kk, i] += bands[kk, i]
            H[i, i + kk] += bands[kk, i]
    return H


@njit(cache=True)
def _take(H, rows, cols):
    out = np.empty((rows.size, cols.size))
    for i in range(rows.size):
        for j in range(cols.size):
            out[i, j] = H[rows[i], cols[j]]
    return out


@njit(cache=True)
def lcp_form(bands, linear, lo, hi, L, F):
    """ContactStep.lcp_form, the condensed LCP and its scaling: (code, M, q, M̃, q̃, dz, dw,
    rows, heights, condensed); code 1: a lower wall on only some contact rows."""
    H = _dense(bands)
    C = np.flatnonzero(np.isfinite(hi))
    Fi = np.flatnonzero(~np.isfinite(hi))
    top = hi[C].copy()
    S = _take(H, C, C)
    ct = linear[C].copy()
    if Fi.size:  # the nodes with no wall row, condensed out
        rhs = np.empty((Fi.size, C.size + 1))
        rhs[:, :C.size] = _take(H, Fi, C)
        rhs[:, C.size] = linear[Fi]
        X = np.linalg.solve(_take(H, Fi, Fi), rhs)
        HCF = _take(H, C, Fi)
        S = S - HCF @ np.ascontiguousarray(X[:, :C.size])
        ct = ct - HCF @ np.ascontiguousarray(X[:, C.size])
    K = 0.5 * (S + S.T)
    z = (-K) @ top - ct
    m = C.size
    lower = 0
    for i in range(m):
        lower += np.isfinite(lo[C[i]])
    if lower == 0:
        M, q = K, z
    elif lower < m:
        return 1, K, z, K, z, z, z, C, top, Fi
    else:
        M, q = np.zeros((2 * m, 2 * m)), np.empty(2 * m)
        M[:m, :m] = K
        for i in range(m):
            M[i, m + i], M[m + i, i] = 1.0, -1.0
            q[m + i] = top[i] - lo[C[i]]
        q[:m] = z
    size = q.size
    dz, dw = np.empty(size), np.empty(size)
    dz[:m], dz[m:], dw[:m], dw[m:] = L, F, F, L
    Ms = np.empty((size, size))
    for i in range(size):
        for j in range(size):
            Ms[i, j] = M[i, j] * dz[j] / dw[i]
    return 0, M, q, Ms, q / dw, dz, dw, C, top, Fi


@njit(cache=True)
def from_lcp(bands, linear, rows, heights, condensed, zeta):
    """ContactStep.from_lcp: the free node heights of an LCP answer ζ."""
    u = np.empty(linear.size)
    for i in range(rows.size):
        u[rows[i]] = heights[i] - zeta[i]
    if condensed.size:
        H = _dense(bands)
        rhs = -linear[condensed] - _take(H, condensed, rows) @ u[rows]
        u[condensed] = np.linalg.solve(_take(H, condensed, condensed), rhs)
    return u


# -- the judge (model.step_solver.step_residuals) -----------------------------------
@njit(cache=True)
def judge(u, bands, linear, lo, hi, cu, cl, coef, b0, fs, links, origin, phi_origin, k,
          rest, nodal_load, L, F):
    """step_residuals: (ok, [natural, min_gap, min_reaction, complementarity, term_size],
    R), the solve kernel's judge (:func:`~.compiled_dual.judge_step`: the nodes with no
    wall row re-solved on the LDLᵀ of their block, :mod:`lcpbench.linalg.ldl_kernel`);
    ``cu``, ``cl``: the elastic walls' compliances 1/k (empty: rigid walls); not ok for
    heights that are not finite or where the nodes with no wall row cannot be re-solved
    (the caller runs the numpy reference)."""
    n = u.size
    for i in range(n):
        if not np.isfinite(u[i]):
            return False, np.zeros(5), np.full(n, np.nan)  # the reference's NaN answer
    out, R = np.empty(5), np.empty(n)
    ok = judge_step(u, bands, linear, lo, hi, cu, cl,
                    (coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load), L, F,
                    out, R, np.empty(n), np.empty(n, np.bool_), np.empty((4, n)),
                    np.empty(coef.shape[0]), np.zeros((2, n)), np.empty(0))
    return ok, out, R


@njit(cache=True)
def gradient(u, coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load, T):
    """:meth:`ContactStep.gradient <lcpbench.model.step.ContactStep.gradient>`: H u + c in
    factored form, Jᵀ k (φ̂(u) − φ*) − f, plus T (u − u₀) where ``T`` has columns (the
    Newton step's bands; none: the Gauss–Newton step) (:func:`~lcpbench.solvers.dual_kernel.grad_into`)."""
    return grad_into(np.empty(u.size), np.empty(coef.shape[0]), u,
                     (coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load), T)


@njit(cache=True)
def gradient_scale(u, coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load, T):
    """The size of the terms :func:`gradient` sums, per node (the round-off tolerances'
    scale; :func:`~.compiled_dual.grad_and_scale`)."""
    n, nj = u.size, coef.shape[0]
    size = np.empty(n)
    grad_and_scale(np.empty(n), size, np.empty(nj), np.empty(nj), u,
                   (coef, b0, fs, links, origin, phi_origin, k, rest, nodal_load), T)
    return size


# -- the outer step (model.compiled_driver.run) --------------------------------------
@njit(cache=True)
def predict(su, alpha0, origin, inv, fs):
    """α̂ of the step answer ``su`` (:func:`~.chain_kernel.predict_alpha`, eq. 21,
    about u₀), for the Python driver."""
    out = np.empty(alpha0.size)
    predict_alpha(su, su.size, origin, alpha0, inv, fs, alpha0, out)
    return out


@njit(cache=True)
def advance(su, u, alpha, E, stiffness_sum, inv, alpha0, origin, phi_origin, coef, fs, k,
            rest, nodal_load, a, jl, jr, link_load, lo, hi, cu, cl):
    """max|α̂ − α| of the step answer ``su`` (eq. 21, about u₀) and the Armijo search
    on the exact energy along u + t(su − u): (max|Δα|, t, α(t), E(t)); t = 0 where
    no t >= ARMIJO_SHORTEST decreases the energy. ``stiffness_sum``: Σ|k| (the noise);
    ``cu``, ``cl``: the elastic walls' compliances (empty: rigid), whose springs'
    energy (:func:`~.chain_kernel.wall_penalty`) is part of the energy searched on."""
    links, n = alpha.size, u.size
    dalpha = predict_alpha(su, su.size, origin, alpha0, inv, fs, alpha, alpha[:0])
    if not np.all(np.isfinite(su - u)):
        return np.nan, 0.0, alpha, E
    g = gradient(u, coef, jr[0], fs, links, origin, phi_origin, k, rest, nodal_load,
                 np.zeros((2, n)))  # (the Gauss–Newton step: T = 0, added)
    wall_penalty(u, lo, hi, cu, cl, g)  # (nothing where no wall yields)
    trial = np.empty(links)
    t, E_t = energy_search(E, u, su, g, np.empty(n), np.empty(n), alpha, trial, np.empty(links),
                           np.empty(links), inv, energy_noise(E, stiffness_sum),
                           (a, jl, jr, k, rest, link_load, fs), lo, hi, cu, cl)
    if t == 0.0:
        return dalpha, 0.0, alpha, E
    return dalpha, t, trial, E_t


# -- walls of any profile (model.profile_kernel's step, for any back-end) -----------
@njit(cache=True)
def _at(n):
    """The scratch rows of :func:`~.wall_kernel.walls_at`: x, y, upper, lower, h', l',
    h'', l'' at the free nodes."""
    return (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
            np.empty(n), np.empty(n))


@njit(cache=True)
def profile_start(start_alpha, rest_alpha, a, fs, walls):
    """:func:`~.profile_kernel.clipped_start`: (fits, cold, α, u) of a solve against
    walls of any profile (``walls`` = (upper rows, lower rows, the upper wall's table,
    the lower's); ``start_alpha`` empty: from the arc)."""
    n, links = walls[0].size, rest_alpha.size
    alpha, u = np.empty(links), np.empty(n)
    ok, cold = clipped_start(start_alpha, rest_alpha, a, fs, walls, alpha, u,
                             np.empty(links), np.empty(links), _at(n))
    return ok, cold, alpha, u


@njit(cache=True)
def profile_assemble(alpha, a, jl, jr, k, rest, fs, nodal_load, walls, mu_up, mu_lo):
    """The contact step against walls of any profile at α, as the profile kernel builds
    it: :func:`assemble`'s arrays with the slope load s = J_xᵀ(μ̄ h'(x) − ν̄ l'(x)) of the
    lagged reactions ``mu_up``, ``mu_lo`` in the nodal load, then (lower, upper, nodal
    load + s): the bounds the walls at the nodes' x where a node has a row."""
    n = nodal_load.size
    sin_a, cos_a = np.sin(alpha), np.cos(alpha)
    at = _at(n)
    walls_at(sin_a, cos_a, a, fs, *walls, *at)
    nl = np.empty(n)
    lagged_load(alpha, cos_a, sin_a, fs, mu_up, mu_lo, at[4], at[5], nodal_load, np.empty(n),
                np.empty(n), nl)
    return assemble(alpha, a, jl, jr, k, rest, fs, n, nl) + (at[3], at[2], nl)


@njit(cache=True)
def profile_advance(su, u, alpha, inv, alpha0, origin, phi_origin, coef, fs, k, rest,
                    nodal_load, a, jl, jr, link_load, walls, mu_up, mu_lo, net, F):
    """:func:`advance` against walls of any profile: max|α̂ − α| and the profile kernel's
    search on its merit (:func:`~.profile_kernel.merit_search`, the step's nodal load
    ``nodal_load`` with its slope load; σ from the step's net reactions ``net``, the
    lagged ones and F = EI/ℓ²): (max|Δα|, t, α(t), E(α(t)), the heights there); t = 0
    where the search found no decrease."""
    links, n = alpha.size, u.size
    dalpha = predict_alpha(su, su.size, origin, alpha0, inv, fs, alpha, alpha[:0])
    if not np.all(np.isfinite(su)):
        return np.nan, 0.0, alpha, np.nan, u
    sin_a = np.sin(alpha)
    E = energy(alpha, a, jl, jr, k, rest, link_load, sin_a)
    at = _at(n)
    walls_at(sin_a, np.cos(alpha), a, fs, *walls, *at)
    hs, ls = at[2].copy(), at[3].copy()
    big = F
    for i in range(n):
        big = max(big, max(abs(net[i]), max(mu_up[i], mu_lo[i])))
    noise_k = 0.0
    for j in range(k.size):
        noise_k += abs(k[j])
    g = gradient(u, coef, jr[0], fs, links, origin, phi_origin, k, rest, nodal_load,
                 np.zeros((2, n)))  # (the Gauss–Newton step: T = 0, added)
    d, ut, trial = np.empty(n), np.empty(n), np.empty(links)
    sin_t, cos_t = np.empty(links), np.empty(links)
    chain = (a, jl, jr, k, rest, link_load, fs)
    t, full = merit_search(E, u, su, g, d, ut, alpha, trial, sin_t, cos_t, inv, dalpha, big,
                           noise_k, chain, walls, mu_up, mu_lo, at, at[1].copy(), hs, ls)
    if t == 0.0:
        return dalpha, 0.0, alpha, E, u
    return (dalpha, t, trial, energy(trial, a, jl, jr, k, rest, link_load, sin_t),
            su.copy() if full else ut)


@njit(cache=True)
def profile_on_walls(alpha, a, fs, walls):
    """(how far α crosses the exact walls (mm), the walls at its nodes' x: upper, lower)
    (:func:`~.profile_kernel.penetration`)."""
    n = walls[0].size
    at = _at(n)
    worst = penetration(np.sin(alpha), np.cos(alpha), a, fs, walls, at)
    return worst, at[2], at[3]
