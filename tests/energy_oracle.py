"""Independent checks of an answer by central differences of the exact energy.

Nothing here calls lcpbench's contact step, driver, judge or stability kernel: only
the exact energy (:func:`lcpbench.model.chain.energy`) and the forward kinematics
(:func:`lcpbench.model.chain.node_positions`), differenced numerically, and, for one
contact step, its matrix and load (``step.bands``, ``step.linear``) with the KKT
conditions written out here. :func:`energy_minimum` is the direct minimisation of the
exact energy (:func:`lcpbench.reference.energy.minimise_energy`, SLSQP and a
Newton polish on the KKT system; no contact step, driver or judge), cached per scene.
Which tests use which oracle: docs/testing.md.
"""

from functools import lru_cache

import numpy as np
import scipy.linalg as sl

from lcpbench.model.chain import energy, node_positions
from lcpbench.reference.energy import minimise_energy


@lru_cache(maxsize=64)
def energy_minimum(scene):
    """The scene's equilibrium by direct minimisation of its exact energy (SLSQP, then
    Newton on the KKT system of its active set): asserted successful, cached per scene
    (scenes are frozen dataclasses). On the paper's scenes at N <= 140 it takes ~0.3 s
    and agrees with a converged contact-step answer to ~1e-10 of EI/ℓ² or the force."""
    ref = minimise_energy(scene)
    assert ref.success, ref.message
    return ref


def force_unit(scene, force):
    """F₀ = max(|F|, EI/ℓ²): the success rule's force unit (N)."""
    return max(abs(force), scene.EI / scene.length**2)


def _gradient(fun, a, h):
    """Central differences of ``fun`` at ``a`` (step ``h`` rad)."""
    g = np.zeros(a.size)
    for i in range(a.size):
        e = np.zeros(a.size)
        e[i] = h
        g[i] = (fun(a + e) - fun(a - e)) / (2 * h)
    return g


def fd_kkt_residual(chain, alpha, fu, fl, h=1e-6, floor=1e-300):
    """First order: max |∇_α (E + Σ (R_q − R'_q) y_q + λ y_N)| over the link angles, with
    λ by least squares, relative to the largest term (N·mm per rad) or ``floor`` if
    larger (a weightless chain at rest on a grazing wall has no term of any size)."""
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
    return float(np.max(np.abs(g)) / max(np.max(np.abs(gE)), np.max(np.abs(gR)), floor))


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


def assert_equilibrium(scene, alpha, forces, forces_lower=None, *, stationarity=1e-6,
                       wall_tol=1e-9, sign_tol=1e-12):
    """An answer of a scene with flat walls (rigid or elastic) is its equilibrium, checked
    from first principles: the node heights by forward kinematics, the walls and the
    right pin from the scene's chain, the reactions' signs and complementarity (rigid:
    R > 0 only on the wall; elastic: R = k (y − h)₊, the Winkler law), and stationarity
    of E + Σ R y by central differences of the exact energy (:func:`fd_kkt_residual`,
    relative to its largest term or EI/ℓ; about the outer tolerance of a converged answer). Lengths relative to the span ℓ, forces to EI/ℓ²
    (or the largest reaction, if larger)."""
    chain = scene.chain()
    assert chain.upper_profile is None and chain.lower_profile is None, "flat walls only"
    fu = np.asarray(forces, dtype=float)
    fl = np.zeros_like(fu) if forces_lower is None else np.asarray(forces_lower, dtype=float)
    y = node_positions(chain, np.asarray(alpha, dtype=float))[1]
    yf = y[chain.free_nodes]
    ell = chain.length
    f0 = max(chain.force_scale, float(np.max(fu, initial=0.0)), float(np.max(fl, initial=0.0)))
    if chain.free_nodes[-1] < chain.links:  # the right pin: y_N = 0
        assert abs(y[-1]) <= wall_tol * ell, ("closure", y[-1])
    assert np.min(fu, initial=0.0) >= -sign_tol * f0 and np.min(fl, initial=0.0) >= -sign_tol * f0
    for R, over, k in ((fu, yf - chain.upper, chain.upper_stiffness),
                       (fl, chain.lower - yf, chain.lower_stiffness)):
        wall = np.isfinite(over)
        assert not np.any(R[~wall] > sign_tol * f0), "a reaction where no wall is"
        if k is None or not np.all(np.isfinite(k[wall])):  # rigid: y <= h, R (h − y) = 0
            assert np.max(over[wall], initial=-np.inf) <= wall_tol * ell, "a wall crossed"
            apart = over[wall] < -wall_tol * ell
            assert np.max(R[wall][apart], initial=0.0) <= sign_tol * f0, "a reaction off the wall"
        else:  # the Winkler law R = k (y − h)₊
            law = k[wall] * np.maximum(over[wall], 0.0)
            assert np.max(np.abs(R[wall] - law), initial=0.0) <= wall_tol * f0, "R ≠ k (y − h)₊"
    # (elastic walls: the exact energy holds the springs' Σ ½ k δ², their reactions' work)
    spring = chain.elastic_walls
    residual = fd_kkt_residual(chain, np.asarray(alpha, dtype=float),
                               0 * fu if spring else fu, 0 * fl if spring else fl,
                               floor=chain.force_scale * chain.length)  # EI/ℓ
    assert residual <= stationarity, ("stationarity", residual)


