"""An independent reference: minimise the exact nonlinear energy with SLSQP.

The contact model of the paper linearises the chain about the current shape
and solves a sequence of LCPs (Fig. 3). This module finds the same
equilibrium without any linearisation, as a reference to judge it by:

    minimise   E(α) = (EI/(2a)) Σ_j (φ_j − φ*_j)²  −  Σ_i μ_i y_c,i(α)
    over       α ∈ R^N  (the link angles)
    subject to c(α) = y_{N+1}(α) = a Σ_i sin α_i = 0        (right pin on y = 0)
               h_k − y_k(α) ≥ 0                             (upper wall, node k)
               y_k(α) − l_k ≥ 0                             (lower wall of a channel)

or, for walls of any profile, h(x_k(α)) − y_k(α) ≥ 0 and y_k(α) − l(x_k(α)) ≥ 0
(:mod:`lcpbench.reference.energy_profile`: exact gradient and Hessian; the wall
multipliers are then the vertical parts of the normal reactions)

with φ the joint angles of :func:`~lcpbench.model.chain.joint_angles`, μ_i the
link loads (``chain.link_load``, acting at the link centres y_c,i) and one
inequality per node that can reach a wall (``chain.upper`` / ``chain.lower``
finite). The energy is :func:`~lcpbench.model.chain.energy`; this module adds
its exact gradient and Hessian and those of the constraints, all of them
closed-form (the constraint Hessians are diagonal).

SLSQP (``scipy.optimize.minimize``) works on the nondimensionalised problem:
energy over EI/ℓ, lengths over ℓ. Its answer is then polished by Newton's
method on the KKT system of the active set it identified (stationarity of the
Lagrangian, closure, active walls at equality), with the exact Hessian of the
Lagrangian; the active set is corrected if a multiplier turns negative or a
wall is crossed. The wall reactions are the inequality multipliers.

Nothing here calls the contact step or the driver.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from ..model.chain import alpha_from_heights, energy, heights, joint_angles, node_positions
from ..model.profile import walls_at
from ..problems.scenes import Chain
from .energy_profile import profile_wall_hessian, profile_walls


@dataclass
class EnergyReference:
    """The minimiser of the exact chain energy and its wall reactions.

    Per-node arrays (forces) run over the free nodes, as in
    :class:`~lcpbench.model.result.ContactResult`.

    Attributes
    ----------
    alpha : ndarray (N,)
        Link angles α (rad).
    x, y : ndarray (N+1,)
        Node coordinates (mm).
    forces : ndarray
        Reaction of the upper wall at each free node (N, > 0 pushing away from
        the wall, i.e. toward −y); the multiplier of h − y_k ≥ 0.
    forces_lower : ndarray or None
        Reaction of the lower wall of a channel (N, > 0 pushing toward +y);
        None without a channel.
    total_force : float
        Sum of ``forces`` (N).
    pin_reaction : float
        Vertical reaction of the right pin (N, +y); 0 for a free end.
    energy : float
        Total potential energy at ``alpha`` (N·mm).
    success : bool
        Whether the final point passes the KKT check (stationarity, closure,
        walls, multiplier signs; see ``kkt_residual``).
    message : str
        SLSQP's message and what the polish did.
    nit : int
        SLSQP iterations.
    newton_iterations : int
        Newton iterations of the polish (0 if not polished).
    polished : bool
        Whether the Newton polish was accepted.
    kkt_residual : float
        Largest of: |∇L| over EI/ℓ, closure and wall violation over ℓ,
        negative multipliers over EI/ℓ², |gap · reaction| over EI/ℓ
        (all dimensionless).
    """

    alpha: np.ndarray
    x: np.ndarray
    y: np.ndarray
    forces: np.ndarray
    forces_lower: np.ndarray | None
    total_force: float
    pin_reaction: float
    energy: float
    success: bool
    message: str
    nit: int
    newton_iterations: int
    polished: bool
    kkt_residual: float


# -- exact derivatives (physical units: mm, N, N·mm) --------------------------


def _incidence(chain: Chain) -> np.ndarray:
    """D (J×N) with φ = D α (a clamp on the left contributes α_l = 0)."""
    d = np.zeros((chain.joint_links.shape[0], chain.links))
    rows = np.arange(d.shape[0])
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]
    d[rows, right] += 1.0
    has_left = left >= 0
    d[rows[has_left], left[has_left]] -= 1.0
    return d


def _load_moment_weights(chain: Chain) -> np.ndarray:
    """W_i with Σ_k μ_k y_c,k = a Σ_i W_i sin α_i: W_i = Σ_{k>i} μ_k + μ_i/2 (N)."""
    load = chain.link_load
    after = np.concatenate((np.cumsum(load[::-1])[::-1][1:], [0.0]))
    return after + 0.5 * load


def energy_gradient(chain: Chain, alpha: np.ndarray) -> np.ndarray:
    """∂E/∂α (N·mm/rad) of :func:`~lcpbench.model.chain.energy`, exact."""
    d = _incidence(chain)
    dphi = joint_angles(chain, alpha) - chain.rest_joint
    gravity = chain.link_length * np.cos(alpha) * _load_moment_weights(chain)
    return d.T @ (chain.joint_stiffness * dphi) - gravity


def energy_hessian(chain: Chain, alpha: np.ndarray) -> np.ndarray:
    """∂²E/∂α² (N·mm/rad²), exact: Dᵀ diag(k) D + diag(a W sin α)."""
    d = _incidence(chain)
    gravity = chain.link_length * np.sin(alpha) * _load_moment_weights(chain)
    return d.T @ (chain.joint_stiffness[:, None] * d) + np.diag(gravity)


def _pinned_right(chain: Chain) -> bool:
    return bool(chain.free_nodes[-1] < chain.links)


def closure(chain: Chain, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The equality constraints c(α) = 0 (mm) and their Jacobian (mm/rad).

    One row, the height of the right pin a Σ sin α_i, when the right end is
    pinned; none for a free end.
    """
    if not _pinned_right(chain):
        return np.zeros(0), np.zeros((0, chain.links))
    a = chain.link_length
    return np.array([a * np.sum(np.sin(alpha))]), (a * np.cos(alpha))[None, :]


