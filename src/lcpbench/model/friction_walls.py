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


def walls_at_x(chain: Chain, x: np.ndarray):
    """(h, l, h', l') per free node: the upper and lower walls' heights (mm; ±inf: no
    row) and slopes at the nodes' x (``x``: every node's, mm, with the chain's
    translation). Flat walls: the chain's rows and slopes 0; a wall of any profile
    (:mod:`lcpbench.problems.walls`) evaluated at x (the rows stay the chain's)."""
    up, lo = chain.upper, chain.lower
    su = sl = np.zeros(up.size)
    xf = x[chain.free_nodes]
    if chain.upper_profile is not None:
        rows = np.isfinite(up)
        up = np.where(rows, chain.upper_profile(xf), np.inf)
        su = np.where(rows, chain.upper_profile.slope(xf), 0.0)
    if chain.lower_profile is not None:
        rows = np.isfinite(lo)
        lo = np.where(rows, chain.lower_profile(xf), -np.inf)
        sl = np.where(rows, chain.lower_profile.slope(xf), 0.0)
    return up, lo, su, sl


def gaps_at(chain: Chain, x: np.ndarray, y: np.ndarray, walls=None
            ) -> tuple[np.ndarray, np.ndarray]:
    """Exact vertical gaps of the free nodes to the upper and lower walls at the nodes'
    x (mm; inf: no wall): h(x) − y and y − l(x); ``walls``: :func:`walls_at_x` at x when
    known."""
    up, lo, _, _ = walls_at_x(chain, x) if walls is None else walls
    yf = y[chain.free_nodes]
    return up - yf, yf - lo


def near_walls(chain: Chain, x: np.ndarray, y: np.ndarray, band: float, walls=None
               ) -> np.ndarray:
    """Free nodes within ``band`` · a of a wall (or through it)."""
    g_up, g_lo = gaps_at(chain, x, y, walls)
    return np.minimum(g_up, g_lo) <= band * chain.link_length


def wall_frames(signs: np.ndarray, slope: np.ndarray) -> np.ndarray:
    """(n_x, n_y) per wall row: the unit normal in which its gap grows, (h', −1)/c at an
    upper wall (``signs`` −1) and (−l', 1)/c at a lower one, c = √(1 + slope²)."""
    c = np.sqrt(1.0 + slope * slope)
    return np.column_stack([-signs * slope / c, signs / c])


def tangential_slip(x, y, x_prev, y_prev, nodes, slope) -> np.ndarray:
    """s = t · (p − p_prev) at ``nodes``, t = (1, slope)/√(1 + slope²): the tangential
    increment of each node's displacement since the previous state (mm; x − x_prev on a
    flat wall, where ``y_prev`` may be None)."""
    dx = x[nodes] - x_prev[nodes]
    if y_prev is None:
        if np.any(slope):
            raise ProblemError("the slip along a sloped wall needs the previous state's "
                               "node heights (y_prev)")
        return dx
    return (dx + slope * (y[nodes] - y_prev[nodes])) / np.sqrt(1.0 + slope * slope)
