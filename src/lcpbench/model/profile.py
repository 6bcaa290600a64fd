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
(any back-end, :mod:`lcpbench.model.compiled_driver`), the profile kernel
(:func:`lcpbench.model.compiled_kernel.solve_profile_chain`, the default back-end) and the large-N driver
(:mod:`lcpbench.model.large_driver`), all on the walls' tables
(:mod:`lcpbench.model.wall_kernel`). This module hands a chain's walls to those
compiled functions for the Python callers (the result, the judge, the large-N driver):
the walls at the nodes' x (:func:`walls_at`, :func:`wall_rows`), the slope load
(:func:`slope_load`), the exact gaps (:func:`profile_gaps`) and the horizontal parts
of the reactions; only the joint moments with horizontal forces
(:func:`joint_moments_xy`, for the report) are numpy, having no compiled twin.

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

_FLAT = (np.zeros(0), np.zeros((4, 0)))  # a wall with no table (never written)


def wall_tables(chain: Chain) -> tuple | None:
    """The walls as the compiled kernels read them: (upper breakpoints, upper
    coefficients, lower breakpoints, lower coefficients), a table of cubic pieces over
    the chain's reach x in [−ℓ, ℓ] (:meth:`lcpbench.problems.walls.WallProfile.pieces`;
    empty: a flat wall); None where a profile has no table. Kept with the chain."""
    return chain.derived("_wall_tables", lambda: _wall_tables(chain))


def _wall_tables(chain: Chain) -> tuple | None:
    reach = (-float(chain.length), float(chain.length))  # no node is further from the pin
    tables = []
    for profile in (chain.upper_profile, chain.lower_profile):
        table = _FLAT if profile is None else profile.pieces(*reach)
        if table is None:
            return None
        tables.extend(table)
    return tuple(tables)


def _kernel():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.model.wall_kernel", "walls_at")


def wall_rows(chain: Chain, alpha: np.ndarray, *, every_node: bool = False) -> tuple:
    """:func:`lcpbench.model.wall_kernel.walls_at` of ``chain`` at α: the free nodes'
    (x, y, upper, lower, h', l', h'', l''), the walls at the nodes' x where a node has
    a row (±inf elsewhere; the chain's flat row where a wall has no table), their
    slopes and curvatures (0: flat). ``every_node``: the profiles at every free node."""
    tables = wall_tables(chain)
    if tables is None:
        raise ValueError("a wall profile with no table of cubic pieces over the chain's reach")
    alpha = np.ascontiguousarray(alpha, dtype=float)
    n = chain.free_nodes.size
    f64 = np.ascontiguousarray
    rows = ((np.zeros(n), np.zeros(n)) if every_node else
            (f64(chain.upper, dtype=float), f64(chain.lower, dtype=float)))
    out = tuple(np.empty(n) for _ in range(8))
    _kernel().walls_at(np.sin(alpha), np.cos(alpha), float(chain.link_length),
                       int(chain.free_nodes[0]) + 1, *rows, *tables, *out)
    return out


def split_reactions(chain: Chain, net: np.ndarray, u: np.ndarray):
    """(upper, lower) wall reactions (N) from the net reactions ``net`` (+ pushes down) of
    the free nodes at heights ``u``: :func:`lcpbench.model.wall_kernel.split_by_wall` on
    the chain's wall rows (one wall: all of it the upper wall's, a negative value that wall
    pulling; a channel: each node's to the nearer wall, its sign kept)."""
    net = np.ascontiguousarray(net, dtype=float)
    upper, lower = np.empty(net.size), np.empty(net.size)
    f64 = np.ascontiguousarray
    _kernel().split_by_wall(net, f64(u, dtype=float), f64(chain.upper, dtype=float),
                            f64(chain.lower, dtype=float), bool(chain.channel), upper, lower)
    return upper, lower


def walls_at(chain: Chain, alpha: np.ndarray) -> Chain:
    """``chain`` with its wall rows at the profile heights of the nodes' x at α
    (:func:`wall_rows`). Rows stay where they are (a node with no row keeps ±inf); a
    chain without a profile is returned as it is."""
    if not chain.profiled_walls:
        return chain
    rows = wall_rows(chain, alpha)
    return replace(chain, upper=rows[2], lower=rows[3])


def slope_load(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
               forces_lower: np.ndarray, rows: tuple | None = None) -> np.ndarray:
    """s = J_xᵀ(μ̄ ⊙ h'(x) − ν̄ ⊙ l'(x)) (N): the generalised force, on the node
    heights, of the horizontal parts of the wall reactions μ̄ (upper), ν̄ (lower), as
    given (not clipped); :func:`lcpbench.model.wall_kernel.slope_load`. ``rows``: the
    chain's :func:`wall_rows` at α, where the caller has them."""
    x, y, _, _, h1, l1, _, _ = wall_rows(chain, alpha) if rows is None else rows
    alpha = np.ascontiguousarray(alpha, dtype=float)
    w = np.asarray(forces_upper, float) * h1 - np.asarray(forces_lower, float) * l1
    out = np.empty(w.size)
    _kernel().slope_load(alpha, np.cos(alpha), np.sin(alpha), int(chain.free_nodes[0]) + 1,
                         np.ascontiguousarray(w), out)
    return out


def profile_gaps(chain: Chain, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Exact gaps of the free nodes: h(x_k) − y_k, and y_k − l(x_k) in a channel (mm).

    Every free node gets a gap (the profile is continued flat outside its
    table), as the flat model's ``wall − y``.
    """
    _, y, h, low, _, _, _, _ = wall_rows(chain, alpha, every_node=True)
    up = (h if chain.upper_profile is not None else chain.wall) - y
    lo = None
    if chain.channel:
        lo = y - (low if chain.lower_profile is not None else -chain.wall)
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
    _, _, _, _, h1, l1, _, _ = wall_rows(chain, alpha)
    return upper * h1 - lower * l1, lower - upper