@dataclass(frozen=True)
class WallRows:
    """The inequality rows g_r(α) = side_r · (limit_r − y_{node_r}) ≥ 0.

    Attributes
    ----------
    free : ndarray of int
        Index of each row's node among the free nodes.
    node : ndarray of int
        0-based node index of each row.
    side : ndarray of float
        +1 for the upper wall (limit = ``chain.upper``), −1 for the lower.
    limit : ndarray
        Wall height (mm).
    """

    free: np.ndarray
    node: np.ndarray
    side: np.ndarray
    limit: np.ndarray

    @classmethod
    def of(cls, chain: Chain) -> WallRows:
        up = np.flatnonzero(np.isfinite(chain.upper))
        lo = np.flatnonzero(np.isfinite(chain.lower))
        free = np.concatenate((up, lo))
        return cls(
            free=free,
            node=chain.free_nodes[free],
            side=np.concatenate((np.ones(up.size), -np.ones(lo.size))),
            limit=np.concatenate((chain.upper[up], chain.lower[lo])),
        )

    def mask(self, chain: Chain) -> np.ndarray:
        """(rows × N) 0/1: link j lies left of the row's node (y_k = a Σ_{j<k} sin α_j)."""
        return (np.arange(chain.links)[None, :] < self.node[:, None]).astype(float)


