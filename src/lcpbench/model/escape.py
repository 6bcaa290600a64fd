"""Escape from a saddle: the starts that leave an unstable equilibrium downhill.

The result judge refuses an answer whose energy has negative curvature on its
contact set (check "stability", :mod:`lcpbench.model.stability_kernel`). Such an
answer satisfies every first-order condition, so the driver, started there,
stays there. This module gives the directions to leave it by: the eigenvectors of
the reduced Hessian of the Lagrangian with negative eigenvalues, on the tangent
space of the nodes held by a wall and of the closure (Z, an orthonormal basis of
the null space of their rows ∇y_q = (a cos α_i)_{i<q}).

Along such a direction d the energy falls by ½ t² dᵀHd to second order; the
walls and the closure move by O(t²) only, which the driver's next contact step
takes back. :func:`escape_starts` returns α ± t d for each negative direction,
with t the largest of a few trial lengths whose exact energy, with the reactions'
work, is below the saddle's: the driver restarts from each, and the judge decides
as for every answer.

Dense (the null space and the eigenvectors), so up to :data:`MAX_LINKS` links:
the check is O(N), the escape only runs where the check refused an answer.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import eigh, null_space

from ..problems.scenes import Chain
from .chain import energy, node_positions

#: the escape's dense eigenproblem is taken up to this many links
MAX_LINKS = 2000
#: trial step lengths: the largest link-angle change along d (rad)
TRIALS = (0.5, 0.2, 0.05, 0.01)


def negative_directions(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
                        forces_lower: np.ndarray, threshold: float) -> list[np.ndarray]:
    """Unit directions in α of negative curvature on the contact set, most negative first.

    The Hessian is the one the judge's check counts with
    (:func:`lcpbench.model.stability_kernel.lagrangian_hessian`), with the held nodes'
    wall curvatures and the elastic walls' springs as rank-one terms in α."""
    from .judge import stability_args

    if chain.links > MAX_LINKS:
        return []
    kern, args = stability_args(chain, alpha, forces_upper, forces_lower)
    (alpha_, a, jl, jr, k, rest, load, first, fu, fl, ku, kl, su, sl, cu, cl) = args
    pinned = bool(chain.free_nodes[-1] < chain.links)
    diag, off, ok = kern.lagrangian_hessian(alpha_, a * np.cos(alpha_), a * np.sin(alpha_),
                                            jl, jr, k, rest, load, first, fu, fl, su, sl,
                                            pinned)
    if not ok:
        return []
    H = np.diag(diag) + np.diag(off, 1) + np.diag(off, -1)
    left_of = np.arange(chain.links)[None, :] < np.asarray(chain.free_nodes)[:, None]
    dy = np.where(left_of, a * np.cos(alpha), 0.0)  # ∇y_q, a row per free node
    dx = np.where(left_of, -a * np.sin(alpha), 0.0)  # ∇x_q
    rows = []
    for i in range(len(fu)):
        for R, ks, slope, curv, sign in ((fu[i], ku[i], su[i], cu[i], -1.0),
                                         (fl[i], kl[i], sl[i], cl[i], 1.0)):
            if not R > threshold:
                continue
            H += sign * R * curv * np.outer(dx[i], dx[i])  # −R h'' above, +R' l'' below
            if np.isfinite(ks):
                H += ks * np.outer(dy[i], dy[i])
            else:
                rows.append(dy[i] - slope * dx[i])
    if pinned:
        rows.append(a * np.cos(alpha))
    Z = null_space(np.array(rows)) if rows else np.eye(chain.links)
    values, vectors = eigh(Z.T @ H @ Z)
    scale = max(float(np.max(np.abs(diag))), 1e-300)
    return [Z @ vectors[:, i] for i in range(values.size) if values[i] < -1e-12 * scale]


def escape_starts(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
                  forces_lower: np.ndarray, threshold: float) -> list[np.ndarray]:
    """Link angles to restart the driver from, downhill of the saddle ``alpha``: for
    each negative direction, both signs, the longest trial step that lowers the
    exact energy with the reactions' work (the Lagrangian)."""
    free = chain.free_nodes

    def lagrangian(a):  # E + Σ R (y − h(x)) + R' (l(x) − y)
        x, y = node_positions(chain, a)
        xf, yf = x[free], y[free]
        value = energy(chain, a) + float(np.dot(forces_upper - forces_lower, yf))
        if chain.upper_profile is not None:
            value -= float(np.dot(forces_upper, chain.upper_profile(xf)))
        if chain.lower_profile is not None:
            value += float(np.dot(forces_lower, chain.lower_profile(xf)))
        return value

    base = lagrangian(alpha)
    starts = []
    for d in negative_directions(chain, alpha, forces_upper, forces_lower, threshold):
        d = d / max(float(np.max(np.abs(d))), 1e-300)
        for sign in (1.0, -1.0):
            for t in TRIALS:
                trial = alpha + sign * t * d
                if lagrangian(trial) < base:
                    starts.append(trial)
                    break
    return starts
