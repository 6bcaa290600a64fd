"""The walls of a frictional step in their own frame (issue 39, docs/friction.md).

Against a wall y = h(x) (a profile, :mod:`lcpbench.problems.walls`) the normal
reaction N acts along the wall's normal n = (h', −1)/√(1 + h'²) (upper wall; the
direction in which the gap grows) or (−l', 1)/√(1 + l'²) (lower), and the tangential
force T along its tangent t = (1, h')/√(1 + h'²); the slip is the tangential part of a
node's displacement since the previous state. Flat walls are the case h' = 0:
n = (0, ∓1), t = (1, 0), the slip x − x_prev. Used by the frictional step
(:mod:`lcpbench.model.friction_driver`) and its judge
(:mod:`lcpbench.model.friction_result`), at the nodes' x (with the chain's
translation): the slopes are lagged, fixed within a step.
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from ..problems.scenes import Chain

_OUTER: list = []  # the compiled outer step (model/friction_outer.py), once loaded


def outer_kernels():
    """The frictional outer step's and the walls' compiled functions
    (:mod:`lcpbench.model.friction_outer`), loaded once through
    :func:`lcpbench.numba_cache.kernel_module`."""
    if not _OUTER:
        from ..numba_cache import held, kernel_module

        held(_OUTER).append(kernel_module("lcpbench.model.friction_outer", "assemble"))
    return _OUTER[0]


def walls_at_x(chain: Chain, x: np.ndarray):
    """(h, l, h', l') per free node: the upper and lower walls' heights (mm; ±inf: no
    row) and slopes at the nodes' x (``x``: every node's, mm, with the chain's
    translation). Flat walls: the chain's rows and slopes 0; a wall of any profile
    read from its table of cubic pieces at x, as the step reads it
    (:func:`lcpbench.model.friction_outer.node_walls`; the rows stay the chain's)."""
    from .friction_driver import frictional_chain_args

    arrays = frictional_chain_args(chain)
    xf = np.ascontiguousarray(np.asarray(x, dtype=float)[chain.free_nodes])
    return outer_kernels().node_walls(xf, *arrays[5:11])


def gaps_at(chain: Chain, x: np.ndarray, y: np.ndarray, walls=None
            ) -> tuple[np.ndarray, np.ndarray]:
    """Exact vertical gaps of the free nodes to the upper and lower walls at the nodes'
    x (mm; inf: no wall): h(x) − y and y − l(x); ``walls``: :func:`walls_at_x` at x when
    known."""
    up, lo, _, _ = walls_at_x(chain, x) if walls is None else walls
    yf = y[chain.free_nodes]
    return up - yf, yf - lo


def wall_frames(signs: np.ndarray, slope: np.ndarray) -> np.ndarray:
    """(n_x, n_y) per wall row (:func:`lcpbench.model.friction_outer.wall_frames`)."""
    return outer_kernels().wall_frames(np.ascontiguousarray(signs, dtype=float),
                                       np.ascontiguousarray(slope, dtype=float))


def tangential_slip(x, y, x_prev, y_prev, nodes, slope) -> np.ndarray:
    """s = t · (p − p_prev) at ``nodes``, t = (1, slope)/√(1 + slope²): the tangential
    increment of each node's displacement since the previous state (mm; x − x_prev on a
    flat wall, where ``y_prev`` may be None;
    :func:`lcpbench.model.friction_outer.tangential_slip`)."""
    f64 = np.ascontiguousarray
    s, ok = outer_kernels().tangential_slip(
        f64(x, dtype=float), f64(y, dtype=float), f64(x_prev, dtype=float),
        np.zeros(0) if y_prev is None else f64(y_prev, dtype=float),
        f64(nodes, dtype=np.int64), f64(slope, dtype=float))
    if not ok:
        raise ProblemError("the slip along a sloped wall needs the previous state's "
                           "node heights (y_prev)")
    return s
