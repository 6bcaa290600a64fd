"""Sensitivities against walls of any profile y = h(x) (issue 38, item 1; docs/design.md).

The answer of a profiled scene is the lagged-slope fixed point of
:mod:`lcpbench.model.profile`: α and the reactions unchanged by one more step. There
the box QP's KKT conditions are exactly those of the exact problem

    minimise E(u; p)  subject to  c_r(u; p) ≥ 0,
    c_r = s_r (h_r(x_k(u)) − u_k)   (s_r = +1 the upper wall h, −1 the lower wall l),

∇E − Σ_r λ_r ∇c_r = 0 with λ_r the vertical reaction of row r (μ_k or ν_k), so the
fixed point's derivative is that of this KKT point (the lag changes how the iteration
gets there, not where it stops). On the active rows A, differentiating in p:

    [ W    −Gᵀ ] [du]   [ −(∂_p∇E − Σ_r λ_r ∂_p∇c_r) ]
    [ −G    0  ] [dλ] = [ ∂_p c_r                     ]

with G the rows ∇c_rᵀ = s_r (h'_r J_x[k] − e_k) and

    W = H + T − Σ_r λ_r ∇²c_r,   ∇²c_r = s_r (h''_r J_x[k]ᵀ J_x[k] + h'_r ∇²x_k),
    ∇²x_k = −Σ_{j<k} d_j d_jᵀ / (a cos³ α_j),   d_j = e_{j+1} − e_j:

the slope load J_xᵀ(μ ⊙ h') moves with x (its Jacobian: the h'' term, rank one per
row) and with α (the ∇²x term, tridiagonal). J_x (∂x_k/∂u_m = −Σ_{j<k} tan α_j
∂Δ_j/∂u_m) is lower triangular and dense, so the system is dense: one LU of size
n + |A|, O(N³) (0.5–3 ms at N = 140); refused above :data:`MAX_LINKS`.

∂_p∇E for θ, EI and w is the flat walls' (the energy does not see the walls). The
walls' own parameters: ``height_mm`` moves both walls apart, h(x) + δ and, in a
channel, l(x) − δ (∂_p c_r = 1, ∂_p∇c_r = 0); ``length_mm`` at a fixed wall follows
from dimensional analysis with the walls scaled along: a force is λ⁻² F(w λ³) when
ℓ, h(·) and l(·) all scale by λ (h_λ(x) = λ h(x/λ), whose derivative at λ = 1 is the
perturbation δh = h − x h', δh' = −x h''), so ℓ ∂F/∂ℓ = −2F + 3w F_w − D_δh F
(a height: u + 3w u_w − D_δh u). The walls are evaluated as the solve evaluates them,
through their tables of cubic pieces (:meth:`WallProfile.pieces`,
:func:`lcpbench.model.wall_kernel.wall_height`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..errors import ProblemError
from .chain import joint_angles, node_positions
from .newton import geometric_bands
from .step import assemble_step

#: the largest N whose profile sensitivities are computed (the dense system: O(N²)
#: memory, O(N³) time; 2000 links take ~1 s)
MAX_LINKS = 2000
#: the parameters covered on a profiled wall
OF_PROFILE = ("theta_deg", "height_mm", "EI", "weight", "length_mm")


def _walls(chain, x: np.ndarray):
    """(h, h', h'') of the upper and the lower wall at the free nodes' x, as the solve
    evaluates them (tables of cubic pieces, continued flat; a function without a table:
    itself); zeros for a wall without a profile."""
    from ..numba_cache import kernel_module

    kern = kernel_module("lcpbench.model.wall_kernel", "wall_height")
    out = []
    for prof in (chain.upper_profile, chain.lower_profile):
        if prof is None:
            out.append((np.zeros_like(x),) * 3)
            continue
        table = prof.pieces(-float(chain.length), float(chain.length))
        if table is None:
            out.append((prof(x), prof.slope(x), prof.curvature(x)))
            continue
        knots, coef = table
        vals = np.array([kern.wall_height(knots, coef, float(t)) for t in x]).reshape(-1, 3)
        out.append((vals[:, 0], vals[:, 1], vals[:, 2]))
    return out


def _dense(bands: np.ndarray) -> np.ndarray:
    """A symmetric matrix from its lower banded storage (k, n)."""
    n = bands.shape[1]
    M = np.diag(bands[0]).astype(float)
    for k in range(1, bands.shape[0]):
        off = np.diag(bands[k, : n - k], -k)
        M += off + off.T
    return M


def profile_derivatives(result, scene, names, eps_R: float) -> dict:
    """{parameter: (d forces_upper, d forces_lower, d heights)} of a converged answer
    against a profiled wall (module docstring), with ``_one_sided`` and ``_heights``."""
    chain = scene.chain()
    if chain.links > MAX_LINKS:
        raise ProblemError(f"sensitivities against a wall profile are computed up to "
                           f"N = {MAX_LINKS} links (a dense system); got N = {chain.links}. "
                           "Flat walls and rows of sections have them at any N")
    alpha = np.asarray(result.alpha, dtype=float)
    free = chain.free_nodes
    n, links, a = free.size, chain.links, chain.link_length
    x_all, y_all = node_positions(chain, alpha)
    x, u = x_all[free], y_all[free]
    (hu, hu1, hu2), (hl, hl1, hl2) = _walls(chain, x)
    fu = np.asarray(result.forces, dtype=float)
    fl = np.zeros(n) if result.forces_lower is None else np.asarray(result.forces_lower, float)
    up = (fu > eps_R) & np.isfinite(chain.upper)
    down = (fl > eps_R) & np.isfinite(chain.lower) & ~up
    # the rows: node, side s, slope, curvature, multiplier λ, the wall's height there
    node = np.concatenate([np.flatnonzero(up), np.flatnonzero(down)])
    side = np.concatenate([np.ones(up.sum()), -np.ones(down.sum())])
    slope = np.concatenate([hu1[up], hl1[down]])
    curv = np.concatenate([hu2[up], hl2[down]])
    lam = np.concatenate([fu[up], fl[down]])
    m = node.size
    # J_x on the free nodes: x_k = Σ_{j<k} a cos α_j, ∂x_k/∂Δ_j = −tan α_j, and link j's
    # Δ_j = y_{j+1} − y_j (d_j: +1 at node j+1, −1 at node j; the pins are fixed)
    col = np.full(links + 1, -1)
    col[free] = np.arange(n)
    D = np.zeros((links, n))
    j = np.arange(links)
    for end, sign in ((j + 1, 1.0), (j, -1.0)):
        ok = col[end] >= 0
        D[j[ok], col[end[ok]]] = sign
    G_links = -np.tan(alpha)[:, None] * D
    Jx = np.vstack([np.zeros((1, n)), np.cumsum(G_links, axis=0)])[free]  # rows: nodes k
    # W = H + T − Σ λ_r ∇²c_r
    step = assemble_step(chain, alpha)
    W = _dense(step.bands) + _dense(geometric_bands(chain, alpha))
    if m:
        rows_x = Jx[node]
        W -= rows_x.T @ ((lam * side * curv)[:, None] * rows_x)
        # Σ_r λ_r s_r h'_r ∇²x_k = Σ_j c_j d_j d_jᵀ, c_j = −Σ_{r: k_r > j} λ s h' / (a cos³ α_j)
        wk = np.zeros(links + 1)
        np.add.at(wk, free[node], lam * side * slope)
        past = np.cumsum(wk[::-1])[::-1][1:]  # link j: the rows at nodes > j
        c = -past / (a * np.cos(alpha) ** 3)
        W -= D.T @ (c[:, None] * D)
    Gm = side[:, None] * (slope[:, None] * Jx[node] - np.eye(n)[node])
    K = np.block([[W, -Gm.T], [-Gm, np.zeros((m, m))]])
    rhs_cols, tags = [], []
    phi = joint_angles(chain, alpha)
    for p in _needed(names):
        dgrad, dc, dgc = np.zeros(n), np.zeros(m), np.zeros(m)  # dgc: ∂_p of c_r's slope
        if p == "theta_deg":
            drest = chain.rest_joint / scene.theta
            dgrad = step._JT(chain.joint_stiffness * -drest)
        elif p == "EI":
            dgrad = step._JT(chain.joint_stiffness / scene.EI * (phi - chain.rest_joint))
        elif p == "weight":
            unit = (chain.nodal_load / scene.weight if scene.weight else
                    replace(scene, weight=1.0).chain().nodal_load)
            dgrad = -np.asarray(unit, float)
        elif p == "height_mm":
            dc = np.ones(m)
        elif p == "scale":  # the walls scaled about the pin: δh = h − x h', δh' = −x h''
            hgt = np.concatenate([hu[up], hl[down]])
            xr = x[node]
            dc = side * (hgt - xr * slope)
            dgc = -xr * curv
        # −(∂_p∇E − Σ λ_r ∂_p∇c_r), ∂_p∇c_r = s_r ∂_p h'_r J_x[k]
        top = -(dgrad - Jx[node].T @ (lam * side * dgc))
        rhs_cols.append(np.concatenate([top, dc]))
        tags.append(p)
    try:
        sol = np.linalg.solve(K, np.column_stack(rhs_cols))
    except np.linalg.LinAlgError:
        raise ProblemError("sensitivities: the KKT matrix at the answer's contact set is "
                           "singular (the contact set is not a stable one)") from None
    out = {}
    for i, p in enumerate(tags):
        du, dlam = sol[:n, i], sol[n:, i]
        dfu, dfl = np.zeros(n), np.zeros(n)
        dfu[node[side > 0]] = dlam[side > 0]
        dfl[node[side < 0]] = dlam[side < 0]
        out[p] = (dfu, dfl, du)
    if "length_mm" in names:
        out["length_mm"] = _length(result, scene, out, u)
    gap_u = np.where(np.isfinite(chain.upper), hu - u, np.inf)
    gap_l = np.where(np.isfinite(chain.lower), u - hl, np.inf)
    touching = (gap_u <= 1e-9 * scene.length) | (gap_l <= 1e-9 * scene.length)
    out["_one_sided"] = np.flatnonzero(touching & ~((fu > eps_R) | (fl > eps_R)))
    out["_heights"] = u
    return out


def _needed(names) -> list[str]:
    need = [p for p in OF_PROFILE if p in names and p != "length_mm"]
    if "length_mm" in names:
        need += [p for p in ("weight",) if p not in need] + ["scale"]
    return need


def _length(result, scene, d: dict, u: np.ndarray):
    """ℓ ∂/∂ℓ = −2F + 3w F_w − D_δh F (a height: u + 3w u_w − D_δh u)."""
    L, w = scene.length, scene.weight
    fu = np.asarray(result.forces, dtype=float)
    fl = np.zeros_like(fu) if result.forces_lower is None else np.asarray(result.forces_lower)
    (au, al, ah), (su, sl, sh) = d["weight"], d["scale"]
    return ((-2 * fu + 3 * w * au - su) / L, (-2 * fl + 3 * w * al - sl) / L,
            (u + 3 * w * ah - sh) / L)


__all__ = ["MAX_LINKS", "OF_PROFILE", "profile_derivatives"]
