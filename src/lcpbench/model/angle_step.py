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

Each step solves the QP of the Lagrangian's exact Hessian with the constraints
linearised in α, in O(N) per change of its active set
(:mod:`lcpbench.model.angle_kernel`): the Hessian is tridiagonal plus diagonal, and
the node height increments lifted into the unknowns make the constraints banded; the
walls by a dual active set warm-started from the last step's, one banded
factorisation per change. Where the Hessian is not positive on the active face a
shift σ I is added (no Newton step there). From a cold start a chain that drapes on a
wall changes O(N) walls, so those first steps cost O(N²) (N = 5000: about 4 s). A step is
accepted by an Armijo search on the ℓ₁ merit function E + ρ (|c| + Σ max(0, −g)).
Near a stable answer the steps are full Newton steps on the KKT system: quadratic
convergence.

The answer is handed back to the height-parameterised driver
(:func:`lcpbench.model.compiled.drive`), whose last step and lcpbench's judge decide
"converged", as for every other solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..numba_cache import kept
from ..problems.scenes import Chain
from .chain import alpha_from_heights, heights

#: chains of more links than this are not solved in angles
MAX_LINKS = 5000
#: the constraints (closure, walls) are met to this fraction of ℓ at an answer
FEASIBLE = 1e-11
#: a wall counts as violated in a step's QP where its linearised gap is below −this × ℓ
QP_GAP = 1e-13
#: load parameter wℓ³/EI (total load over EI/ℓ²) from which a chain is solved in
#: angles first: from about 40 the height steps crawl (41 outer iterations at 1e-3
#: for a chain hanging at wℓ³/EI = 42) and from a few hundred they stall
#: (benchmarks/heavy_chains.py)
HEAVY = 40.0
_KERNEL: list = []  # the SQP kernel's module, once loaded (emptied by numba_cache.use_aot)


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
    closure: float = 0.0  # λ, the closure's multiplier (the right pin's vertical reaction, N)


def load_parameter(chain: Chain) -> float:
    """wℓ³/EI: the chain's total load over EI/ℓ² (dimensionless)."""
    return total_load(chain) / float(chain.force_scale)


def total_load(chain: Chain) -> float:
    """Σ|μ_i|: the chain's total load (N), kept with the chain."""
    return chain.derived("_total_load", lambda: float(np.sum(np.abs(chain.link_load))))


def in_reach(chain: Chain) -> bool:
    """Whether the SQP takes the chain: rigid flat walls, joints between adjacent links
    (or a clamp of the first), at most :data:`MAX_LINKS` links. Kept with the chain."""
    return chain.derived("_in_reach", lambda: _in_reach(chain))


def _in_reach(chain: Chain) -> bool:
    if chain.elastic_walls or chain.profiled_walls or chain.links > MAX_LINKS:
        return False
    if chain.consecutive:  # the scene built this layout (Chain.consecutive says so)
        return True
    jl, jr = chain.joint_links[:, 0], chain.joint_links[:, 1]
    return bool(np.all(jl == jr - 1) and np.all(chain.free_nodes == np.arange(
        1, chain.free_nodes.size + 1)))


def heavy(chain: Chain) -> bool:
    """Whether the chain is solved in angles first: :func:`in_reach` and load
    parameter ≥ :data:`HEAVY`."""
    return in_reach(chain) and load_parameter(chain) >= HEAVY


class _Problem:
    """The arrays of the SQP kernel for a chain (:func:`angle_kernel.solve_sqp`), O(N), but
    its rest joint angles φ*: its layout, walls and load, which a step of the loading path
    shares with the whole chain (:func:`sqp_arrays`)."""

    def __init__(self, chain: Chain):
        self.a = float(chain.link_length)
        self.jl = np.ascontiguousarray(chain.joint_links[:, 0], dtype=np.int64)
        self.jr = np.ascontiguousarray(chain.joint_links[:, 1], dtype=np.int64)
        self.k = np.ascontiguousarray(chain.joint_stiffness, dtype=float)
        load = chain.link_load  # Σ μ_k y_c,k = a Σ_i W_i sin α_i
        self.load = np.ascontiguousarray(load, dtype=float)
        self.W = np.concatenate((np.cumsum(load[::-1])[::-1][1:], [0.0])) + 0.5 * load
        self.pinned = bool(chain.free_nodes[-1] < chain.links)
        up = np.flatnonzero(np.isfinite(chain.upper))
        lo = np.flatnonzero(np.isfinite(chain.lower))
        self.free = np.concatenate((up, lo))
        self.node = np.ascontiguousarray(chain.free_nodes[self.free], dtype=np.int64)
        self.side = np.concatenate((np.ones(up.size), -np.ones(lo.size)))
        self.limit = np.concatenate((chain.upper[up], chain.lower[lo])).astype(float)
        self.n_up, self.up, self.lo = up.size, up, lo  # the wall rows' free nodes, by wall


