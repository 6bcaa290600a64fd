"""The energy reference's wall rows for walls of any profile y = h(x).

:mod:`lcpbench.reference.energy` minimises the exact energy over the
link angles α subject to the wall rows g_r(α) ≥ 0. With a profile the row of
node k is

    g_r(α) = side_r · (h_r(x_k(α)) − y_k(α)),
    x_k = a Σ_{j<k} cos α_j,   y_k = a Σ_{j<k} sin α_j,

(h_r the upper wall's profile, side +1, or the lower wall's, side −1), with
the exact gradient

    ∂g_r/∂α_j = side_r · (−h'(x_k) a sin α_j − a cos α_j) [j < k]

and Hessian

    ∇²g_r = side_r · (h''(x_k) v vᵀ + diag((a sin α_j − h'(x_k) a cos α_j) [j < k])),
    v_j = −a sin α_j [j < k],

which is no longer diagonal (the h'' term is a rank-one block per row).
Nothing here calls the contact step or the driver.
"""

from __future__ import annotations

import numpy as np

from ..model.chain import node_positions
from ..problems.scenes import Chain


def _evaluate(chain: Chain, rows, x_nodes: np.ndarray):
    """Per row: h(x_k), h'(x_k), h''(x_k) of its wall (a flat row: its limit, 0, 0)."""
    h = rows.limit.astype(float).copy()
    d1 = np.zeros_like(h)
    d2 = np.zeros_like(h)
    for side, prof in ((1.0, chain.upper_profile), (-1.0, chain.lower_profile)):
        if prof is None:
            continue
        sel = rows.side == side
        xs = x_nodes[rows.node[sel]]
        h[sel] = prof(xs)
        d1[sel] = prof.slope(xs)
        d2[sel] = prof.curvature(xs)
    return h, d1, d2


def profile_walls(chain: Chain, alpha: np.ndarray, rows) -> tuple[np.ndarray, np.ndarray]:
    """The wall gaps g(α) (mm) and their Jacobian (mm/rad) with profiles."""
    x, y = node_positions(chain, alpha)
    h, d1, _ = _evaluate(chain, rows, x)
    a = chain.link_length
    g = rows.side * (h - y[rows.node])
    mask = rows.mask(chain)
    jac = rows.side[:, None] * mask * (-d1[:, None] * (a * np.sin(alpha))[None, :]
                                       - (a * np.cos(alpha))[None, :])
    return g, jac


def profile_wall_hessian(chain: Chain, alpha: np.ndarray, wall_multiplier: np.ndarray,
                         rows) -> np.ndarray:
    """Σ_r μ_r ∇²g_r (N·mm/rad²) with profiles (dense N × N)."""
    x, _ = node_positions(chain, alpha)
    _, d1, d2 = _evaluate(chain, rows, x)
    a = chain.link_length
    mask = rows.mask(chain)
    w = wall_multiplier * rows.side
    diag = (w[:, None] * mask * (a * np.sin(alpha)[None, :]
                                 - d1[:, None] * a * np.cos(alpha)[None, :])).sum(axis=0)
    v = mask * (-a * np.sin(alpha))[None, :]
    return np.diag(diag) + v.T @ ((w * d2)[:, None] * v)