def walls(
    chain: Chain, alpha: np.ndarray, rows: WallRows | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """The wall gaps g(α) ≥ 0 (mm) and their Jacobian (mm/rad), one row per reachable wall."""
    rows = WallRows.of(chain) if rows is None else rows
    if chain.profiled_walls:  # h(x_k(α)): reference/energy_profile.py
        return profile_walls(chain, alpha, rows)
    _, y = node_positions(chain, alpha)
    g = rows.side * (rows.limit - y[rows.node])
    jac = -rows.side[:, None] * rows.mask(chain) * (chain.link_length * np.cos(alpha))[None, :]
    return g, jac


def lagrangian_hessian(
    chain: Chain,
    alpha: np.ndarray,
    eq_multiplier: np.ndarray,
    wall_multiplier: np.ndarray,
    rows: WallRows | None = None,
) -> np.ndarray:
    """∇²(E − λ·c − μ·g) with respect to α (N·mm/rad²), exact.

    c and g have diagonal Hessians: ∂²(a Σ sin α)/∂α² = −diag(a sin α), and
    ∂²g_r/∂α² = side_r · diag(a sin α_j [j < node_r]).
    """
    rows = WallRows.of(chain) if rows is None else rows
    a_sin = chain.link_length * np.sin(alpha)
    diag = np.zeros(chain.links)
    if eq_multiplier.size:
        diag += float(eq_multiplier[0]) * a_sin
    if chain.profiled_walls:  # the walls' Hessians are not diagonal: reference/energy_profile.py
        return energy_hessian(chain, alpha) + np.diag(diag) \
            - profile_wall_hessian(chain, alpha, wall_multiplier, rows)
    diag -= ((wall_multiplier * rows.side) @ rows.mask(chain)) * a_sin
    return energy_hessian(chain, alpha) + np.diag(diag)


# -- the minimisation ----------------------------------------------------------


def _start(chain: Chain) -> np.ndarray:
    """The unconstrained arc clipped to the walls, or the arc scaled down until it fits."""
    u = np.clip(heights(chain, chain.rest_alpha), chain.lower, chain.upper)
    alpha = alpha_from_heights(chain, u, chain.rest_alpha)
    for _ in range(5 if chain.profiled_walls and alpha is not None else 0):
        at = walls_at(chain, alpha)  # a profile: clip again at the nodes' new x
        u = np.clip(heights(chain, alpha), at.lower, at.upper)
        alpha = alpha_from_heights(chain, u, alpha)
        if alpha is None:
            break
    if alpha is not None:
        return alpha
    for scale in 0.5 ** np.arange(1, 60):  # pragma: no cover - clipping always fits so far
        trial = scale * chain.rest_alpha
        u = heights(chain, trial)
        if np.all(u <= chain.upper) and np.all(u >= chain.lower):
            return trial
    return np.zeros(chain.links)  # pragma: no cover


def _kkt(chain: Chain, rows: WallRows, alpha, lam, mu) -> float:
    """The dimensionless KKT residual (see :attr:`EnergyReference.kkt_residual`)."""
    e0 = chain.force_scale * chain.length  # EI/ℓ
    ell = chain.length
    c, jc = closure(chain, alpha)
    g, jg = walls(chain, alpha, rows)
    stat = energy_gradient(chain, alpha) - jc.T @ lam - jg.T @ mu
    parts = [
        np.max(np.abs(stat), initial=0.0) / e0,
        np.max(np.abs(c), initial=0.0) / ell,
        max(0.0, -float(np.min(g, initial=0.0))) / ell,
        max(0.0, -float(np.min(mu, initial=0.0))) / chain.force_scale,
        np.max(np.abs(g * mu), initial=0.0) / e0,
    ]
    return float(max(parts))


def _newton(chain, rows, alpha, lam, mu, active, max_iter=30):
    """Newton on the KKT system with ``active`` walls at equality; returns (α, λ, μ, its, ok)."""
    e0 = chain.force_scale * chain.length
    ell = chain.length
    n = chain.links
    mu = np.where(active, mu, 0.0)
    idx = np.flatnonzero(active)
    best = np.inf
    for it in range(1, max_iter + 1):
        c, jc = closure(chain, alpha)
        g, jg = walls(chain, alpha, rows)
        ja = jg[idx]
        grad = energy_gradient(chain, alpha) - jc.T @ lam - ja.T @ mu[idx]
        # scaled residual: stationarity over EI/ℓ, constraints over ℓ
        res = np.concatenate((grad / e0, c / ell, g[idx] / ell))
        norm = float(np.max(np.abs(res), initial=0.0))
        if norm < 1e-15 or (it > 3 and norm >= 0.5 * best):
            return alpha, lam, mu, it - 1, norm < 1e-11
        best = min(best, norm)
        h = lagrangian_hessian(chain, alpha, lam, mu, rows) / e0
        m_eq, m_a = c.size, idx.size
        kkt = np.zeros((n + m_eq + m_a, n + m_eq + m_a))
        jac = np.vstack((jc, ja)) / ell  # d(constraints/ℓ)/dα
        kkt[:n, :n] = h
        kkt[:n, n:] = -jac.T  # multiplier unknowns are dimensionless: λ ℓ/E0
        kkt[n:, :n] = jac
        try:
            step = np.linalg.solve(kkt, -res)
        except np.linalg.LinAlgError:
            return alpha, lam, mu, it - 1, False
        alpha = alpha + step[:n]
        scale = e0 / ell  # multiplier units: N
        lam = lam + step[n:n + m_eq] * scale
        mu = mu.copy()
        mu[idx] += step[n + m_eq:] * scale
    return alpha, lam, mu, max_iter, False


def _polish(chain, rows, alpha, lam, mu):
    """Newton polish with active-set corrections; None if it does not settle."""
    fs = chain.force_scale
    active = mu > 1e-9 * max(fs, float(np.max(mu, initial=0.0)))
    its = 0
    for _ in range(2 * rows.node.size + 2):
        a2, l2, m2, k, ok = _newton(chain, rows, alpha.copy(), lam.copy(), mu.copy(), active)
        its += k
        if not ok:
            return None
        g, _ = walls(chain, a2, rows)
        negative = active & (m2 < -1e-12 * fs)
        crossed = ~active & (g < -1e-13 * chain.length)
        if not negative.any() and not crossed.any():
            return a2, l2, np.where(active, m2, 0.0), its
        active = (active & ~negative) | crossed
    return None


def minimise_energy(
    chain_or_scene,
    *,
    ftol: float = 1e-12,
    maxiter: int = 1000,
    polish: bool = True,
    check: float = 1e-9,
    start: np.ndarray | None = None,
) -> EnergyReference:
    """Equilibrium of a chain by direct minimisation of its exact energy (SLSQP).

    Parameters
    ----------
    chain_or_scene : Chain or a scene with ``.chain()``
        What to solve (an :class:`~lcpbench.problems.scenes.ActuatorScene`,
        a :class:`~lcpbench.problems.cantilever.CantileverScene`, or their chain).
    ftol : float
        SLSQP's ``ftol`` on the dimensionless energy (energy over EI/ℓ).
    maxiter : int
        SLSQP iteration limit.
    polish : bool
        Refine SLSQP's answer by Newton's method on the KKT system of its
        active set (default). Without it the answer is SLSQP's alone, good to
        about sqrt(ftol) in the angles.
    check : float
        ``success`` requires ``kkt_residual <= check``.
    start : link angles α (rad) to start from; None: the free arc clipped to the
        walls. A scene with several stable states gives the one nearest the start.

    Returns
    -------
    EnergyReference
        Never raises on non-convergence: ``success`` is False with a message.
    """
    chain = chain_or_scene.chain() if hasattr(chain_or_scene, "chain") else chain_or_scene
    e0 = chain.force_scale * chain.length  # EI/ℓ (N·mm)
    ell = chain.length
    rows = WallRows.of(chain)

    constraints = []
    if _pinned_right(chain):
        constraints.append({
            "type": "eq",
            "fun": lambda al: closure(chain, al)[0] / ell,
            "jac": lambda al: closure(chain, al)[1] / ell,
        })
    if rows.node.size:
        constraints.append({
            "type": "ineq",
            "fun": lambda al: walls(chain, al, rows)[0] / ell,
            "jac": lambda al: walls(chain, al, rows)[1] / ell,
        })
    res = minimize(
        lambda al: energy(chain, al) / e0,
        _start(chain) if start is None else np.array(start, float),
        jac=lambda al: energy_gradient(chain, al) / e0,
        method="SLSQP",
        constraints=constraints,
        options={"ftol": ftol, "maxiter": maxiter},
    )
    alpha = np.asarray(res.x, dtype=float)
    m_eq = 1 if _pinned_right(chain) else 0
    mult = np.asarray(getattr(res, "multipliers", np.zeros(m_eq + rows.node.size)), float)
    lam = mult[:m_eq] * e0 / ell  # N
    mu = mult[m_eq:m_eq + rows.node.size] * e0 / ell
    message = str(res.message)
    newton_its, polished = 0, False
    if polish:
        out = _polish(chain, rows, alpha, lam, mu)
        if out is None:
            message += "; Newton polish did not settle (SLSQP answer kept)"
        else:
            alpha, lam, mu, newton_its = out
            polished = True
            message += f"; polished by {newton_its} Newton steps on the KKT system"
    residual = _kkt(chain, rows, alpha, lam, mu)
    n_free = chain.free_nodes.size
    upper = np.zeros(n_free)
    lower = np.zeros(n_free)
    is_up = rows.side > 0
    upper[rows.free[is_up]] = mu[is_up]
    lower[rows.free[~is_up]] = mu[~is_up]
    x, y = node_positions(chain, alpha)
    return EnergyReference(
        alpha=alpha,
        x=x,
        y=y,
        forces=upper,
        forces_lower=lower if chain.channel else None,
        total_force=float(upper.sum()),
        pin_reaction=float(lam[0]) if lam.size else 0.0,
        energy=energy(chain, alpha),
        success=bool(residual <= check),
        message=message,
        nit=int(getattr(res, "nit", 0)),
        newton_iterations=newton_its,
        polished=polished,
        kkt_residual=residual,
    )
