"""The paper-faithful dense assembly of the contact step, eqs. (3)–(31).

Kept as the reference that the banded, energy-based assembly
(:mod:`lcpbench.model.step`) is tested against, and as the "dense path" of the
benchmarks. It follows the printed equations symbol by symbol, for the
actuator scene (pinned–pinned, all interior nodes as contact rows), with the
two misprints found in them corrected (see ``docs/errata.md``):

* eq. (13): γ carries a stray factor a/2 (and "m" for μ). As printed, τ = (a/2)γ
  would have units N·mm²; the statics of the chain give γ = μ (s − …).
  ``printed_gamma=True`` restores the printed form.
* eqs. (25)–(27): the 1/a multiplies v as well as M û; v (eq. 24) is already an
  angle. Eq. (31) is consistent with the corrected form, which is used.

Cost: O(N²) to build and O(N³) for A⁻¹ — this is the slow path on purpose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class PaperStep:
    """K, z (eqs. 30, 31) and the intermediate matrices of the paper's step."""

    K: np.ndarray
    z: np.ndarray
    A: np.ndarray
    L: np.ndarray
    M: np.ndarray
    gamma: np.ndarray


def paper_step(
    alpha: np.ndarray,
    *,
    EI: float,
    length: float,
    weight: float,
    height: float,
    rest_joint: np.ndarray,
    printed_gamma: bool = False,
) -> PaperStep:
    """Assemble the paper's LCP data at link angles ``alpha`` (rad).

    Parameters
    ----------
    alpha : (N,) link angles α of the current configuration.
    EI, length, weight, height : scene parameters (N·mm², mm, N/mm, mm).
    rest_joint : (N−1,) unconstrained joint angles φ̄*.
    printed_gamma : use eq. (13) exactly as printed (dimensionally wrong).
    """
    alpha = np.asarray(alpha, dtype=float)
    N = alpha.size
    a = length / N  # (12)
    mu = weight * length / N  # (5)
    cos = np.cos(alpha)
    d = cos.sum()  # (4)
    idx = np.arange(1, N)  # i = 1..N−1
    b1 = d / 2 + np.sum(idx * cos[1:])  # (6): Σ i cos α_{i+1}
    bn = d / 2 + np.sum((N - idx) * cos[:-1])  # (9): Σ (N−i) cos α_i
    csum = np.concatenate(([0.0], np.cumsum(cos)))  # csum[k] = Σ_{j<=k} cos α_j
    c1 = csum[N] - csum[idx]  # (7): Σ_{j=i+1}^{N} cos α_j
    cn = csum[idx]  # (10): Σ_{j=1}^{i} cos α_j
    # (14): s(i) = d/2 + Σ_{j=1}^{N−2} ζ_j cos α_{j+1}, ζ_j = j if i > j else N − j − 1
    j = np.arange(1, N - 1)
    zeta = np.where(idx[:, None] > j[None, :], j[None, :], N - j[None, :] - 1)
    s = d / 2 + zeta @ cos[1 : N - 1]
    gamma = mu * (s - (b1 * cn + bn * c1) / d)  # (13), corrected
    if printed_gamma:
        gamma = (a / 2) * gamma
    # (16): B(i, k) = Σ_{m=min(i,k)+1}^{max(i,k)} cos α_m, zero diagonal
    lo = np.minimum(idx[:, None], idx[None, :])
    hi = np.maximum(idx[:, None], idx[None, :])
    B = csum[hi] - csum[lo]
    A = B - (np.outer(cn, c1) + np.outer(c1, cn)) / d  # (15)
    L = np.zeros((N - 1, N))  # (19)
    L[idx - 1, idx - 1] = -1.0
    L[idx - 1, idx] = 1.0
    M = np.zeros((N, N - 1))  # (22)
    M[idx - 1, idx - 1] = 1.0 / cos[:-1]
    M[idx, idx - 1] = -1.0 / cos[1:]
    v = np.tan(alpha) - alpha  # (24)
    Ainv = np.linalg.inv(A)
    K = (2 * EI / a**3) * Ainv @ L @ M  # (30)
    hbar = np.full(N - 1, height)
    z = -K @ hbar + (2 * EI / a**2) * Ainv @ (L @ v + rest_joint) - Ainv @ gamma  # (31)
    return PaperStep(K=K, z=z, A=A, L=L, M=M, gamma=gamma)


def paper_predict_alpha(step: PaperStep, u: np.ndarray, alpha: np.ndarray, a: float) -> np.ndarray:
    """α̂ from eq. (21): (1/a) M û − v."""
    return step.M @ u / a - (np.tan(alpha) - alpha)


def solve_paper_dense(scene, *, tol: float = 1e-3, max_outer: int = 200):
    """The paper's whole method, literally: dense eqs. (3)–(31), Lemke, undamped Fig. 3.

    Every interior node is a contact row against the wall at h. Returns
    ``(alpha, reactions, outer_iterations, converged)``. This is the "dense
    path" that the banded, globalised :func:`lcpbench.solve` is compared
    against; it is for the single-wall actuator scene only.
    """
    from ..solvers.lemke import lemke

    chain = scene.chain()
    a = scene.length / chain.links
    alpha = chain.rest_alpha.copy()
    R = np.zeros(chain.links - 1)
    for it in range(1, max_outer + 1):
        p = paper_step(alpha, EI=scene.EI, length=scene.length, weight=scene.weight,
                       height=scene.height, rest_joint=chain.rest_joint)
        sol = lemke(p.K, p.z)
        if not sol.solved:
            return alpha, R, it, False
        R = sol.w
        u = scene.height - sol.z  # eq. (28)
        new = paper_predict_alpha(p, u, alpha, a)
        change = float(np.max(np.abs(new - alpha)))
        alpha = new
        if not np.all(np.isfinite(alpha)):
            return alpha, R, it, False
        if change < tol:
            return alpha, R, it, True
    return alpha, R, max_outer, False