def assert_solved(res, *, stationarity=None, wall_tol=1e-9, sign_tol=1e-12):
    """:func:`assert_equilibrium` on a converged result of :func:`lcpbench.solve` (or a
    batch's), stationary to ``stationarity`` (default: 10 tol, at least 1e-6: the outer
    loop stops on max|Δα| < tol, which leaves a gradient of about that size)."""
    assert res.converged, res.reason
    if stationarity is None:
        stationarity = max(10 * res.tol, 1e-6)
    assert_equilibrium(res.scene, res.alpha, res.forces, res.forces_lower,
                       stationarity=stationarity, wall_tol=wall_tol, sign_tol=sign_tol)


def _dense_hessian(step):
    """The step's symmetric banded H (``step.bands``: diagonal, then each band below) as
    a dense matrix."""
    b = step.bands
    n = step.linear.size
    H = np.diag(b[0, :n])
    for k in range(1, b.shape[0]):
        H += np.diag(b[k, : n - k], k) + np.diag(b[k, : n - k], -k)
    return H


def assert_step_kkt(step, u, *, rtol=1e-9, gap_tol=1e-12):
    """Heights ``u`` solve a contact step (minimise ½ uᵀHu + fᵀu, lower <= u <= upper,
    H from ``step.bands``, f = ``step.linear``), checked by its KKT conditions written
    out here: feasible, the gradient g = H u + f zero on free rows, g <= 0 where the
    upper wall holds the node and g >= 0 where the lower one does; g relative to the
    size of its terms |H| |u| + |f|, lengths relative to 1 + max|u|. Returns −g, the
    net reactions at u (N)."""
    H, f = _dense_hessian(step), step.linear
    u = np.asarray(u, dtype=float)
    g = H @ u + f
    size = np.abs(H) @ np.abs(u) + np.abs(f)
    span = gap_tol * (1.0 + np.max(np.abs(u)))
    assert np.all(u <= step.upper + span) and np.all(u >= step.lower - span), "infeasible"
    up, lo = u >= step.upper - span, u <= step.lower + span
    free = ~(up | lo)
    assert np.all(np.abs(g[free]) <= rtol * size[free]), "not stationary on a free row"
    assert np.all(g[up & ~lo] <= rtol * size[up & ~lo]), "the upper wall pulls"
    assert np.all(g[lo & ~up] >= -rtol * size[lo & ~up]), "the lower wall pulls"
    return -g  # the net reactions R_upper − R_lower the walls exert at u


def assert_elastic_step_kkt(step, u, *, rtol=1e-9):
    """Heights ``u`` solve a contact step with elastic walls (Winkler springs): they
    minimise ½ uᵀHu + fᵀu + Σ ½ k (u − upper)₊² + Σ ½ k' (lower − u)₊², strictly convex,
    so its stationarity decides the answer: H u + f + k (u − upper)₊ − k' (lower − u)₊ = 0
    on every row, relative to the size of its terms (H and f from ``step.bands`` and
    ``step.linear``, k and k' from ``step.upper_stiffness`` and ``step.lower_stiffness``;
    a wall of infinite k is not elastic and is left to :func:`assert_step_kkt`)."""
    H, f = _dense_hessian(step), step.linear
    n = f.size
    u = np.asarray(u, dtype=float)

    def springs(k, pressed):
        k = np.full(n, np.inf) if k is None else np.asarray(k, dtype=float)
        soft = np.isfinite(k)
        assert soft.any() or not np.any(pressed > 0), "a rigid wall crossed"
        return np.where(soft, np.where(soft, k, 0.0) * pressed, 0.0)

    with np.errstate(invalid="ignore"):
        up = springs(step.upper_stiffness, np.nan_to_num(np.maximum(u - step.upper, 0.0)))
        lo = springs(step.lower_stiffness, np.nan_to_num(np.maximum(step.lower - u, 0.0)))
    g = H @ u + f + up - lo
    size = np.abs(H) @ np.abs(u) + np.abs(f) + up + lo
    assert np.all(np.abs(g) <= rtol * size), ("not stationary", float(np.max(np.abs(g) / size)))
    return up, lo
