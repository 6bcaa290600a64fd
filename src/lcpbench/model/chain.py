"""Exact (nonlinear) geometry, energy and statics of a Hencky bar chain.

Nothing here is linearised: these functions judge a configuration, so the
driver's certificate and line search use them, never the contact step.

Conventions (0-based arrays): link i joins nodes i and i+1 and makes angle
α_i with the x-axis; node 0 sits at the origin. A joint j joins links
``joint_links[j] = (l, r)``; l = −1 is a clamp (a horizontal reference).
The joint sits at node r.
"""

from __future__ import annotations

import numpy as np

from ..problems.scenes import Chain
from .elastic import penalty


def node_positions(chain: Chain, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates x, y (mm) by forward kinematics from the link angles."""
    a = chain.link_length
    x = np.concatenate(([0.0], np.cumsum(a * np.cos(alpha))))
    y = np.concatenate(([0.0], np.cumsum(a * np.sin(alpha))))
    return x, y


def joint_angles(chain: Chain, alpha: np.ndarray) -> np.ndarray:
    """Joint angles φ (rad): α_r − α_l, with α_l = 0 at a clamp (eq. 18)."""
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]
    return alpha[right] - np.where(left >= 0, alpha[np.maximum(left, 0)], 0.0)


def _kernel():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.model.chain_kernel", "energy")


def joint_arrays(chain: Chain) -> tuple:
    """``(jl, jr, k, φ*, P)``: the joints' links, stiffness and rest angle and the link
    loads as the kernels read them (contiguous, kept with the chain)."""
    def make():
        f64 = np.ascontiguousarray
        return (f64(chain.joint_links[:, 0], dtype=np.int64),
                f64(chain.joint_links[:, 1], dtype=np.int64),
                f64(chain.joint_stiffness, dtype=float), f64(chain.rest_joint, dtype=float),
                f64(chain.link_load, dtype=float))

    return chain.derived("_joint_arrays", make)


def energy(chain: Chain, alpha: np.ndarray, walls: bool = True) -> float:
    """Total potential energy E (N·mm): springs ½Σk(φ−φ*)² minus the work of the loads
    (:func:`lcpbench.model.chain_kernel.energy`, its sums compensated).

    Each link load acts at the link centre, whose height is the mean of its
    end-node heights. Elastic walls add their springs' energy Σ ½ k_i δ_i²
    (:func:`lcpbench.model.elastic.penalty`; 0 for rigid walls) unless ``walls`` is
    False (the chain's own energy).
    """
    alpha = np.ascontiguousarray(alpha, dtype=float)
    E = float(_kernel().energy(alpha, float(chain.link_length), *joint_arrays(chain),
                               np.sin(alpha)))
    if walls and chain.elastic_walls:
        E += penalty(chain, heights(chain, alpha))
    return E


def heights(chain: Chain, alpha: np.ndarray) -> np.ndarray:
    """Heights of the free nodes (the unknowns u of the contact step), a plain running
    sum as :func:`node_positions` (the same bits, without the x coordinates); a step's
    linearisation point sums them with compensation
    (:func:`lcpbench.model.chain_kernel.add_compensated`), equal to a few ulps of |y|
    more."""
    y = np.concatenate(([0.0], np.cumsum(chain.link_length * np.sin(alpha))))
    return y[chain.free_nodes]


def alpha_from_heights(
    chain: Chain, u: np.ndarray, reference: np.ndarray
) -> np.ndarray | None:
    """Link angles whose node heights are ``u`` (exact inverse kinematics).

    Each link keeps the branch (sign of cos α) and the 2π-winding of the
    ``reference`` angles, so a link cannot jump across the vertical. Returns
    None when some link would need to be longer than a (|Δy| > a): no chain
    of these links has these heights. numpy's arcsin, not the kernels'
    (:func:`lcpbench.model.chain_kernel.fit_heights`): on AVX-512 machines numpy's
    SIMD arcsin and libm's differ by an ulp on ~8 % of arguments, and the numpy
    path's answers for borderline back-ends (SCS) follow those ulps.
    """
    y = np.zeros(chain.links + 1)
    y[chain.free_nodes] = u
    s = np.diff(y) / chain.link_length
    if not np.all(np.isfinite(s)) or np.any(np.abs(s) >= 1.0):
        return None
    base = np.arcsin(s)
    base = np.where(np.cos(reference) >= 0.0, base, np.pi - base)
    return base + 2 * np.pi * np.round((reference - base) / (2 * np.pi))


def joint_moments(
    chain: Chain, alpha: np.ndarray, nodal_force: np.ndarray
) -> np.ndarray:
    """Sagging bending moment at every joint from statics (N·mm).

    Forces: the link loads at the link centres and ``nodal_force`` (N, +y) at
    the free nodes. For a chain pinned at both ends, the right support
    reaction follows from moments about the left pin (eq. 8); a free end has
    none. The moment at a joint is taken from the forces to its right,
    with lever arms from the exact node positions.
    """
    x, _ = node_positions(chain, alpha)
    xc = 0.5 * (x[:-1] + x[1:])
    n = chain.links
    force = np.zeros(n + 1)
    force[chain.free_nodes] = nodal_force
    pinned_right = chain.free_nodes[-1] < n
    if pinned_right:  # moments about node 0 vanish: fixes the right support reaction
        force[n] = -(chain.link_load @ xc + force @ x) / x[n]
    at = chain.joint_links[:, 1]  # node of each joint
    # Σ_{q>p} F_q (x_q − x_p) and Σ_{i>=p} P_i (xc_i − x_p) via suffix sums.
    f_sum = np.cumsum(force[::-1])[::-1]  # Σ_{q>=p} F_q
    fx_sum = np.cumsum((force * x)[::-1])[::-1]
    p_sum = np.cumsum(chain.link_load[::-1])[::-1]
    px_sum = np.cumsum((chain.link_load * xc)[::-1])[::-1]
    xp = x[at]
    nodes = fx_sum[at] - xp * f_sum[at]  # the force at the joint's own node has no lever arm
    links = px_sum[at] - xp * p_sum[at]
    return nodes + links


def torque_residual(
    chain: Chain, alpha: np.ndarray, nodal_force: np.ndarray
) -> np.ndarray:
    """Spring torque k(φ − φ*) minus the statically required moment, per joint (N·mm)."""
    spring = chain.joint_stiffness * (joint_angles(chain, alpha) - chain.rest_joint)
    return spring - joint_moments(chain, alpha, nodal_force)
