"""The chain's kinematics, exact energy and Armijo rule, compiled once for every loop.

- :func:`add_compensated` — the compensated sum, with which every kernel sums the node
  heights of a step's linearisation point and its closure y_N;
- :func:`fit_heights`, :func:`link_angle` — the inverse kinematics: the link angles of
  given node heights, each link on its branch and winding; :func:`free_heights`, the
  forward one (the free nodes' heights at α);
- :func:`energy`, :func:`wall_penalty` — the exact energy E(α) = ½ Σ k (φ − φ*)² −
  Σ P ȳ (eq. 18's joint angles, the link loads P at the link centres ȳ), its sums
  compensated (a line search compares energies of ~10⁵ terms to 1e-12 of their size),
  and the elastic walls' springs;
- :func:`armijo`, :func:`energy_noise` — the sufficient-decrease test at one step
  length, and the round-off it allows; :func:`energy_search`, the Armijo search on
  the energy along a step in the heights (the solve kernel's and the compiled
  driver's);
- :func:`predict_alpha` — the linearised kinematics, eq. (21).

The kernels call these in their loops; plain Python through
:func:`lcpbench.numba_cache.kernel_module` (:func:`lcpbench.model.chain.energy`,
:func:`lcpbench.model.outer.armijo`). ``NUMBA_DISABLE_JIT=1`` runs them as Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..thresholds import ARMIJO_DECREASE, ARMIJO_SHORTEST, ENERGY_NOISE


@njit(cache=True)
def add_compensated(y, lost, term):
    """``(y + term, lost + its rounding error)``: one step of a compensated sum
    (Neumaier's; the error by Knuth's TwoSum, exact and without a branch: the same
    bits as Fast2Sum with the larger operand first); ``y + lost`` is the sum.

    The kernels sum the node heights y_i = Σ_{k<=i} Δy_k of a step's linearisation point
    and its closure y_N with it. A plain running sum carries ~√N ε max|y| (at N = 10⁵,
    10⁻¹³ mm): a height error δ moves a node's force by ~16 EI δ / a³, and the closure
    error, put on the last link, bends it by δ / (a cos α) — a torque 10 % off at the
    last joint at 10⁵. Compensated, y_i is exact to a few ulps of itself."""
    y1 = y + term
    back = y1 - y
    return y1, lost + ((y - (y1 - back)) + (term - back))


@njit(cache=True)
def link_angle(s, reference, back):
    """The angle α with sin α = ``s`` on the branch of ``reference`` (``back``: cos α < 0,
    α = π − arcsin s, else arcsin s) and its 2π-winding (the nearest to it)."""
    base = np.arcsin(s)
    if back:
        base = np.pi - base
    return base + 2 * np.pi * np.rint((reference - base) / (2 * np.pi))


@njit(cache=True)
def fit_heights(out, u, reference, a, fs, links, inv, sines, cosines):
    """The link angles whose free nodes (``fs`` − 1 on, contiguous) have heights ``u``
    (inverse kinematics, :func:`lcpbench.model.chain.alpha_from_heights`) into ``out``;
    False when some |Δy| >= a. ``inv``:
    1 / (a cos α) of ``reference`` if known (its sign is the branch), else empty.

    ``sines``, ``cosines``: sin α and cos α of the fitted α, without a transcendental
    call: sin α = s = Δy / a exactly (α = arcsin s, or π − arcsin s, plus 2πk), and
    cos α = ±√((1 − s)(1 + s)), the sign that of the branch. They equal numpy's
    sin and cos of the rounded α to round-off (closer to the exact values: α
    carries the rounding of arcsin, s does not), and save the energy's sine and the
    assembly's cosine of every link (the reference computes both from α)."""
    off, n = fs - 1, u.size
    y0 = u[0] if off == 0 else 0.0
    for i in range(links):
        y1 = u[i + 1 - off] if off <= i + 1 < off + n else 0.0
        s = (y1 - y0) / a
        y0 = y1
        if not np.isfinite(s) or abs(s) >= 1.0:
            return False
        back = (inv[i] if inv.size == links else np.cos(reference[i])) < 0.0
        out[i] = link_angle(s, reference[i], back)
        c = np.sqrt((1.0 - s) * (1.0 + s))
        sines[i] = s
        cosines[i] = -c if back else c
    return True


@njit(cache=True)
def free_heights(u, alpha, a, fs):
    """The free nodes' heights of the chain at α into u: the running sums of a sin α
    (model.chain.heights)."""
    y, n = 0.0, u.size
    if fs == 1:
        u[0] = 0.0
    for i in range(alpha.size):
        y += a * np.sin(alpha[i])
        node = i + 1 - (fs - 1)
        if 0 <= node < n:
            u[node] = y


@njit(cache=True)
def predict_alpha(su, n, origin, alpha0, inv, fs, alpha, out):
    """α̂ of a step's answer ``su`` (its first ``n`` free nodes' heights) from the
    linearised kinematics, eq. (21), written about u₀: α̂_i = α̂_i(u₀) +
    (y_(i+1) − y_i) / (a cos α_i), y the heights less u₀ (``origin``; 0 at the
    pinned nodes), ``alpha0`` α̂(u₀), ``inv`` 1/(a cos α); ``fs`` the shifted index
    (node + 1) of the first free node. α̂ goes into ``out`` (not kept where ``out``
    is empty) for the links of ``alpha``; returns max|α̂ − α|, the outer loops' step
    size. The solve kernel, the profile kernel, the compiled driver and the judge
    kernel call it."""
    dalpha = prev = 0.0
    keep = out.size > 0
    for i in range(alpha.size):  # (``alpha0``, ``inv`` may be longer: workspace rows)
        node = i + 1 - (fs - 1)
        cur = su[node] - origin[node] if 0 <= node < n else 0.0
        new = alpha0[i] + (cur - prev) * inv[i]
        if keep:
            out[i] = new
        dalpha = max(dalpha, abs(new - alpha[i]))
        prev = cur
    return dalpha


