"""The chain's exact energy and the Armijo rule on it, compiled once for every loop.

Every outer loop of lcpbench searches along its step on the exact (nonlinear) energy
of the chain; this module is the one copy of that energy and of the rule that
accepts or shortens a step:

- :func:`add_compensated` — one step of Neumaier's compensated sum (the energy's
  sums, the node heights of a step's linearisation point and its closure,
  :func:`lcpbench.model.chain.compensated_heights`);
- :func:`energy` — E(α) = ½ Σ k (φ − φ*)² − Σ P ȳ of the chain (eq. 18's joint
  angles, the link loads P at the link centres ȳ), its two sums compensated, since a
  line search compares energies of up to ~10⁵ terms to 1e-12 of their size;
- :func:`armijo` — one test of the sufficient decrease
  E(t) ≤ E + c₁ t min(slope, 0) + noise at step length t, and the next length;
- :func:`energy_noise` — the round-off the test allows.

The kernels (the solve kernel, the compiled driver, large N, the angles' SQP, wall
profiles) call these inside their loops; plain Python calls them through
:func:`lcpbench.numba_cache.kernel_module` (:func:`lcpbench.model.chain.energy`,
:func:`lcpbench.model.outer.armijo`). ``NUMBA_DISABLE_JIT=1`` runs them as Python.
"""

from __future__ import annotations

from numba import njit

from ..thresholds import ARMIJO_DECREASE, ENERGY_NOISE


@njit(cache=True)
def add_compensated(y, lost, term):
    """``(y + term, lost + its rounding error)``: one step of Neumaier's compensated
    sum, the larger operand first (model.chain.compensated_heights)."""
    y1 = y + term
    if abs(y) >= abs(term):
        return y1, lost + ((y - y1) + term)
    return y1, lost + ((term - y1) + y)


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
