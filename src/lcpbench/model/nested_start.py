"""A start for the large-N driver from the same chain at fewer links (nested iteration).

From a cold start (the unconstrained arc clipped to the walls) the increment driver
(:mod:`.large_driver`) takes 6 outer steps at the paper's scene, and its walk
bisects spans of thousands of nodes to find each point contact: 116 face solves
at N = 10⁵, each a pass over every node, so the face count grows as log N and the
time faster than N (``results/large-n.md``). The same chain at
:data:`COARSE_LINKS` links solves in about a millisecond. Its shape, interpolated
to N links, is within the discretisation error O(N_c⁻²) of the answer (the first
fine step moves α by ~1e-5 rad), and its contacts are within ~N/N_c nodes of the
fine ones, so the fine driver starts in the right contact set, a gallop away from
the exact nodes, and stops after the two steps its per-node rule needs.

This is grid sequencing (nested iteration, as full multigrid starts each level):
only the start changes. The fine answer is the fine driver's, accepted by the
judge as every other; a coarse solve that fails or a shape that does not fit
the fine chain's walls leaves the cold start.

``coarse_chain`` resamples the chain's distributed quantities by arc length
s (the layout :func:`lcpbench.model.large_n.layout_fits`: N links of length
a = ℓ/N, joint j between links j and j + 1 at node j + 1, both ends pinned):
rest angles α*(s) and loads w(s) = μ/a at link centres, bending stiffness
EI(s) = k a and rest curvature κ(s) = φ*/a at joints, walls at the nodes.
For the paper's actuator this is the chain the scene builds at N_c links.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..linalg import solveh_banded
from ..problems.scenes import Chain
from ..solvers.base import Status, StepSolution
from .angle_step import load_parameter
from .chain import alpha_from_heights, heights
from .heavy_driver import MODERATE
from .outer import DriverOutput, DriverStart

#: links of the coarse chain (a solve of ~1 ms in the compiled kernel); 0: no nested start
COARSE_LINKS = 1000
#: outer steps allowed to the coarse solve (a chain it does not settle in these starts cold)
COARSE_OUTER = 50


def coarse_chain(chain: Chain, links: int) -> Chain:
    """``chain`` with ``links`` links: the same bar, loads and walls, resampled by arc
    length (see the module's docstring).

    Each coarse node takes the wall rows of the fine node nearest it: where N is not a
    multiple of ``links`` a row at the ends of the reachable span may differ from the
    scene's own chain at ``links`` (a node there touches only a vertical chain). The
    rest angles α* are sampled, not re-levelled: for an asymmetric layout the rest
    shape's right pin may sit ~1e-4 mm off y = 0; the energy uses φ*, and the start
    is fitted to the walls and pins again (:func:`interpolated_start`)."""
    n, L = chain.links, float(chain.length)
    a, ac = float(chain.link_length), L / links
    mid = (np.arange(n) + 0.5) * a  # link centres
    node = np.arange(1, n) * a  # joints = free nodes (interior)
    mid_c = (np.arange(links) + 0.5) * ac
    node_c = np.arange(1, links) * ac
    # walls at the fine node nearest each coarse node (flat walls; rows that cannot
    # reach a wall stay +-inf)
    near = np.clip(np.rint(node_c / a).astype(np.int64) - 1, 0, n - 2)
    joints = np.column_stack((np.arange(links - 1), np.arange(1, links)))
    return replace(  # the rest (flat rigid walls' height, scales) as the chain's
        chain,
        links=links,
        link_length=ac,
        rest_alpha=np.interp(mid_c, mid, chain.rest_alpha),
        joint_stiffness=np.interp(node_c, node, chain.joint_stiffness * a) / ac,
        joint_links=joints,
        rest_joint=np.interp(node_c, node, chain.rest_joint / a) * ac,
        link_load=np.interp(mid_c, mid, chain.link_load / a) * ac,
        free_nodes=np.arange(1, links),
        upper=chain.upper[near].copy(),
        lower=chain.lower[near].copy(),
        # elastic walls: a node's spring is k times its share of wall, ∝ its link length
        upper_stiffness=_resampled(chain.upper_stiffness, near, ac / a),
        lower_stiffness=_resampled(chain.lower_stiffness, near, ac / a),
        consecutive=True,
    )


def _resampled(stiffness: np.ndarray | None, near: np.ndarray, ratio: float):
    return None if stiffness is None else np.asarray(stiffness, float)[near] * ratio


def interpolated_start(chain: Chain, coarse: Chain, out: DriverOutput) -> DriverStart | None:
    """The fine chain's start from the coarse answer ``out``.

    Its node heights are the cubic spline in arc length through the coarse node
    heights (:func:`_spline`; both pins on y = 0, and a coarse node on a wall puts the
    fine node at its arc length on it when N is a multiple of N_c), clipped to the
    fine walls where they are rigid; α is their exact inverse kinematics (on the branch of the coarse link
    angles). The coarse contact nodes, mapped to the nearest fine nodes, are the warm
    contact set. None when no chain of the fine links has those heights."""
    n, nc = chain.links, coarse.links
    yc = np.zeros(nc + 1)
    yc[coarse.free_nodes] = heights(coarse, out.alpha)
    u = _spline(yc, np.arange(n + 1) * (nc / n))[chain.free_nodes]
    if not chain.elastic_walls:  # (an elastic wall's nodes indent it)
        u = np.clip(u, chain.lower, chain.upper)
    ref = np.interp((np.arange(n) + 0.5) / n, (np.arange(nc) + 0.5) / nc, out.alpha)
    alpha = alpha_from_heights(chain, u, ref)
    if alpha is None:
        return None
    m = chain.free_nodes.size
    last = out.last_step
    warm = StepSolution(np.full(m, np.nan), np.zeros(m), np.zeros(m), Status.SOLVED,
                        active_upper=_mapped(getattr(last, "active_upper", None), coarse, chain),
                        active_lower=_mapped(getattr(last, "active_lower", None), coarse, chain))
    return DriverStart(alpha, warm)


def _spline(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The cubic spline through ``y`` (at 0, 1, …, len(y) − 1), evaluated at ``x``.

    Its second derivatives M_j solve M_{j−1} + 4 M_j + M_{j+1} = 6 Δ²y_j inside,
    with the end values the one-sided second differences of ``y`` (a pinned end
    carries its rest curvature, not zero, so a natural spline would bend it)."""
    m = y.size
    M = np.empty(m)
    M[0], M[-1] = y[2] - 2 * y[1] + y[0], y[-1] - 2 * y[-2] + y[-3]
    rhs = 6.0 * (y[2:] - 2 * y[1:-1] + y[:-2])
    rhs[0] -= M[0]
    rhs[-1] -= M[-1]
    bands = np.empty((2, m - 2))  # symmetric, lower form: the diagonal 4, then the 1s
    bands[0], bands[1] = 4.0, 1.0
    M[1:-1] = solveh_banded(bands, rhs, lower=True, check_finite=False)
    j = np.minimum(x.astype(np.int64), m - 2)
    t = x - j
    s = 1.0 - t
    return s * y[j] + t * y[j + 1] + ((s**3 - s) * M[j] + (t**3 - t) * M[j + 1]) / 6.0


def _mapped(active: np.ndarray | None, coarse: Chain, chain: Chain) -> np.ndarray:
    """The fine free nodes nearest the coarse free nodes held on a wall (``active``, the
    coarse answer's last contact step's set; the driver's reactions carry round-off at
    every node)."""
    held = np.zeros(chain.free_nodes.size, bool)
    if active is None or np.size(active) != coarse.free_nodes.size:
        return held
    nodes = coarse.free_nodes[np.flatnonzero(active)]
    fine = np.rint(nodes * (chain.links / coarse.links)).astype(np.int64) - 1  # free index
    held[np.clip(fine, 0, held.size - 1)] = True
    return held


def nested_start(chain: Chain, solve: Callable[[Chain], DriverOutput | None]
                 ) -> DriverStart | None:
    """A start for ``chain`` from ``solve(coarse chain)`` (the caller's solve at
    :data:`COARSE_LINKS` links), or None: no coarser chain, a coarse solve that did
    not converge, a shape that does not fit."""
    links = COARSE_LINKS
    if not links or chain.links < 4 * links:
        return None
    if np.any(np.cos(chain.rest_alpha) <= 0.0):  # links past the vertical (θ > 180°): the
        return None  # fine driver's own cold start says what it can do there
    if load_parameter(chain) >= MODERATE:  # a heavy chain: its height steps crawl at both
        return None  # sizes (:mod:`.heavy_driver`), a coarse solve would only add to it
    coarse = coarse_chain(chain, links)
    out = solve(coarse)
    if out is None or not out.converged:
        return None
    return interpolated_start(chain, coarse, out)
