"""The result judge's friction checks, compiled (issue 39, docs/friction.md).

Part of the one judge (:mod:`lcpbench.model.judge`, whose :data:`~lcpbench.model.judge.THRESHOLDS`
hold their thresholds; :func:`lcpbench.model.friction_result.friction_verdict` applies
them): the residuals of a frictional answer on the exact geometry. Kept beside
:mod:`lcpbench.model.judge_kernel`, not in it: they run only for frictional answers
(never when μ = 0 and the ends are the paper's), that file stays the frictionless
judge's arithmetic, and both stay under the modules' 600 lines. Loaded through
:func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: entries of :func:`friction_checks`' stats
FRICTION_STATS = ("spring_max", "max_torque_residual", "x_balance", "cone_excess",
                  "slide_deficit", "slide_direction", "stick_slip", "min_gap", "min_normal",
                  "complementarity")


@njit(cache=True)
def friction_checks(alpha, x0, a, jl, jr, k, rest, link_load, free, fy, fx, tangential,
                    normal, limit, gap, slip, pull, right_x_held, right_y_held, eps_f, eps_s,
                    L, F0, left_pull):
    """The frictional answer's residuals on the exact geometry: the torque residual with
    the nodes' vertical fy and horizontal fx forces (N, per free node), the pull P on
    the right end (and ``left_pull`` along x on the left end: a mirrored scene's) and
    the supports' reactions (the right one's vertical from moments
    about node 1 when it holds y, its horizontal when it holds x); the horizontal balance ΣF_x (what no
    support takes); per node, in the wall's frame (``tangential``: T along the wall's
    tangent, ``slip``: the tangential slip, ``limit``: μN), the cone max(|T| − μN), and for nodes that slide
    (|s| > eps_s) the cone deficit μN − |T| and T·sign(s) (<= 0: T opposes the slip);
    the largest |s| of a node inside the cone by more than eps_f; the smallest gap
    (in ℓ), normal force and max min(N/F₀, g/ℓ) over the wall rows."""
    links = alpha.size
    x = np.empty(links + 1)
    y = np.empty(links + 1)
    x[0], y[0] = x0, 0.0
    for i in range(links):
        x[i + 1] = x[i] + a * np.cos(alpha[i])
        y[i + 1] = y[i] + a * np.sin(alpha[i])
    FX = np.zeros(links + 1)
    FY = np.zeros(links + 1)
    for i in range(free.size):
        FX[free[i]] += fx[i]
        FY[free[i]] += fy[i]
    FX[links] += pull
    FX[0] += left_pull
    m0 = 0.0
    for q in range(links + 1):
        m0 += FY[q] * (x[q] - x[0]) - FX[q] * (y[q] - y[0])
    for i in range(links):
        m0 += link_load[i] * (0.5 * (x[i] + x[i + 1]) - x[0])
    if right_y_held:  # (a free right end has no reaction)
        FY[links] -= m0 / (x[links] - x[0])
    sx = 0.0
    for q in range(links + 1):
        sx += FX[q]
    if right_x_held:
        FX[links] -= sx
    # suffix sums Σ_{q>=p} of FY, FY x, FX, FX y and of the link loads
    fy_s = fyx_s = fx_s = fxy_s = p_s = px_s = 0.0
    spring_max = worst = 0.0
    out = np.zeros(len(FRICTION_STATS))
    j = jr.size - 1
    for p in range(links, -1, -1):
        fy_s += FY[p]
        fyx_s += FY[p] * x[p]
        fx_s += FX[p]
        fxy_s += FX[p] * y[p]
        if p < links:
            p_s += link_load[p]
            px_s += link_load[p] * 0.5 * (x[p] + x[p + 1])
        while j >= 0 and jr[j] == p:
            moment = (fyx_s - x[p] * fy_s) - (fxy_s - y[p] * fx_s) + (px_s - x[p] * p_s)
            phi = alpha[jr[j]] - (alpha[jl[j]] if jl[j] >= 0 else 0.0)
            spring = k[j] * (phi - rest[j])
            spring_max = max(spring_max, abs(spring))
            worst = max(worst, abs(spring - moment))
            j -= 1
    out[0], out[1], out[2] = spring_max, worst, sx
    cone = deficit = direction = stick = 0.0
    for i in range(fx.size):
        T = tangential[i]
        cone = max(cone, abs(T) - limit[i])
        if abs(slip[i]) > eps_s:
            deficit = max(deficit, limit[i] - abs(T))
            direction = max(direction, T if slip[i] > 0 else -T)
        if limit[i] - abs(T) > eps_f:
            stick = max(stick, abs(slip[i]))
    out[3], out[4], out[5], out[6] = cone, deficit, direction, stick
    gmin, nmin, comp = np.inf, np.inf, 0.0
    for r in range(gap.size):
        gmin = min(gmin, gap[r] / L)
        nmin = min(nmin, normal[r])
        comp = max(comp, min(normal[r] / F0, gap[r] / L))
    out[7], out[8], out[9] = gmin, nmin, comp
    return out
