"""Outer steps in the link angles α, for heavy chains whose links pass the vertical.

The contact step works in the free-node heights u and linearises the link
angles per eq. (21), α̂ = (û_{i+1} − û_i)/(a cos α_i) − v_i: singular where a
link reaches ±90°. A heavy chain (load parameter wℓ³/EI of tens to 10⁴)
hangs off the wall or drapes on it with links past the vertical, and the
height-parameterised driver crawls or stalls there (200 outer iterations).

This module takes the outer steps in α instead, where every angle is
regular: a sequential quadratic programme (SQP) on the exact energy

    minimise   E(α) = ½ Σ_j k_j (φ_j − φ*_j)² − Σ_i μ_i y_c,i(α)
    subject to c(α) = a Σ sin α_i = 0                (right pin on y = 0)
               side_r (limit_r − y_{k_r}(α)) ≥ 0      (the walls, node k_r)

Each step solves the QP of the Lagrangian's exact Hessian (made positive
definite by taking |eigenvalues|, floored) with the constraints linearised
in α. Its wall multipliers are an LCP (the dual, with the closure row
eliminated), solved by Lemke's method; a step is accepted by an Armijo
search on the ℓ₁ merit function E + ρ (|c| + Σ max(0, −g)). Near the answer
the steps are full Newton steps on the KKT system: quadratic convergence.

The Hessian is dense in α (heights are cumulative sums of a sin α), so the
solve is dense: O(N³) per step, capped at :data:`MAX_LINKS` links. The
answer is handed back to the height-parameterised driver
(:func:`lcpbench.model.compiled.drive`), whose last step and lcpbench's
judge decide "converged", as for every other solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..problems.scenes import Chain
from ..solvers.base import Status
from ..solvers.lemke import lemke
from .chain import alpha_from_heights, energy, heights, joint_angles, node_positions

#: chains of more links than this are not solved in angles (dense O(N³) steps)
MAX_LINKS = 1500
#: the constraints (closure, walls) are met to this fraction of ℓ at an answer
FEASIBLE = 1e-11
#: load parameter wℓ³/EI (total load over EI/ℓ²) from which a chain is solved in
#: angles first: from about 40 the height steps crawl (41 outer iterations at 1e-3
#: for a chain hanging at wℓ³/EI = 42) and from a few hundred they stall
#: (benchmarks/heavy_chains.py)
HEAVY = 40.0


@dataclass
class AngleOutcome:
    """The SQP's answer: link angles α (rad), whether the KKT point was reached,
    the step sizes max|Δα| (rad) per iteration, and why it stopped."""

    alpha: np.ndarray
    converged: bool
    step_sizes: list
    energies: list
    reason: str
    forces_upper: np.ndarray | None = None  # the wall multipliers per free node (N)
    forces_lower: np.ndarray | None = None


def load_parameter(chain: Chain) -> float:
    """wℓ³/EI: the chain's total load over EI/ℓ² (dimensionless)."""
    return total_load(chain) / float(chain.force_scale)


def total_load(chain: Chain) -> float:
    """Σ|μ_i|: the chain's total load (N), kept with the chain."""
    return chain.derived("_total_load", lambda: float(np.sum(np.abs(chain.link_load))))


def in_reach(chain: Chain) -> bool:
    """Whether the SQP takes the chain: rigid flat walls, at most :data:`MAX_LINKS`
    links."""
    if chain.elastic_walls or chain.profiled_walls:
        return False
    return chain.links <= MAX_LINKS


def heavy(chain: Chain) -> bool:
    """Whether the chain is solved in angles first: :func:`in_reach` and load
    parameter ≥ :data:`HEAVY`."""
    return in_reach(chain) and load_parameter(chain) >= HEAVY


def _incidence(chain: Chain) -> np.ndarray:
    d = np.zeros((chain.joint_links.shape[0], chain.links))
    rows = np.arange(d.shape[0])
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]
    d[rows, right] += 1.0
    d[rows[left >= 0], left[left >= 0]] -= 1.0
    return d


