"""Independent checks of an answer by central differences of the exact energy.

Nothing here calls lcpbench's contact step, driver, judge or stability kernel: only
the exact energy (:func:`lcpbench.model.chain.energy`) and the forward kinematics
(:func:`lcpbench.model.chain.node_positions`), differenced numerically.
"""

import numpy as np
import scipy.linalg as sl

from lcpbench.model.chain import energy, node_positions


def _gradient(fun, a, h):
    """Central differences of ``fun`` at ``a`` (step ``h`` rad)."""
    g = np.zeros(a.size)
    for i in range(a.size):
        e = np.zeros(a.size)
        e[i] = h
        g[i] = (fun(a + e) - fun(a - e)) / (2 * h)
    return g


def fd_kkt_residual(chain, alpha, fu, fl, h=1e-6):
    """First order: max |∇_α (E + Σ (R_q − R'_q) y_q + λ y_N)| over the link angles, with
    λ by least squares, relative to the largest term (N·mm per rad)."""
    free = chain.free_nodes

    def heights(a):
        return node_positions(chain, a)[1]

    def grad(fun, a):
        return _gradient(fun, a, h)

    gE = grad(lambda a: energy(chain, a), alpha)
    gR = grad(lambda a: float(np.dot(fu - fl, heights(a)[free])), alpha)
    g = gE + gR
    if free[-1] < chain.links:
        gN = grad(lambda a: heights(a)[-1], alpha)
        g = g - (g @ gN) / (gN @ gN) * gN
    return float(np.max(np.abs(g)) / max(np.max(np.abs(gE)), np.max(np.abs(gR)), 1e-300))


def _walls_term(chain, fu, fl):
    """Σ R (y − h(x)) + R' (l(x) − y) over the free nodes, as a function of α."""
    free = chain.free_nodes

    def term(a):
        x, y = node_positions(chain, a)
        xf, yf = x[free], y[free]
        up = chain.upper_profile(xf) if chain.upper_profile is not None else 0.0
        lo = chain.lower_profile(xf) if chain.lower_profile is not None else 0.0
        return float(np.sum(fu * (yf - up)) + np.sum(fl * (lo - yf)))
    return term


def fd_unstable_directions(chain, alpha, fu, fl, threshold, h=1e-5):
    """Negative curvature directions of the Lagrangian on the contact set, all by
    central differences of the exact energy, node positions and wall profiles."""
    n = alpha.size
    free = chain.free_nodes

    def grad(fun, a):
        return _gradient(fun, a, h)

    walls = _walls_term(chain, fu, fl)

    def L0(a):
        return energy(chain, a) + walls(a)

    rows = []
    for j, (up, lo) in enumerate(zip(fu, fl)):
        if max(up, lo) <= threshold:
            continue
        one_up = np.zeros_like(fu)
        one_lo = np.zeros_like(fl)
        (one_up if up >= lo else one_lo)[j] = 1.0
        rows.append(grad(_walls_term(chain, one_up, one_lo), alpha))
    lam = 0.0

    def yN(a):
        return node_positions(chain, a)[1][-1]

    if free[-1] < chain.links:  # the right pin's closure y_N = 0
        gN = grad(yN, alpha)
        lam = -float(grad(L0, alpha) @ gN) / float(gN @ gN)
        rows.append(gN)

    def L(a):
        return L0(a) + lam * yN(a)

    H = np.zeros((n, n))
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        H[:, i] = (grad(L, alpha + e) - grad(L, alpha - e)) / (2 * h)
    H = 0.5 * (H + H.T)
    Z = sl.null_space(np.array(rows))
    values = np.linalg.eigvalsh(Z.T @ H @ Z)
    # a finite-difference Hessian is good to ~1e-4 here: only clear signs count
    assert np.min(np.abs(values)) > 1e-3 * np.max(np.abs(values))
    return int(np.sum(values < 0))
