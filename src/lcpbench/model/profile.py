"""Walls of any profile y = h(x) in the contact step (issue 17, item 3).

The gap of a free node k to an upper wall of profile h is g_k = h(x_k) − y_k,
and x_k moves with the configuration: x_k = Σ_{j<k} a cos α_j. In the node
heights u (the unknowns of the contact step), with α_j = asin(Δy_j / a),

    dx_k = −Σ_{j<k} tan α_j (du_{j+1} − du_j),

a cumulative sum: the Jacobian J_x of x in u is lower triangular and dense
(semiseparable), not banded. The exact problem is

    minimise E(u)  subject to  h(x_k(u)) − u_k ≥ 0,   u_k − l(x_k(u)) ≥ 0,

and its KKT conditions (μ, ν ≥ 0, complementary to the gaps) are

    ∇E(u) + μ − ν = J_xᵀ (μ ⊙ h'(x) − ν ⊙ l'(x)).                 (P)

μ_k is the vertical component of the wall's force on node k; the force is
normal to the wall, μ_k (h'(x_k), −1) for the upper wall, and its horizontal
part is carried to the fixed left pin (the right pin slides along x).

**The formulation (option b of the issue: lagged multipliers).** Each contact
step stays the paper's banded box QP (H pentadiagonal, every back-end runs
it). At a configuration α with the last step's multipliers μ̄, ν̄ it is the
Gauss–Newton step of the merit function

    Φ(u) = E(u) − Σ_k μ̄_k h(x_k(u)) + Σ_k ν̄_k l(x_k(u))

on the box  l(x_k(α)) <= u_k <= h(x_k(α))  (the walls at the nodes' current
x): the box's bounds are the profile at the current x, and the slope enters
as an extra nodal load s = J_xᵀ(μ̄ ⊙ h' − ν̄ ⊙ l') in the linear term (the
work of the horizontal part of the lagged reactions). s costs O(N): one
suffix sum (:func:`slope_load`). At a fixed point (α and the multipliers
unchanged) the box QP's KKT conditions are exactly (P). The iteration is a
fixed point in (u, μ): it contracts like the flat-wall Gauss–Newton step
when |h' tan α| is small (the coupling the lag drops), more slowly on steep
walls; the drivers line-search Φ, and the judge checks (P) on the exact
geometry, so a slow or stalled iteration is a status, never a wrong answer.

The step is assembled once, compiled: :func:`lcpbench.model.driver_kernel.profile_assemble`
(any back-end, :mod:`lcpbench.model.compiled_driver`) and the profile kernel
(:mod:`lcpbench.model.profile_kernel`, the default back-end), both on the walls' tables
(:mod:`lcpbench.model.wall_kernel`). This module keeps the geometry in numpy that the
result, the judge and the large-N driver read: the walls at the nodes' x, the exact
gaps, J_xᵀ and the moments with horizontal forces.

Option (a), the exact linearised row h_k + h'_k J_x du − du_k ≥ 0, would
make the constraint matrix I − diag(h') J_x dense: an O(N²) LCP
(M = A H⁻¹ Aᵀ) for the dense back-ends, and a general (not box) QP for the
others. See docs/profile.md.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..problems.scenes import Chain
from .chain import node_positions


def has_profile(chain: Chain) -> bool:
    """Whether a wall of ``chain`` has a profile h(x) (not the flat rows)."""
    return chain.profiled_walls


def node_x(chain: Chain, alpha: np.ndarray) -> np.ndarray:
    """x of the free nodes (mm)."""
    return node_positions(chain, alpha)[0][chain.free_nodes]


def walls_at(chain: Chain, alpha: np.ndarray) -> Chain:
    """``chain`` with its wall rows at the profile heights of the nodes' x at α.

    Rows stay where they are (a node with no row keeps ±inf); a chain
    without a profile is returned as it is.
    """
    if not has_profile(chain):
        return chain
    x = node_x(chain, alpha)
    upper, lower = chain.upper, chain.lower
    if chain.upper_profile is not None:
        upper = np.where(np.isfinite(chain.upper), chain.upper_profile(x), np.inf)
    if chain.lower_profile is not None:
        lower = np.where(np.isfinite(chain.lower), chain.lower_profile(x), -np.inf)
    return replace(chain, upper=upper, lower=lower)


def slopes(chain: Chain, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """h'(x_k) and l'(x_k) at the free nodes (0 where a wall has no profile)."""
    x = node_x(chain, alpha)
    up = chain.upper_profile.slope(x) if chain.upper_profile is not None else np.zeros_like(x)
    lo = chain.lower_profile.slope(x) if chain.lower_profile is not None else np.zeros_like(x)
    return up, lo


def x_jacobian_t(chain: Chain, alpha: np.ndarray, w: np.ndarray) -> np.ndarray:
    """J_xᵀ w in O(N): Σ_k w_k ∂x_k/∂u on the free nodes (w per free node).

    With W_j = Σ_{k>j} w_k (a suffix sum) and p_j = −tan α_j W_j per link j,
    the entry of node m is p_{m−1} − p_m.
    """
    n = chain.links
    wn = np.zeros(n + 1)
    wn[chain.free_nodes] = w
    suffix = np.cumsum(wn[::-1])[::-1]  # Σ_{k>=j}
    W = suffix[1:]  # link j: Σ_{k>=j+1}
    p = -np.tan(alpha) * W
    g = np.zeros(n + 1)
    g[1:] += p
    g[:-1] -= p
    return g[chain.free_nodes]


def slope_load(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
               forces_lower: np.ndarray) -> np.ndarray:
    """s = J_xᵀ(μ̄ ⊙ h'(x) − ν̄ ⊙ l'(x)) (N): the generalised force, on the node
    heights, of the horizontal parts of the wall reactions μ̄ (upper), ν̄ (lower)."""
    h1, l1 = slopes(chain, alpha)
    return x_jacobian_t(chain, alpha, forces_upper * h1 - forces_lower * l1)


def profile_gaps(chain: Chain, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Exact gaps of the free nodes: h(x_k) − y_k, and y_k − l(x_k) in a channel (mm).

    Every free node gets a gap (the profile is continued flat outside its
    table), as the flat model's ``wall − y``.
    """
    x, y = node_positions(chain, alpha)
    xf, yf = x[chain.free_nodes], y[chain.free_nodes]
    up = chain.upper_profile(xf) - yf if chain.upper_profile is not None else \
        chain.wall - yf
    lo = None
    if chain.channel:
        lo = yf - chain.lower_profile(xf) if chain.lower_profile is not None else \
            yf + chain.wall
    return up, lo