class _Problem:
    """E, c, g of a chain with their exact first and second derivatives in α."""

    def __init__(self, chain: Chain):
        self.chain = chain
        self.a = chain.link_length
        self.D = _incidence(chain)
        self.K = self.D.T @ (chain.joint_stiffness[:, None] * self.D)
        load = chain.link_load  # Σ μ_k y_c,k = a Σ_i W_i sin α_i
        self.W = np.concatenate((np.cumsum(load[::-1])[::-1][1:], [0.0])) + 0.5 * load
        self.pinned = bool(chain.free_nodes[-1] < chain.links)
        up = np.flatnonzero(np.isfinite(chain.upper))
        lo = np.flatnonzero(np.isfinite(chain.lower))
        self.free = np.concatenate((up, lo))
        self.node = chain.free_nodes[self.free]
        self.side = np.concatenate((np.ones(up.size), -np.ones(lo.size)))
        self.limit = np.concatenate((chain.upper[up], chain.lower[lo]))
        self.mask = (np.arange(chain.links)[None, :] < self.node[:, None]).astype(float)

    def energy(self, alpha):
        return energy(self.chain, alpha)

    def gradient(self, alpha):
        dphi = joint_angles(self.chain, alpha) - self.chain.rest_joint
        return self.D.T @ (self.chain.joint_stiffness * dphi) - self.a * np.cos(alpha) * self.W

    def closure(self, alpha):
        if not self.pinned:
            return np.zeros(0), np.zeros((0, alpha.size))
        return np.array([self.a * np.sum(np.sin(alpha))]), (self.a * np.cos(alpha))[None, :]

    def walls(self, alpha):
        y = node_positions(self.chain, alpha)[1]
        g = self.side * (self.limit - y[self.node])
        jac = -self.side[:, None] * self.mask * (self.a * np.cos(alpha))[None, :]
        return g, jac

    def hessian(self, alpha, lam, mu):
        """∇²(E − λ c − μ·g)."""
        a_sin = self.a * np.sin(alpha)
        diag = self.W * a_sin
        if lam.size:
            diag = diag + lam[0] * a_sin
        diag = diag - ((mu * self.side) @ self.mask) * a_sin
        return self.K + np.diag(diag)


def _convexify(H: np.ndarray) -> np.ndarray:
    """H with its eigenvalues replaced by their absolute values, floored at 1e-10 of
    the largest: positive definite, and H itself wherever H is."""
    val, vec = np.linalg.eigh(0.5 * (H + H.T))
    top = float(np.max(np.abs(val)))
    val = np.maximum(np.abs(val), 1e-10 * top)
    return (vec * val) @ vec.T


def _qp_step(B, grad, c, Jc, g, Jg):
    """The QP min ½dᵀBd + gradᵀd s.t. c + Jc d = 0, g + Jg d ≥ 0: (d, λ, μ) or None."""
    L = np.linalg.cholesky(B)

    def solve(rhs):
        return np.linalg.solve(L.T, np.linalg.solve(L, rhs))

    A = np.vstack((Jc, Jg))
    BiAt = solve(A.T) if A.shape[0] else np.zeros((B.shape[0], 0))
    Big = solve(grad)
    M = A @ BiAt
    q = -A @ Big + np.concatenate((c, g))  # A d + (c, g) = M ν + q
    ne = c.size
    mu = np.zeros(g.size)
    if g.size:
        Mii, qi = M[ne:, ne:], q[ne:]
        if ne:
            Mee, Mei = M[:ne, :ne], M[:ne, ne:]
            S = np.linalg.solve(Mee, np.hstack((Mei, q[:ne, None])))
            Mii = Mii - M[ne:, :ne] @ S[:, :-1]
            qi = qi - M[ne:, :ne] @ S[:, -1]
        if np.any(qi < 0):
            sol = lemke(0.5 * (Mii + Mii.T), qi)
            if sol.status not in (Status.SOLVED, Status.INACCURATE):
                return None
            mu = np.maximum(np.asarray(sol.z, float), 0.0)
    lam = -np.linalg.solve(M[:ne, :ne], M[:ne, ne:] @ mu + q[:ne]) if ne else np.zeros(0)
    d = BiAt @ np.concatenate((lam, mu)) - Big
    return _on_active_set(B, grad, c, Jc, g, Jg, mu > 0) or (d, lam, mu)


