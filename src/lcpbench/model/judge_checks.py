"""The result judge's certificate and checks of an answer, compiled (checks 3-6 and 8 of
:mod:`lcpbench.model.judge`).

The exact geometry of the chain at the answer's link angles α (forward kinematics,
the heights summed with compensation), the certificate
(:class:`lcpbench.model.judge.Certificate`: the smallest gap and reaction, the
complementarity, the right pin's closure and the joint torques' balance, with the
walls' normal reactions on a wall profile), the sign, complementarity and
penetration checks and the second-order check
(:mod:`lcpbench.model.stability_kernel`), written once: the judge kernel
(:mod:`lcpbench.model.judge_kernel`, its exact steps in node heights or in
increments) calls :func:`certify_checks` after its first step.
Also the layout of the judge's work array (one allocation per call, :data:`ROWS`)
and the names of the numbers it returns (:data:`STATS`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..thresholds import (  # the rule's numbers, as model.judge reads them
    FORCE_TOL_CAP,
    FORCE_TOL_PER_RAD,
    GEOMETRY_TOL,
    NODE_FACTOR,
    NODE_GROSS,
    NODE_SHARE,
)
from .chain_kernel import add_compensated  # once (numba_cache)
from .stability_kernel import CHECKED, unstable_directions_at

#: names of the entries of the ``stats`` array that :func:`judge_answer` returns
STATS = ("tau", "F0", "eps_R", "comp", "comp_allowed", "min_gap", "min_force",
         "complementarity", "closure", "max_torque_residual", "relative_torque_residual",
         "floor_R", "R_min", "total", "node", "node_allowed", "rho", "judge_total_force",
         "rounds", "pen", "closure_allowed", "unstable", "judge_rho")
SETTLED, NOT_SETTLED = 0, 1


# rows of the judge's work array: one allocation per call, each row links + 2 long
# (a node's or link's entries from column 0; the step's accumulators in shifted
# node index, node + 1). The certificate's suffix sums reuse the step's rows, which
# are spent by then.
(X, Y, COS, INV, V, ALPHA0, DIAG, OFF1, OFF2, LIN, C0, C1, C2, PHI0, ORIGIN, LINEAR, U, NET,
 SCALE, ROUNDOFF, NOISE, RHS, HY, HG, HGA, JU, JLO, SIZE, YC, HX, AC, AS) = range(32)
ROWS = 32
FORCE, F_SUM, FX_SUM, P_SUM, PX_SUM, H_SUM, HY_SUM = DIAG, OFF1, OFF2, LIN, HY, C0, C1
# a node's place in the judge step's contact set
FREE, UP, LO = 0, 1, 2


# -- the chain's exact geometry (model.chain) ------------------------------------------
@njit(cache=True)
def without_noise(forces_upper, forces_lower, noise, settled):
    """Copies of the reactions R on the upper and lower walls (N) with the values within
    their round-off ``noise`` set to zero (not reactions), where the judge step
    ``settled``; else the reactions as given."""
    fu, fl = forces_upper.copy(), forces_lower.copy()
    if settled:
        for i in range(fu.size):
            if abs(fu[i]) <= noise[i]:
                fu[i] = 0.0
            if abs(fl[i]) <= noise[i]:
                fl[i] = 0.0
    return fu, fl


@njit(cache=True)
def positions(alpha, a, w):
    """Node positions x, y (rows X, Y, as model.chain.node_positions), cos α (row COS),
    tan α − α (row V), the heights summed with compensation (row YC, the judge
    step's linearisation point and closure, as model.step) and the links' a cos α,
    a sin α (rows AC, AS: the second-order check's)."""
    x, y, cs, v, yc, ac, as_ = w[X], w[Y], w[COS], w[V], w[YC], w[AC], w[AS]
    x[0] = y[0] = yc[0] = 0.0
    sx = sy = lost = 0.0
    for i in range(alpha.size):
        c, s = np.cos(alpha[i]), np.sin(alpha[i])
        cs[i] = c
        v[i] = s / c - alpha[i]  # tan α − α, on the cos and sin at hand
        ac[i], as_[i] = a * c, a * s
        sx += ac[i]
        sy, lost = add_compensated(sy, lost, as_[i])
        x[i + 1], y[i + 1], yc[i + 1] = sx, sy, sy + lost


@njit(cache=True)
def _torque_residual(alpha, w, jl, jr, k, rest, link_load, fs, fu, fl, h1, l1, pinned_right,
                     res):
    """chain.torque_residual of the net reactions fl − fu into ``res``: k(φ − φ*) minus
    the moment statics demands at each joint; returns the largest spring torque. On a
    wall of slope h', l' (empty: flat) the reactions are normal to it, with horizontal
    parts fu h' − fl l' (model.profile.joint_moments_xy)."""
    links, x, y = alpha.size, w[X], w[Y]
    force, hx = w[FORCE], w[HX]
    for i in range(links + 1):
        force[i] = hx[i] = 0.0
    for i in range(fu.size):
        force[fs - 1 + i] = fl[i] - fu[i]
        if h1.size:
            hx[fs - 1 + i] = fu[i] * h1[i] - fl[i] * l1[i]
    if pinned_right:
        m = 0.0
        for i in range(links):
            m += link_load[i] * (0.5 * (x[i] + x[i + 1]))
        fx = 0.0
        for i in range(links + 1):
            fx += force[i] * x[i] - hx[i] * y[i]
        force[links] = -(m + fx) / x[links]
    f_sum, fx_sum, p_sum, px_sum = w[F_SUM], w[FX_SUM], w[P_SUM], w[PX_SUM]  # Σ_{q>=p}
    f_sum[links + 1] = fx_sum[links + 1] = 0.0
    p_sum[links] = px_sum[links] = 0.0
    for p in range(links, -1, -1):
        f_sum[p] = f_sum[p + 1] + force[p]
        fx_sum[p] = fx_sum[p + 1] + force[p] * x[p]
    for p in range(links - 1, -1, -1):
        p_sum[p] = p_sum[p + 1] + link_load[p]
        px_sum[p] = px_sum[p + 1] + link_load[p] * (0.5 * (x[p] + x[p + 1]))
    h_sum, hy_sum = w[H_SUM], w[HY_SUM]  # the horizontal parts: −Σ_{q>=p} F_x,q (y_q − y_p)
    if h1.size:
        h_sum[links + 1] = hy_sum[links + 1] = 0.0
        for p in range(links, -1, -1):
            h_sum[p] = h_sum[p + 1] + hx[p]
            hy_sum[p] = hy_sum[p + 1] + hx[p] * y[p]
    spring_max = 0.0
    for j in range(jr.size):
        at = jr[j]
        xp = x[at]
        moment = (fx_sum[at] - xp * f_sum[at]) + (px_sum[at] - xp * p_sum[at])
        if h1.size:
            moment += y[at] * h_sum[at] - hy_sum[at]
        phi = alpha[jr[j]] - (alpha[jl[j]] if jl[j] >= 0 else 0.0)
        spring = k[j] * (phi - rest[j])
        res[j] = spring - moment
        spring_max = max(spring_max, k[j] * abs(phi - rest[j]))
    return spring_max


@njit(cache=True)
def units(forces_upper, forces_lower, F, tol):
    """(τ, F₀, ε_R) of an answer: τ = min(FORCE_TOL_CAP, FORCE_TOL_PER_RAD tol)
    (model.judge.force_tol), F₀ = max(|F_upper|, |F_lower|, EI/ℓ²), ε_R = NODE_SHARE τ F₀;
    F₀ is NaN where a reaction is not finite, so the force error bounds fail."""
    tau = min(FORCE_TOL_CAP, FORCE_TOL_PER_RAD * tol)
    F_up = F_lo = 0.0
    for i in range(forces_upper.size):
        F_up += forces_upper[i]
        F_lo += forces_lower[i]
    F0 = max(max(abs(F_up), abs(F_lo)), F)
    if not (np.isfinite(F_up) and np.isfinite(F_lo)):
        F0 = np.nan  # (max drops a NaN that is not first: a NaN reaction fails the bounds)
    return tau, F0, NODE_SHARE * tau * F0


@njit(cache=True)
def certify_checks(alpha, a, jl, jr, k, rest, link_load, fs, lo, hi, L, F, cu, cl, wall,
                   channel, has_gap, profiled, g_up, g_lo, h1, l1, h2, l2, fu, fl, w, floor_R,
                   tau, F0, eps_R, stats):
    """The certificate (exact geometry: rows X, Y of ``w``, :func:`positions`) and checks
    3-6 and 8 of model.judge on the reactions ``fu``, ``fl`` (round-off set to zero)
    into ``stats``; returns the torque residual per joint. ``floor_R``: the round-off of
    a reaction R = K g + z, FLOOR_ULPS ε S (0: the judge step did not settle); ``lo``,
    ``hi`` (the walls' rows at the nodes' x), ``g_up``, ``g_lo``, ``h1``.. (a wall
    profile's exact gaps, slopes and curvatures; empty: flat) as
    :func:`lcpbench.model.judge_bound.profile_rows` gives them. Rows FORCE to HY_SUM of
    ``w`` are overwritten."""
    n, links, nj = lo.size, alpha.size, jr.size
    y = w[Y]
    min_gap, min_force, cmp = np.inf, 0.0, 0.0
    comp = 0.0  # complementarity and sign on the answer's heights
    R_min = 0.0
    soft = cu.size == n
    for i in range(n):
        yf = y[fs - 1 + i]
        # an elastic wall's gap is the compliant one, g + R/k (the node indents by R/k)
        iu = cu[i] * max(fu[i], 0.0) if soft else 0.0
        il = cl[i] * max(fl[i], 0.0) if soft else 0.0
        min_force = min(min_force, fu[i])
        gap_up = g_up[i] if profiled else wall - yf
        gap_lo = g_lo[i] if profiled else yf + wall
        if has_gap:
            min_gap = min(min_gap, gap_up + iu)
            cmp = max(cmp, abs((gap_up + iu) * fu[i]))
        if channel:
            min_force = min(min_force, fl[i])
            min_gap = min(min_gap, gap_lo + il)
            cmp = max(cmp, abs((gap_lo + il) * fl[i]))
        comp = max(comp, min(fu[i] / F0, (hi[i] - yf + iu) / L))
        comp = max(comp, min(fl[i] / F0, (yf - lo[i] + il) / L))
        R_min = min(R_min, min(fu[i], fl[i]))
    pinned_right = fs - 1 + n - 1 < links
    closure = abs(y[links]) if pinned_right else 0.0
    res = np.empty(nj)
    spring_max = _torque_residual(alpha, w, jl, jr, k, rest, link_load, fs, fu, fl, h1, l1,
                                  pinned_right, res)
    worst_t = 0.0
    for j in range(nj):
        worst_t = max(worst_t, abs(res[j]))
    rel_t = worst_t / max(spring_max, F * L)
    stats[0], stats[1], stats[2], stats[3] = tau, F0, eps_R, comp
    stats[4] = max(NODE_SHARE * tau, floor_R / F0)
    stats[5], stats[6], stats[7], stats[8] = min_gap, min_force, cmp, closure
    stats[9], stats[10], stats[11], stats[12] = worst_t, rel_t, floor_R, R_min
    c_max = 0.0  # model.judge.penetration_allowed: + ε_R / k at an elastic wall
    for i in range(cu.size):
        c_max = max(c_max, max(cu[i], cl[i]))
    stats[19] = min(GEOMETRY_TOL, NODE_SHARE * tau) * L + eps_R * c_max
    stats[20] = GEOMETRY_TOL * L
    # per node, the force error bound is certified down to the round-off of R = K g + z
    stats[15] = max(max(NODE_FACTOR * tau, NODE_GROSS), NODE_FACTOR * floor_R / F0)
    # the second-order check (model.stability_kernel): the walls' springs (rigid: inf), and
    # their slopes and curvatures at the nodes' x (flat: 0)
    k_up, k_lo, flat = np.full(n, np.inf), np.full(n, np.inf), np.zeros(n)
    if soft:
        for i in range(n):
            k_up[i] = 1.0 / cu[i] if cu[i] > 0.0 else np.inf
            k_lo[i] = 1.0 / cl[i] if cl[i] > 0.0 else np.inf
    if not profiled:
        h1 = l1 = h2 = l2 = flat
    code, unstable, _ = unstable_directions_at(alpha, w[AC, :links], w[AS, :links], jl, jr,
                                               k, rest, link_load, fs - 1, fu, fl, k_up,
                                               k_lo, h1, l1, h2, l2, eps_R, pinned_right)
    stats[21] = unstable if code == CHECKED else 0.0
    return res