def joint_moments_xy(chain: Chain, alpha: np.ndarray, force_x: np.ndarray,
                     force_y: np.ndarray) -> np.ndarray:
    """Sagging bending moment at every joint (N·mm) with nodal forces (F_x, F_y)
    on the free nodes: Σ_{q>p} [F_y,q (x_q − x_p) − F_x,q (y_q − y_p)] plus the
    link loads. The right pin takes a vertical force only (it slides along x),
    fixed by moments about the left pin; the left pin takes the rest.
    :func:`lcpbench.model.chain.joint_moments` is the case F_x = 0.
    """
    x, y = node_positions(chain, alpha)
    xc = 0.5 * (x[:-1] + x[1:])
    n = chain.links
    fy = np.zeros(n + 1)
    fx = np.zeros(n + 1)
    fy[chain.free_nodes] = force_y
    fx[chain.free_nodes] = force_x
    if chain.free_nodes[-1] < n:  # pinned right end: moments about node 0 vanish
        fy[n] = -(chain.link_load @ xc + fy @ x - fx @ y) / x[n]

    def suffix(v):
        return np.cumsum(v[::-1])[::-1]

    at = chain.joint_links[:, 1]
    xp, yp = x[at], y[at]
    nodes = (suffix(fy * x)[at] - xp * suffix(fy)[at]
             - suffix(fx * y)[at] + yp * suffix(fx)[at])
    p = chain.link_load
    links = suffix(p * xc)[at] - xp * suffix(p)[at]
    return nodes + links


def wall_forces_xy(chain: Chain, alpha: np.ndarray, upper: np.ndarray,
                   lower: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F_x, F_y) on the free nodes of the normal wall reactions: μ (h', −1) from the
    upper wall and ν (−l', 1) from the lower (μ, ν: their vertical parts, N)."""
    h1, l1 = slopes(chain, alpha)
    return upper * h1 - lower * l1, lower - upper