def _on_active_set(B, grad, c, Jc, g, Jg, active):
    """The step again from the full KKT system of the closure and the active walls
    as equalities (round-off of the dense KKT solve, not of the LCP's normal
    equations A B⁻¹ Aᵀ), or None if its multipliers or the other walls disagree."""
    A = np.vstack((Jc, Jg[active]))
    m, n = A.shape[0], B.shape[0]
    kkt = np.zeros((n + m, n + m))
    kkt[:n, :n], kkt[:n, n:], kkt[n:, :n] = B, -A.T, A
    try:
        sol = np.linalg.solve(kkt, np.concatenate((-grad, -c, -g[active])))
    except np.linalg.LinAlgError:
        return None
    d, nu = sol[:n], sol[n:]
    mu = np.zeros(g.size)
    mu[active] = nu[c.size:]
    scale = float(np.max(np.abs(g), initial=0.0)) + float(np.max(np.abs(Jg), initial=0.0))
    if np.any(mu < 0) or np.any((g + Jg @ d)[~active] < -1e-12 * max(scale, 1.0)):
        return None
    return d, nu[:c.size], mu


def _start(chain: Chain) -> np.ndarray:
    u = np.clip(heights(chain, chain.rest_alpha), chain.lower, chain.upper)
    alpha = alpha_from_heights(chain, u, chain.rest_alpha)
    return chain.rest_alpha.copy() if alpha is None else alpha


def solve_in_angles(chain: Chain, *, tol: float = 1e-10, max_iter: int = 30,
                    start: np.ndarray | None = None) -> AngleOutcome:
    """The equilibrium of ``chain`` by SQP steps in the link angles α.

    Stops when a full step moved α by less than ``tol`` (rad) with the
    constraints met to round-off, or after ``max_iter`` steps. Never raises on
    non-convergence.
    """
    p = _Problem(chain)
    alpha = _start(chain) if start is None else np.array(start, float)
    lam = np.zeros(1 if p.pinned else 0)
    mu = np.zeros(p.free.size)
    sizes: list = []
    energies: list = []
    near = False
    scale = float(chain.force_scale) * chain.length  # EI/ℓ
    for _ in range(max_iter):
        grad = p.gradient(alpha)
        c, Jc = p.closure(alpha)
        g, Jg = p.walls(alpha)
        B = _convexify(p.hessian(alpha, lam, mu))
        try:
            out = _qp_step(B, grad, c, Jc, g, Jg)
        except np.linalg.LinAlgError:
            out = None
        if out is None:
            return AngleOutcome(alpha, False, sizes, energies, "the QP of a step failed")
        d, lam_new, mu_new = out
        size = float(np.max(np.abs(d), initial=0.0))
        cap = 0.5  # rad: no link turns by more than this in one step
        if size > cap:
            d = d * (cap / size)
        rho = 2.0 * float(np.max(np.abs(np.concatenate((lam_new, mu_new))), initial=0.0)) \
            + 1e-8 * scale / chain.length

        def merit(al, rho=rho):
            cc = p.closure(al)[0]
            gg = p.walls(al)[0]
            return p.energy(al) + rho * (float(np.sum(np.abs(cc)))
                                         + float(np.sum(np.maximum(-gg, 0.0))))

        m0 = merit(alpha)
        slope = float(grad @ d) - rho * (float(np.sum(np.abs(c)))
                                         + float(np.sum(np.maximum(-g, 0.0))))
        noise = 1e-13 * (abs(m0) + scale)
        t = 1.0
        while True:  # a step below tol is taken whole: the merit is round-off there
            trial = alpha + t * d
            if size < tol:
                break
            if merit(trial) <= m0 + 1e-4 * t * min(slope, 0.0) + noise:
                break
            t *= 0.5
            if t < 1e-10:
                break
        alpha = trial
        lam, mu = lam_new, mu_new
        sizes.append(float(t * np.max(np.abs(d), initial=0.0)))
        energies.append(p.energy(alpha))
        viol = max(float(np.max(np.abs(p.closure(alpha)[0]), initial=0.0)),
                   float(np.max(-p.walls(alpha)[0], initial=0.0)))
        # one more full step after the first that meets the test: the active walls'
        # gaps then sit at round-off, not at the size of the step before
        polished = bool(t == 1.0 and size < tol and viol < FEASIBLE * chain.length and near)
        near = bool(t == 1.0 and size < tol)
        if t == 1.0 and size < tol and viol < FEASIBLE * chain.length and polished:
            n = chain.free_nodes.size
            upper, lower = np.zeros(n), np.zeros(n)
            upper[p.free[p.side > 0]] = mu[p.side > 0]
            lower[p.free[p.side < 0]] = mu[p.side < 0]
            return AngleOutcome(alpha, True, sizes, energies, "converged", upper, lower)
    return AngleOutcome(alpha, False, sizes, energies,
                        f"no convergence in {max_iter} angle steps")
