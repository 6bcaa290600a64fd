"""The walls of a frictional step in their own frame (issue 39, docs/friction.md), for
the judge (:mod:`lcpbench.model.friction_result`): the normal n = (h', −1)/√(1 + h'²)
(upper wall; (−l', 1)/√(1 + l'²) lower), the tangent t = (1, h')/√(1 + h'²) and the
slip t · (p − p_prev) at the nodes' x, read from the walls' tables as the step reads
them: the compiled functions of :mod:`lcpbench.model.friction_outer`, called here, on
the chain's arrays as those kernels take them (:func:`frictional_chain_args`).
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from ..problems.scenes import Chain
from .elastic import compliances

#: a state whose chain moves along x by more than RUNAWAY · ℓ has no equilibrium
RUNAWAY = 10.0

_OUTER: list = []  # the compiled outer step (model/friction_outer.py), once loaded


def outer_kernels():
    """The frictional outer step's and the walls' compiled functions
    (:mod:`lcpbench.model.friction_outer`), loaded once through
    :func:`lcpbench.numba_cache.kernel_module`."""
    if not _OUTER:
        from ..numba_cache import held, kernel_module

        held(_OUTER).append(kernel_module("lcpbench.model.friction_outer", "assemble"))
    return _OUTER[0]


def frictional_chain_args(chain: Chain) -> tuple:
    """The chain's arrays as :mod:`lcpbench.model.friction_outer` takes them, once per
    chain: joints, springs, rest angles, loads, the walls' rows and tables of cubic
    pieces (:meth:`~lcpbench.problems.walls.WallProfile.pieces` over the x a chain that
    runs away reaches; empty: flat; a profile without one refused) and compliances."""
    def make():
        f64 = np.ascontiguousarray
        L = float(chain.length)
        reach = (-(RUNAWAY + 1.0) * L, (RUNAWAY + 2.0) * L)
        tables = []
        for side, profile in (("upper", chain.upper_profile), ("lower", chain.lower_profile)):
            table = None if profile is None else profile.pieces(*reach)
            if profile is not None and table is None:
                raise ProblemError(f"wall_profile ({side} wall): the frictional step reads a "
                                   "wall as a table of cubic pieces, and this profile needs "
                                   "more of them than MAX_PIECES")
            tables += ([np.zeros(0), np.zeros((4, 0))] if table is None else
                       [f64(table[0], dtype=float), f64(table[1], dtype=float)])
        c_up, c_lo = compliances(chain)
        return (f64(chain.joint_links[:, 0], dtype=np.int64),
                f64(chain.joint_links[:, 1], dtype=np.int64),
                f64(chain.joint_stiffness, dtype=float), f64(chain.rest_joint, dtype=float),
                f64(chain.nodal_load, dtype=float), f64(chain.upper, dtype=float),
                f64(chain.lower, dtype=float), *tables, f64(c_up, dtype=float),
                f64(c_lo, dtype=float))
    return chain.derived("friction: kernel arrays", make)


def walls_at_x(chain: Chain, x: np.ndarray):
    """(h, l, h', l') per free node at every node's x ``x`` (mm; ±inf: no row):
    :func:`lcpbench.model.friction_outer.node_walls`."""
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
    """s = t · (p − p_prev) at ``nodes`` (mm; ``y_prev`` None on flat walls only):
    :func:`lcpbench.model.friction_outer.tangential_slip`."""
    f64 = np.ascontiguousarray
    s, ok = outer_kernels().tangential_slip(
        f64(x, dtype=float), f64(y, dtype=float), f64(x_prev, dtype=float),
        np.zeros(0) if y_prev is None else f64(y_prev, dtype=float),
        f64(nodes, dtype=np.int64), f64(slope, dtype=float))
    if not ok:
        raise ProblemError("the slip along a sloped wall needs the previous state's "
                           "node heights (y_prev)")
    return s
