"""Large N: the contact step in increments, on the tridiagonal factor of H.

Two things limit the height formulation of the step (:mod:`.step`) at large N:

1. **Forming H = Jᵀ diag(k) J squares the conditioning of J.** cond(H) grows
   as N⁴; at N ≈ 7,000 one refinement of the dual active set no longer
   reaches round-off (the judge sees reactions of −2.7 EI/ℓ² where the active
   set certified zero), and near N = 3·10⁴ the banded Cholesky of the rounded
   H fails. The face solves here use J itself
   (:class:`lcpbench.linalg.saddle.TridiagonalFactor`): error ~ cond(J) ε ~ N² ε.
2. **Heights rounded to doubles carry force.** A reaction is a second
   difference of the joint moments, which are second differences of the
   heights: R ~ 16 EI δu / a³. Heights of a few mm rounded to ε give
   δR ~ 1e-5 N at N = 10⁴ and ~1e-2 N (a few % of the paper scene's force)
   at N = 10⁵. So the step here is written in *increments* d = u − u₀ about
   the linearisation point (whose joint angles come from α, not from
   heights), and the driver moves α by exact inverse kinematics of the
   increments, sin α'_i = sin α_i + (d_{i+1} − d_i)/a (:func:`alpha_from_increments`):
   round-off then scales with the increment and with ε·k/a² per node, not with
   the heights.

The same minimisation, the same walls and the same Armijo search as the
globalised driver (:mod:`.driver`); only the unknown (increments, not
heights) and the face solves differ. The driver is :mod:`.large_driver`;
the result judge (:mod:`.judge`) takes its own judge step the same way.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..linalg.saddle import TridiagonalFactor
from ..linalg.twisted import TwistedFactor
from ..problems.scenes import Chain
from .step import ContactStep

#: links from which :func:`lcpbench.solve` and the judge use this formulation
#: (below it the Cholesky of H is accurate: one refinement contracts by
#: cond(H) ε ≈ 1e-2 at N = 4000, 0.26 at N = 7000)
LARGE_N = 4000


def layout_fits(chain: Chain) -> bool:
    """J is square and tridiagonal: joint j joins links j, j + 1 and bends at free node j
    (both ends pinned, as an actuator section)."""
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]
    f = chain.free_nodes
    n = f.size
    return bool(n >= 3 and right.size == n and np.array_equal(f, np.arange(1, n + 1))
                and np.array_equal(right, np.arange(1, n + 1))
                and np.array_equal(left, np.arange(n)) and chain.links == n + 1)


def applies(chain: Chain) -> bool:
    """Whether solves and the judge use the increment formulation (N >= LARGE_N; rigid,
    flat walls: elastic walls and wall profiles keep their own steps)."""
    if chain.elastic_walls or chain.profiled_walls:
        return False
    return chain.links >= LARGE_N and layout_fits(chain)


def increment_step(step: ContactStep, *, restart: bool = True) -> ContactStep:
    """The step in increments d = u − u₀: the same QP, moved to the origin.

    Its linear term is the factored gradient at u₀ (from the joint angles of α,
    no cancellation), its walls are the gaps of u₀, and its face solves use
    the tridiagonal factor (``restart``: twisted, each face refactored between its
    first and last change, :class:`~lcpbench.linalg.twisted.TwistedFactor`; False:
    the reference, a full factorisation per face, :class:`TridiagonalFactor`).
    """
    n = step.size
    factor = (TwistedFactor(step.coef, step.stiffness) if restart
              else TridiagonalFactor(step.coef, step.stiffness, restart=False))
    return replace(step, linear=step.gradient(step.origin), lower=step.lower - step.origin,
                   upper=step.upper - step.origin, origin=np.zeros(n), factor=factor)


def alpha_from_increments(chain: Chain, alpha: np.ndarray, du: np.ndarray
                          ) -> np.ndarray | None:
    """Link angles whose free node heights are those of α moved by ``du`` (exact).

    The pins do not move, so sin α'_i = sin α_i + (du_{i+1} − du_i)/a; each
    link keeps the branch (sign of cos α) and the 2π-winding of α
    (:func:`lcpbench.model.chain.alpha_from_heights` from heights). None when
    some |sin α'| >= 1.
    """
    dy = np.zeros(chain.links + 1)
    dy[chain.free_nodes] = du
    s = np.sin(alpha) + np.diff(dy) / chain.link_length
    if not np.all(np.isfinite(s)) or np.any(np.abs(s) >= 1.0):
        return None
    base = np.arcsin(s)
    base = np.where(np.cos(alpha) >= 0.0, base, np.pi - base)
    return base + 2 * np.pi * np.round((alpha - base) / (2 * np.pi))