@njit(cache=True)
def energy(alpha, a, jl, jr, k, rest, link_load, sines):
    """The chain's energy E (N·mm) at link angles α: ½ Σ_j k_j (φ_j − φ*_j)² minus the
    loads' work Σ_i P_i ȳ_i, both sums compensated.

    φ_j = α_r − α_l of joint j (``jl[j]``, ``jr[j]``; l = −1 a clamp, α_l = 0), k and
    φ* = ``rest`` per joint, P = ``link_load`` per link at its centre
    ȳ_i = (y_i + y_(i+1)) / 2, the node heights y summed from y_0 = 0 by
    a · ``sines`` (sin α, given: a fit's exact Δy / a, or np.sin α)."""
    s, ls = 0.0, 0.0
    for j in range(jr.size):
        left = alpha[jl[j]] if jl[j] >= 0 else 0.0
        d = (alpha[jr[j]] - left) - rest[j]
        s, ls = add_compensated(s, ls, k[j] * (d * d))
    w, lw, y = 0.0, 0.0, 0.0
    for i in range(alpha.size):  # the node heights y_i, y_(i+1) summed as they go
        y1 = y + a * sines[i]
        w, lw = add_compensated(w, lw, link_load[i] * (0.5 * (y + y1)))
        y = y1
    return 0.5 * (s + ls) - (w + lw)


@njit(cache=True)
def wall_penalty(u, lo, hi, cu, cl, grad):
    """The elastic walls' energy Σ ½ δ_i² / c_i at the free nodes' heights u
    (:func:`lcpbench.model.elastic.penalty`, δ the indentation, c = 1/k the compliance; 0 at a rigid
    wall, c = 0, which u never passes); ``grad``: its gradient added into it, unless
    empty. 0 where no wall yields (``cu`` empty)."""
    if cu.size != u.size:
        return 0.0
    e = 0.0
    for i in range(u.size):
        if cu[i] > 0.0 and u[i] > hi[i]:
            p = (u[i] - hi[i]) / cu[i]
            e += 0.5 * p * (u[i] - hi[i])
            if grad.size:
                grad[i] += p
        if cl[i] > 0.0 and u[i] < lo[i]:
            p = (lo[i] - u[i]) / cl[i]
            e += 0.5 * p * (lo[i] - u[i])
            if grad.size:
                grad[i] -= p
    return e


@njit(cache=True)
def energy_noise(E, stiffness_sum):
    """The round-off an energy comparison allows: ENERGY_NOISE · (|E| + 1e-6 Σ|k|)
    (``stiffness_sum`` = Σ|k|, N·mm/rad)."""
    return ENERGY_NOISE * (abs(E) + stiffness_sum * 1e-6)


@njit(cache=True)
def armijo(t, E_t, E, slope, noise, shortest):
    """One test of Armijo's rule at step length ``t`` along a step of directional
    derivative ``slope`` from energy (or merit) ``E``: returns ``t`` itself where the
    trial's ``E_t`` decreases enough, E_t ≤ E + ARMIJO_DECREASE · t · min(slope, 0) +
    ``noise`` (accept), else t/2 (try again), or 0 where t/2 < ``shortest`` (no
    decrease). E_t = NaN (no chain fits at t) never decreases."""
    if E_t <= E + ARMIJO_DECREASE * t * min(slope, 0.0) + noise:
        return t
    t *= 0.5
    return t if t >= shortest else 0.0


@njit(cache=True)
def energy_search(E, u, su, g_u, d, ut, alpha, trial, sin_t, cos_t, inv, noise, chain, lo,
                  hi, cu, cl):
    """Armijo's search on the exact energy E(α) plus the elastic walls' springs along
    the heights u + t(su − u), from the heights ``u`` at α (energy ``E``, its gradient
    in the heights ``g_u``): t = 1, halved until :func:`armijo` accepts it. ``chain`` =
    (a, jl, jr, k, rest, link_load, fs); ``inv``: 1/(a cos α) of the step's
    linearisation point (the branch of each link, :func:`fit_heights`); ``noise``: the
    round-off allowed (:func:`energy_noise`). Writes ``d`` = su − u, ``ut`` (the last
    heights tried), ``trial`` (α there), ``sin_t``, ``cos_t``. Returns (t, E(t)): t = 0
    where no t >= ARMIJO_SHORTEST decreases the energy."""
    a, jl, jr, k, rest, link_load, fs = chain
    links, n = alpha.size, u.size
    slope = 0.0
    for i in range(n):  # the dot product, a loop (the same sum in every caller)
        d[i] = su[i] - u[i]
        slope += g_u[i] * d[i]
    t = 1.0
    while True:
        for i in range(n):
            ut[i] = u[i] + t * d[i]
        E_t = np.nan
        if fit_heights(trial, ut, alpha, a, fs, links, inv, sin_t, cos_t):
            E_t = energy(trial, a, jl, jr, k, rest, link_load, sin_t) + wall_penalty(
                ut, lo, hi, cu, cl, inv[:0])
        step = armijo(t, E_t, E, slope, noise, ARMIJO_SHORTEST)
        if step == t:
            return t, E_t
        if step == 0.0:
            return 0.0, E_t
        t = step
