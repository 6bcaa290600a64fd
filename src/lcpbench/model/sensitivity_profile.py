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
∂Δ_j/∂u_m) is lower triangular and dense, but it is a running sum: with the nodes' dx
and the suffix sums of the slope loads lifted into the unknowns, the system is banded
(4 unknowns per node), and one banded LU solves it for every parameter at once, O(N)
whatever the number of contact nodes (compiled:
:mod:`lcpbench.model.sensitivity_profile_kernel`, where the lifted rows are written out).

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

import numpy as np

from ..errors import ProblemError
from .kernel_call import kernel_args
from .profile import wall_tables

#: the parameters covered on a profiled wall
OF_PROFILE = ("theta_deg", "height_mm", "EI", "weight", "length_mm")
#: the kernel's output row of each parameter (``scale``: the walls scaled about the pin)
_ROW = {"theta_deg": 0, "height_mm": 1, "EI": 2, "weight": 3, "scale": 4}


def profile_derivatives(result, scene, names, eps_R: float, rows) -> dict:
    """{parameter: (d forces_upper, d forces_lower, d heights)} of a converged answer
    against a profiled wall (module docstring), with ``_one_sided`` and ``_heights``;
    ``rows``: ∂φ*/∂θ per joint, ∂k/∂EI per joint and the nodal load at unit weight."""
    from ..numba_cache import kernel_module  # numba at the first sensitivity

    kern = kernel_module("lcpbench.model.sensitivity_profile_kernel", "derivatives")
    chain = scene.chain()
    _, a, jl, jr, k, rest, _, nodal_load, fs, lo, hi, L, _, _, _ = kernel_args(chain)
    tables = wall_tables(chain)
    if tables is None:  # (the plan refuses such a scene before it is solved)
        raise ProblemError("sensitivities: a wall profile without a table of cubic pieces "
                           "over the chain's reach; give it as a table "
                           "(WallProfile.from_table)")
    ku, cu, kl, cl = tables
    alpha = np.ascontiguousarray(result.alpha, dtype=float)
    n = lo.size
    fu = np.ascontiguousarray(result.forces, dtype=float)
    fl = np.zeros(n) if result.forces_lower is None else \
        np.ascontiguousarray(result.forces_lower, dtype=float)
    need = _needed(names)
    want = np.zeros(len(_ROW), bool)
    want[[_ROW[p] for p in need]] = True
    drest, dk, unit_load = rows
    code, du, dfu, dfl, u, one_sided = kern.derivatives(
        alpha, a, jl, jr, k, rest, fs, nodal_load, lo, hi, ku, cu, kl, cl, fu, fl,
        float(eps_R), drest, dk, unit_load, float(L), want)
    if code != kern.OK:
        raise ProblemError("sensitivities: the KKT matrix at the answer's contact set is "
                           "singular (the contact set is not a stable one)")
    out = {p: (dfu[_ROW[p]], dfl[_ROW[p]], du[_ROW[p]]) for p in need}
    if "length_mm" in names:
        out["length_mm"] = _length(result, scene, out, u)
    out["_one_sided"] = np.flatnonzero(one_sided)
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


__all__ = ["OF_PROFILE", "profile_derivatives"]
