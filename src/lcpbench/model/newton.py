"""The Newton outer step: the exact Hessian of the energy in the node heights.

The paper's contact step (eqs. 20–31) linearises the joint angles in the node
heights, φ̂ = J u + φ₀, and minimises ½ Σ k (φ̂ − φ*)² − fᵀu. That is a
Gauss–Newton step on the exact energy

    E(u) = ½ Σ_j k_j (φ_j(u) − φ*_j)² − fᵀu,   φ_j = α_r(j) − α_l(j),
    α_i = asin((u_{i+1} − u_i) / a)   (each link on its branch),

whose Hessian is Jᵀ diag(k) J (the step's H) plus the curvature the
linearisation drops,

    T = Σ_i μ_i ∇²α_i,   μ_i = Σ_j k_j (φ_j − φ*_j) ∂φ_j/∂α_i,
    ∇²α_i = (sin α_i / (a² cos³ α_i)) e_i e_iᵀ,   e_i = (−1 at node i, +1 at node i+1),

where μ_i is the net spring moment on link i. T is tridiagonal. Adding it to
the step's H makes the step Newton's: quadratic convergence near the
solution, where Gauss–Newton contracts linearly (about two decades per step on
the paper's scenes, 0.7 on very heavy chains).

Far from the solution H + T can be indefinite. The Newton step is then not a
descent direction of a convex model; :func:`newton_step` keeps the
Gauss–Newton step there (H alone), so the globalised driver's line search
and its convergence proof are unchanged.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from numpy.linalg import LinAlgError  # scipy.linalg's LinAlgError is this class

from ..linalg import banded_matvec, cholesky_banded
from ..problems.scenes import Chain
from .chain import joint_angles
from .step import ContactStep


def geometric_bands(chain: Chain, alpha: np.ndarray) -> np.ndarray:
    """T on the free nodes, in the step's lower banded storage (3, n) (N/mm)."""
    a = chain.link_length
    cos = np.cos(alpha)
    curvature = np.sin(alpha) / (a * a * cos**3)  # d²α_i / d(u_{i+1} − u_i)²
    moment = chain.joint_stiffness * (joint_angles(chain, alpha) - chain.rest_joint)
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]
    mu = np.zeros(chain.links)
    np.add.at(mu, right, moment)
    has_left = left >= 0
    np.add.at(mu, left[has_left], -moment[has_left])
    w = mu * curvature
    diag = np.zeros(chain.links + 1)
    diag[:-1] += w
    diag[1:] += w
    free = chain.free_nodes
    n = free.size
    bands = np.zeros((3, n))
    bands[0] = diag[free]
    bands[1, : n - 1] = -w[free[:-1]]  # link free[k] joins nodes free[k] and free[k] + 1
    return bands


def newton_step(step: ContactStep, chain: Chain) -> tuple[ContactStep, bool]:
    """The step with the exact Hessian H + T, and whether it was used.

    The model keeps the exact gradient at the linearisation point u₀: its
    linear term becomes c − T u₀, and :meth:`ContactStep.gradient` adds
    T (u − u₀). Where H + T is not positive definite the Gauss–Newton step is
    returned unchanged (False).
    """
    T = geometric_bands(chain, step.alpha)
    bands = step.bands + T
    try:
        cholesky_banded(bands, lower=True, check_finite=False)
    except (LinAlgError, ValueError):
        return step, False
    linear = step.linear - banded_matvec(T, step.origin)
    return replace(step, bands=bands, linear=linear, geometric=T), True
