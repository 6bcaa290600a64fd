"""Walls of any profile in the compiled solve: the outer loop's merit, start and stop.

The scheme (:mod:`lcpbench.model.profile`): each contact step the paper's banded box
QP, its bounds the wall heights h(x_k) at the nodes' current x, the slope of the wall
entering the load through the last step's reactions μ̄, ν̄ as the nodal load
s = J_xᵀ(μ̄ h'(x) − ν̄ l'(x)) (:func:`lcpbench.model.wall_kernel.lagged_load`). The
outer loop is the flat walls' (:func:`lcpbench.model.compiled_kernel.outer_loop`, its
entry :func:`~lcpbench.model.compiled_kernel.solve_profile_chain`); what a profile
changes in it is here:

- the start: the heights clipped to the walls at the nodes' x (:func:`clipped_start`);
- the Armijo search on the merit (:func:`merit_search`)

      P(u) = E(u) − Σ μ̄_k h(x_k(u)) + Σ ν̄_k l(x_k(u)) + σ Σ (penetration of the walls)

  σ = PENALTY × the largest reaction, a full step near the answer where the merit
  would cut it below LOCAL_CUT;
- the stop at max|Δα| < tol with every node on its side of the exact walls to
  GEOMETRY_SLACK ℓ (:func:`penetration`).

The compiled driver around any other back-end and scheme
(:mod:`lcpbench.model.compiled_driver`, through :mod:`lcpbench.model.driver_kernel`)
and the large-N driver call the same functions.

A wall is a table of cubic pieces (:mod:`lcpbench.problems.profile_table`):
breakpoints ``knots`` and coefficients ``coef`` (4 × pieces, scipy's PPoly
layout), continued flat outside; an empty table is a flat wall whose rows
(``hi_rows``, ``lo_rows``) stand as they are. Rigid walls only (a profile and
an elastic wall do not combine, :class:`lcpbench.problems.scenes.ActuatorScene`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..thresholds import (
    ARMIJO_SHORTEST,
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
)
from .wall_kernel import walls_at

__all__ = ["clipped_start", "merit_at", "merit_parts", "merit_search", "penetration"]


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
