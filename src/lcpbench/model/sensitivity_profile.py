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
∂Δ_j/∂u_m) is lower triangular and dense, but only the |A| rows of the active nodes
enter: with B = H + T − Σ_r λ_r s_r h'_r ∇²x_k (pentadiagonal) and U the active rows
of J_x, W = B − U diag(λ s h'') Uᵀ, so B⁻¹ on the right-hand sides, U and Gᵀ (banded
LU, O(N) each) leave a dense system of 2|A| unknowns (w = diag(λ s h'') Uᵀ du and dλ):
O(N |A|) in all; refused above :data:`MAX_ROWS` contact nodes.

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
from .profile import profile_gaps
from .step import assemble_step

#: the most contact nodes whose profile sensitivities are computed (the dense system of
#: twice their number; U and Gᵀ take N × their number)
MAX_ROWS = 2000
#: the parameters covered on a profiled wall
OF_PROFILE = ("theta_deg", "height_mm", "EI", "weight", "length_mm")


def _walls(chain, x: np.ndarray, lower: bool = False):
    """(h, h', h'') of the upper (``lower``: the lower) wall at ``x``, as the solve
    evaluates it (its table of cubic pieces, continued flat; a function without a
    table: itself)."""
    from ..numba_cache import kernel_module

    prof = chain.lower_profile if lower else chain.upper_profile
    if prof is None or x.size == 0:
        return (np.zeros_like(x),) * 3
    table = prof.pieces(-float(chain.length), float(chain.length))
    if table is None:
        return prof(x), prof.slope(x), prof.curvature(x)
    kern = kernel_module("lcpbench.model.wall_kernel", "wall_height")
    vals = np.array([kern.wall_height(*table, float(t)) for t in x]).reshape(-1, 3)
    return vals[:, 0], vals[:, 1], vals[:, 2]