def sqp_arrays(chain: Chain) -> _Problem:
    """The SQP kernel's arrays of ``chain`` but its φ* (a :class:`_Problem`), kept with it
    and handed on to the chains of its loading path made after
    (:meth:`~lcpbench.problems.scenes.Chain.with_rest_shape`,
    :data:`~lcpbench.problems.scenes.LAYOUT_DERIVED`: nothing in them depends on the rest
    shape)."""
    return chain.derived("_angle_problem", lambda: _Problem(chain))


def _first_multipliers(p: _Problem, multipliers) -> tuple[np.ndarray, np.ndarray]:
    """(λ, μ per wall row) to start from: ``multipliers`` (λ, R upper, R lower per free
    node), reactions below zero read as 0; zero where None."""
    if multipliers is None:
        return np.zeros(1), np.zeros(p.free.size)
    lam, upper, lower = multipliers
    mu = np.concatenate((np.asarray(upper, float)[p.up], np.asarray(lower, float)[p.lo]))
    return np.array([float(lam) if p.pinned else 0.0]), np.maximum(mu, 0.0)


def _start(chain: Chain) -> np.ndarray:
    u = np.clip(heights(chain, chain.rest_alpha), chain.lower, chain.upper)
    alpha = alpha_from_heights(chain, u, chain.rest_alpha)
    return chain.rest_alpha.copy() if alpha is None else alpha


def solve_in_angles(chain: Chain, *, tol: float = 1e-10, max_iter: int = 30,
                    start: np.ndarray | None = None,
                    multipliers: tuple | None = None) -> AngleOutcome:
    """The equilibrium of ``chain`` by SQP steps in the link angles α.

    ``multipliers``: (λ, R upper, R lower per free node) of a neighbouring answer (a
    step of the loading path), the first step's multipliers: its walls with R > 0 start
    the QP's active set. None: all zero.

    Stops when a full step moved α by less than ``tol`` (rad) with the
    constraints met to round-off, or after ``max_iter`` steps. Never raises on
    non-convergence.
    """
    p = sqp_arrays(chain)
    kern = kept(_KERNEL, "lcpbench.model.angle_kernel", "solve_sqp")
    alpha = _start(chain) if start is None else np.array(start, float)
    lam, mu = _first_multipliers(p, multipliers)
    code, alpha, sizes, energies, lam, mu = kern.solve_sqp(
        alpha, p.a, p.jl, p.jr, p.k, np.ascontiguousarray(chain.rest_joint, dtype=float), p.load, p.W,
        p.pinned, p.node, p.side, p.limit, lam, mu, QP_GAP * chain.length, float(tol),
        int(max_iter), float(chain.force_scale) * chain.length, float(chain.length), FEASIBLE)
    sizes, energies = sizes.tolist(), energies.tolist()
    if code == kern.QP_FAILED:
        return AngleOutcome(alpha, False, sizes, energies, "the QP of a step failed")
    if code != kern.CONVERGED:
        return AngleOutcome(alpha, False, sizes, energies,
                            f"no convergence in {max_iter} angle steps")
    n = chain.free_nodes.size
    upper, lower = np.zeros(n), np.zeros(n)
    upper[p.up] = mu[:p.n_up]
    lower[p.lo] = mu[p.n_up:]
    return AngleOutcome(alpha, True, sizes, energies, "converged", upper, lower,
                        float(lam[0]))


