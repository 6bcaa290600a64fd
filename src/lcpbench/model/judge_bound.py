"""The result judge's force error bound (check 7 of :mod:`lcpbench.model.judge`), compiled.

Written once in numba and called by the one judge kernel
(:mod:`lcpbench.model.judge_kernel`, its steps in heights or in increments)
from compiled code, and by the large-N driver's contraction estimate from Python
(:func:`lcpbench.model.judge.contraction_estimate`).

The judge takes two exact contact steps of its own: the first at the answer's
final α (reactions R_{k+1}), the second at α₁, where the first step moves the
chain (reactions R_{k+2}). Under linear contraction of the outer iteration by ρ
per step, ‖R_{k+1} − R*‖ ≤ ‖R_{k+2} − R_{k+1}‖ / (1 − ρ), so

* **one step** (the driver's ρ, from its last step sizes and the first judge
  step's, :func:`contraction`): |F_k − F*| ≲ |F_k − F_{k+1}| / (1 − ρ);
* **two steps** (ρ' from the judge's own two steps, :func:`judge_contraction`):
  |F_k − F*| ≤ |F_k − F_{k+1}| + |F_{k+1} − F*| ≲ |F_k − F_{k+1}|
  + |F_{k+1} − F_{k+2}| / (1 − ρ').

Both are estimates under linear contraction, not proofs. The bound is the smaller
of the two (:func:`force_error_bound`), so no answer the one-step bound accepts is
refused; the two-step estimate helps where a back-end's last driver steps make ρ
pessimistic (ρ at its cap 0.99 turns a 1e-9 step into a 1e-7 bound) while the
judge's own steps contract at the rate of the exact outer step. (ρ'/(1 − ρ')
times the second difference bounds |F_{k+2} − F*|, not |F_{k+1} − F*|: it is not
used.) Per node the bound stays the one-step estimate (:func:`force_error_bound`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..thresholds import RHO_MAX, RHO_MIN, STEP_NOISE
from .wall_kernel import lagged_load, walls_at

__all__ = ["contraction", "force_error_bound", "judge_contraction", "profile_rows"]


@njit(cache=True)
def contraction(step_sizes, judge_dalpha):
    """ρ from the last two ratios of step sizes (the driver's, then the first judge
    step's ``judge_dalpha``), the larger of the two, in [RHO_MIN, RHO_MAX]. Sizes at
    the round-off of an angle (below STEP_NOISE rad) are left out: the ratio of two
    rounding errors says nothing about the contraction."""
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
def judge_contraction(first, second):
    """ρ' = (the judge's second step size) / (its first), max|Δα| each, in [RHO_MIN,
    RHO_MAX]. A first step at round-off (below STEP_NOISE rad) gives RHO_MIN if the
    second is at round-off too, else RHO_MAX."""
    if not (np.isfinite(first) and np.isfinite(second)):
        return RHO_MAX
    if first <= STEP_NOISE:
        return RHO_MIN if second <= STEP_NOISE else RHO_MAX
    return min(max(second / first, RHO_MIN), RHO_MAX)


@njit(cache=True)
def force_error_bound(d_up, d_lo, e_up, e_lo, rho, rho2, floor1, floor2, F0, two):
    """``(total, node)``: the force error bound of F (relative to F₀), the smaller of
    the one-step and the two-step estimate, and of the worst node, the one-step
    estimate κ max_i |R_k,i − R_{k+1},i| / F₀.

    The per-node threshold (NODE_GROSS, :mod:`lcpbench.thresholds`) is set against the
    one-step estimate, κ ≥ 2: it refuses 13 % of a node's force moved to its neighbour
    on a converged shape, where both judge steps agree and the two-step estimate
    would say half as much. The success rule is on F; the node bound stays as it was.

    ``d_up``, ``d_lo``: R_k − R_{k+1} per node on the upper and lower wall (the
    answer's reactions minus the first judge step's); ``e_up``, ``e_lo``:
    R_{k+1} − R_{k+2} (the first judge step's minus the second's); ``rho`` the driver's
    contraction (:func:`contraction`), ``rho2`` the judge's (:func:`judge_contraction`);
    ``floor1``, ``floor2``: each judge step's round-off, relative to F₀; ``two``:
    whether the second step settled (else the one-step bound alone).
    """
    kappa = 1.0 / (1.0 - rho)
    s_up = s_lo = d_max = 0.0
    for i in range(d_up.size):
        s_up += d_up[i]
        s_lo += d_lo[i]
        d_max = max(d_max, max(abs(d_up[i]), abs(d_lo[i])))
    total = kappa * max(abs(s_up), abs(s_lo)) / F0 + floor1
    node = kappa * d_max / F0
    if not two:
        return total, node
    kappa2 = 1.0 / (1.0 - rho2)
    t_up = t_lo = 0.0
    for i in range(e_up.size):
        t_up += e_up[i]
        t_lo += e_lo[i]
    total2 = (max(abs(s_up) + kappa2 * abs(t_up), abs(s_lo) + kappa2 * abs(t_lo)) / F0
              + floor1 + floor2)
    return min(total, total2), node


@njit(cache=True)
def profile_rows(alpha, cosines, a, fs, hi, lo, wall, ku, cu_, kl, cl_, forces_upper,
                 forces_lower, nodal_load):
    """A judge step's walls on a wall profile (:mod:`lcpbench.model.wall_kernel`'s
    tables ``ku``, ``cu_``, ``kl``, ``cl_``) at the nodes' x for link angles α:

    ``(hi, lo, nodal_load, g_up, g_lo, h1, l1, h2, l2)``: the flat rows ``hi``, ``lo``
    with the profile's heights where a node has a row, the nodal load plus the slope
    load of the lagged reactions (clipped at 0, as the profile kernel's step), the
    exact gaps at the nodes (``wall`` where a wall has no table), the walls' slopes
    and curvatures at the nodes' x."""
    n = hi.size
    links = alpha.size
    sines, xf, yf = np.sin(alpha), np.empty(n), np.empty(n)
    g_up, g_lo, h1, l1, h2, l2 = (np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                                  np.empty(n), np.empty(n))
    walls_at(sines, cosines[:links], a, fs, np.zeros(n), np.zeros(n), ku, cu_, kl, cl_, xf,
             yf, g_up, g_lo, h1, l1, h2, l2)  # (h(x), l(x) at every node)
    hi, lo, load = hi.copy(), lo.copy(), np.empty(n)
    for i in range(n):
        if ku.size and np.isfinite(hi[i]):
            hi[i] = g_up[i]
        if kl.size and np.isfinite(lo[i]):
            lo[i] = g_lo[i]
        g_up[i] = (g_up[i] if ku.size else wall) - yf[i]  # the exact gaps
        g_lo[i] = yf[i] - (g_lo[i] if kl.size else -wall)
    lagged_load(alpha, cosines[:links], sines, fs, forces_upper, forces_lower, h1, l1, nodal_load,
                yf, xf, load)
    return hi, lo, load, g_up, g_lo, h1, l1, h2, l2