def profile_derivatives(result, scene, names, eps_R: float) -> dict:
    """{parameter: (d forces_upper, d forces_lower, d heights)} of a converged answer
    against a profiled wall (module docstring), with ``_one_sided`` and ``_heights``."""
    from scipy.linalg import solve_banded

    chain = scene.chain()
    alpha = np.asarray(result.alpha, dtype=float)
    free = chain.free_nodes
    n, links, a = free.size, chain.links, chain.link_length
    x_all, y_all = node_positions(chain, alpha)
    x, u = x_all[free], y_all[free]
    fu = np.asarray(result.forces, dtype=float)
    fl = np.zeros(n) if result.forces_lower is None else np.asarray(result.forces_lower, float)
    up = (fu > eps_R) & np.isfinite(chain.upper)
    down = (fl > eps_R) & np.isfinite(chain.lower) & ~up
    # the rows: node, side s, the wall's height, slope and curvature there, multiplier λ
    node = np.concatenate([np.flatnonzero(up), np.flatnonzero(down)])
    side = np.concatenate([np.ones(up.sum()), -np.ones(down.sum())])
    (hu, hu1, hu2), (hl, hl1, hl2) = _walls(chain, x[up]), _walls(chain, x[down], lower=True)
    hgt, slope, curv = (np.concatenate(pair) for pair in ((hu, hl), (hu1, hl1), (hu2, hl2)))
    lam = np.concatenate([fu[up], fl[down]])
    m = node.size
    if m > MAX_ROWS:
        raise ProblemError(f"sensitivities against a wall profile are computed with up to "
                           f"{MAX_ROWS} contact nodes (a dense system of twice as many); "
                           f"this answer has {m}. Flat walls and rows of sections have them "
                           "at any number")
    # U: the rows ∇x_k of the active nodes (n × m); x_k = Σ_{j<k} a cos α_j, so
    # ∂x_k/∂u_i = t_{i−1} − t_i with t_j = −tan α_j for the links j < k (else 0)
    k_full = free[node]
    t = np.where(np.arange(links)[None, :] < k_full[:, None], -np.tan(alpha)[None, :], 0.0)
    U = (t[:, free - 1] - np.where(free < links, t[:, np.minimum(free, links - 1)], 0.0)).T
    # B = H + T − Σ_r λ_r s_r h'_r ∇²x_k (pentadiagonal): ∇²x_k = −Σ_{j<k} d_j d_jᵀ /
    # (a cos³ α_j), so the sum is Σ_j c_j d_j d_jᵀ with c_j the rows past link j
    step = assemble_step(chain, alpha)
    low = step.bands + geometric_bands(chain, alpha)
    wk = np.zeros(links + 1)
    np.add.at(wk, k_full, lam * side * slope)
    c = -np.cumsum(wk[::-1])[::-1][1:] / (a * np.cos(alpha) ** 3)
    cn = np.zeros(links + 2)  # (link j joins nodes j, j + 1; −c on the diagonal of both)
    cn[:links] += c
    cn[1:links + 1] += c
    low[0] -= cn[free]
    low[1, : n - 1] += c[free[:-1]]
    ab = np.zeros((5, n))  # solve_banded's storage of the symmetric B
    ab[2] = low[0]
    ab[3, : n - 1] = ab[1, 1:] = low[1, : n - 1]
    ab[4, : n - 2] = ab[0, 2:] = low[2, : n - 2]
    # G: the rows ∇c_rᵀ = s_r (h'_r ∇x_k − e_k); W = B − U diag(β) Uᵀ, β = λ s h''
    E = np.zeros((n, m))
    E[node, np.arange(m)] = 1.0
    Gt = (U * slope - E) * side  # Gᵀ (n × m)
    beta = lam * side * curv
    rhs_cols, dcs, tags = [], [], []
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
            xr = x[node]
            dc = side * (hgt - xr * slope)
            dgc = -xr * curv
        # −(∂_p∇E − Σ λ_r ∂_p∇c_r), ∂_p∇c_r = s_r ∂_p h'_r ∇x_k
        rhs_cols.append(-(dgrad - U @ (lam * side * dgc)))
        dcs.append(dc)
        tags.append(p)
    # B⁻¹ on the right-hand sides, U and Gᵀ (banded, O(N) each), then the 2m × 2m system
    # in (w = β Uᵀ du, dλ): du = X + Z w + Q dλ
    try:
        sol = solve_banded((2, 2), ab, np.column_stack([*rhs_cols, U, Gt]),
                           check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        sol = None
    if sol is None or not np.all(np.isfinite(sol)):
        raise ProblemError("sensitivities: the Hessian at the answer's contact set is "
                           "singular (the contact set is not a stable one)")
    P = len(tags)
    X, Z, Q = sol[:, :P], sol[:, P:P + m], sol[:, P + m:]
    bU = beta[:, None] * U.T
    S = np.block([[np.eye(m) - bU @ Z, -bU @ Q], [Gt.T @ Z, Gt.T @ Q]])
    R = np.vstack([bU @ X, -np.column_stack(dcs) - Gt.T @ X]) if m else np.zeros((0, P))
    try:
        wl = np.linalg.solve(S, R) if m else np.zeros((0, P))
    except np.linalg.LinAlgError:
        raise ProblemError("sensitivities: the KKT matrix at the answer's contact set is "
                           "singular (the contact set is not a stable one)") from None
    dU = X + Z @ wl[:m] + Q @ wl[m:]
    out = {}
    for i, p in enumerate(tags):
        dlam = wl[m:, i]
        dfu, dfl = np.zeros(n), np.zeros(n)
        dfu[node[side > 0]] = dlam[side > 0]
        dfl[node[side < 0]] = dlam[side < 0]
        out[p] = (dfu, dfl, dU[:, i])
    if "length_mm" in names:
        out["length_mm"] = _length(result, scene, out, u)
    gap_u, gap_l = profile_gaps(chain, alpha)
    gap_u = np.where(np.isfinite(chain.upper), gap_u, np.inf)
    gap_l = np.full(n, np.inf) if gap_l is None else np.where(np.isfinite(chain.lower),
                                                               gap_l, np.inf)
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


__all__ = ["MAX_ROWS", "OF_PROFILE", "profile_derivatives"]
