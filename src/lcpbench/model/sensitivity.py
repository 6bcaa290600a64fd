"""Sensitivities of a converged answer by implicit differentiation (issue 38, item 1).

At an equilibrium whose contact set is stable, the free nodes' heights u and the
wall reactions R satisfy, with E(u; p) the exact energy in the heights and p a
parameter of the scene,

    ∇_u E(u; p) + R = 0,    u_i = h_i (i held by a rigid wall),
    R_i = k_i (u_i − h_i) (i held by an elastic wall),    R_i = 0 (i free).

Differentiating in p at the answer: (H + T) du = −∂_p∇E − dR, du_i = dh_i on the
rigid rows, dR_i = k_i (du_i − dh_i) + ∂_p k_i (u_i − h_i) on the elastic ones and
dR_i = 0 on the free ones, where H + T is the exact Hessian of E in the heights (the
Newton step's, :mod:`lcpbench.model.newton`). It is one face solve of the walk's
banded LDLᵀ (:func:`lcpbench.linalg.ldl_kernel.refactor`, compiled, the elastic rows in
its compliance form), O(N): du = du₀ − (H + T)_face⁻¹ r with du₀ = dh on the held
nodes and r = ∂_p∇E + (H + T) du₀ (+ ∂_p k (u − h) at an elastic wall) off the rigid
rows; then dR = −(∂_p∇E + (H + T) du) on the held nodes.

∂_p∇E is exact: the energy's gradient Jᵀ k (φ − φ*) − f is linear in the joint
stiffness k = EI/a, the rest angles φ* = −θ/N and the loads f ∝ w. The length ℓ
enters everywhere (a = ℓ/N); its derivative follows from dimensional analysis,
exact for the discrete chain at fixed N: a force is (EI/ℓ²) Φ(θ, h/ℓ, wℓ³/EI,
kℓ⁴/EI), so ℓ ∂F/∂ℓ = −2F − h F_h + 3w F_w + 4k F_k (a height: u − h u_h + 3w u_w
+ 4k u_k).

Where a node is at a change of contact set (reaction at most ε_R and gap at most
the judge's penetration allowance: touching without force) the derivative is
one-sided: it is taken with that node free (the side where it leaves the wall), and
``one_sided`` lists the node. Actuator scenes with flat walls (one wall or a
channel, rigid or elastic) are covered; sections, wall profiles and the cantilever
are refused with a ProblemError.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ProblemError
from ..problems.scenes import ActuatorScene, wall_share
from .chain import heights
from .elastic import compliances
from .newton import geometric_bands
from .step import assemble_step

#: the parameters (and their units) a sensitivity is taken with respect to
PARAMETERS = {"theta_deg": "deg", "height_mm": "mm", "EI": "N mm²", "weight": "N/mm",
              "length_mm": "mm", "wall_stiffness": "N/mm²"}


@dataclass
class Sensitivities:
    """Derivatives of a result's outputs with respect to the scene's parameters.

    Each dict maps a parameter name of :data:`PARAMETERS` to the derivative, in the
    output's unit per the parameter's unit: ``total_force`` (N per …), ``forces``
    and ``forces_lower`` (per free node, N per …), ``heights`` (per free node, mm
    per …), ``peak_pressure`` (the largest contact pressure per length, N/mm per
    …). ``one_sided``: the free nodes (0-based indices into the per-node arrays)
    at a change of contact set, whose derivatives are one-sided (the node leaving
    the wall); empty where the contact set is stable and every derivative exact.
    """

    wrt: tuple[str, ...]
    total_force: dict[str, float]
    forces: dict[str, np.ndarray]
    forces_lower: dict[str, np.ndarray] | None
    heights: dict[str, np.ndarray]
    peak_pressure: dict[str, float]
    one_sided: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    def as_json(self) -> dict:
        """The derivatives as JSON-ready dicts (lists for the per-node ones)."""
        out = {"total_force": dict(self.total_force), "peak_pressure": dict(self.peak_pressure),
               "forces": {k: v.tolist() for k, v in self.forces.items()},
               "heights": {k: v.tolist() for k, v in self.heights.items()},
               "units": {k: PARAMETERS[k] for k in self.wrt},
               "one_sided_nodes": self.one_sided.tolist()}
        if self.forces_lower is not None:
            out["forces_lower"] = {k: v.tolist() for k, v in self.forces_lower.items()}
        return out


def unsupported(scene) -> str | None:
    """Why :func:`sensitivities` does not cover ``scene``, or None."""
    if isinstance(scene, ActuatorScene) and scene.wall_profile is None:
        return None
    what = "a wall profile" if isinstance(scene, ActuatorScene) else type(scene).__name__
    return ("sensitivities cover actuator scenes with flat walls (one wall or a channel, "
            f"rigid or elastic); got {what}")


def sensitivities(result, wrt=None) -> Sensitivities:
    """The derivatives of ``result``'s total force, node forces, node heights and peak
    contact pressure with respect to the parameters ``wrt`` (names of
    :data:`PARAMETERS`; default: all that apply, ``wall_stiffness`` for elastic walls
    only), by implicit differentiation at its contact set (module docstring)."""
    scene = result.scene
    if (why := unsupported(scene)) is not None:
        raise ProblemError(why)
    if not result.converged:
        raise ProblemError("sensitivities need a converged result (result.converged is False: "
                           f"{result.reason})")
    elastic = not math.isinf(scene.wall_stiffness)
    names = tuple(p for p in PARAMETERS if elastic or p != "wall_stiffness") if wrt is None \
        else tuple(wrt)
    for p in names:
        if p not in PARAMETERS or (p == "wall_stiffness" and not elastic):
            allowed = ", ".join(q for q in PARAMETERS if elastic or q != "wall_stiffness")
            raise ProblemError(f"wrt must name parameters among {allowed}; got {p!r}")
    need = {p for p in names if p != "length_mm"}
    if "length_mm" in names:  # from the others, by dimensional analysis
        need |= {"height_mm", "weight"} | ({"wall_stiffness"} if elastic else set())
    d = _derivatives(result, scene, need, elastic)
    if "length_mm" in names:
        d["length_mm"] = _by_dimensions(result, scene, d, elastic)
    return _collect(result, scene, names, d)


def _derivatives(result, scene: ActuatorScene, names: set, elastic: bool) -> dict:
    """{parameter: (d forces_upper, d forces_lower, d heights)} by the face solve."""
    from ..numba_cache import kernel_module  # numba at the first sensitivity

    ldl = kernel_module("lcpbench.linalg.ldl_kernel")
    chain = scene.chain()
    alpha = np.asarray(result.alpha, dtype=float)
    step = assemble_step(chain, alpha)
    n = step.size
    bands = np.ascontiguousarray(step.bands + geometric_bands(chain, alpha))
    u = step.origin
    fu = np.asarray(result.forces, dtype=float)
    fl = np.zeros(n) if result.forces_lower is None else np.asarray(result.forces_lower, float)
    eps_R = result.judgement.contact_threshold if result.judgement is not None else 0.0
    c_up, c_lo = compliances(chain)
    up, lo = fu > eps_R, (fl > eps_R) & ~(fu > eps_R)
    touching = ((np.isfinite(step.upper) & (step.upper - u <= max(1e-9 * scene.length,
                                                                  c_up.max(initial=0.0)
                                                                  * eps_R)))
                | (np.isfinite(step.lower) & (u - step.lower <= 1e-9 * scene.length)))
    result_one_sided = np.flatnonzero(touching & ~(up | lo))
    comp = np.where(up, c_up, np.where(lo, c_lo, 0.0))
    rigid = (up | lo) & ~(comp > 0)
    soft = (up | lo) & (comp > 0)
    fac = np.zeros((4, n))
    shift = np.ascontiguousarray(comp) if soft.any() else np.zeros(0)
    if not ldl.refactor(fac, bands, np.ascontiguousarray(rigid), shift, 0, n):
        raise ProblemError("sensitivities: the Hessian on the answer's free nodes is not "
                           "positive definite (the contact set is not a stable one)")
    wall_sign = np.where(up, 1.0, np.where(lo, -1.0, 0.0))  # dh of a held node per dh
    out = {}
    for p in names:
        dgrad, du0, extra = _parameter_terms(p, scene, step, u, fu, fl, up, lo, wall_sign)
        r = dgrad + _banded_matvec(bands, du0) + extra
        r[rigid] = 0.0
        du = du0 - ldl.resolve(fac, np.ascontiguousarray(r))
        dR = -(dgrad + _banded_matvec(bands, du))
        dfu = np.where(up, dR, 0.0)
        dfl = np.where(lo, -dR, 0.0)
        out[p] = (dfu, dfl, du)
    out["_one_sided"] = result_one_sided
    return out


def _parameter_terms(p: str, scene, step, u, fu, fl, up, lo, wall_sign):
    """(∂_p ∇E at u, du₀ on the held nodes, the springs' ∂_p k (u − h) term)."""
    n = step.size
    zero = np.zeros(n)
    if p == "height_mm":  # the walls move: +1 the upper wall, −1 the lower (at −h)
        return zero, np.where(up | lo, wall_sign, 0.0), zero
    if p == "wall_stiffness":  # k_i = k share_i: ∂k_i (u − h) = R_i / k
        return zero, zero, np.where(up | lo, (fu - fl) / scene.wall_stiffness, 0.0)
    m = step.joint_angles(u) - step.rest_joint  # φ − φ*
    if p == "theta_deg":  # φ* = −θ/N: ∂g = Jᵀ k (π/180)/N
        return step._JT(step.stiffness * (math.pi / 180.0 / scene.links)), zero, zero
    if p == "EI":  # k = EI/a: ∂g = Jᵀ (φ − φ*) / a
        return step._JT(m * (step.stiffness / scene.EI)), zero, zero
    if p == "weight":  # f ∝ w: ∂g = −f(w = 1)
        unit = replace(scene, weight=1.0).chain().nodal_load
        return -np.asarray(unit, dtype=float), zero, zero
    raise ProblemError(f"no sensitivity with respect to {p!r}")  # (checked before)


def _by_dimensions(result, scene: ActuatorScene, d: dict, elastic: bool):
    """∂/∂ℓ from dimensional analysis: ℓ ∂F/∂ℓ = −2F − h F_h + 3w F_w (+ 4k F_k)."""
    L, h, w = scene.length, scene.height, scene.weight
    fu = np.asarray(result.forces, dtype=float)
    fl = np.zeros_like(fu) if result.forces_lower is None else np.asarray(result.forces_lower)
    u = heights(scene.chain(), np.asarray(result.alpha, dtype=float))
    parts = [("height_mm", -h), ("weight", 3 * w)] + ([("wall_stiffness",
                                                         4 * scene.wall_stiffness)]
                                                       if elastic else [])
    dfu, dfl, du = -2.0 * fu, -2.0 * fl, np.asarray(u, dtype=float).copy()
    for name, factor in parts:
        a, b, c = d[name]
        dfu, dfl, du = dfu + factor * a, dfl + factor * b, du + factor * c
    return dfu / L, dfl / L, du / L


def _collect(result, scene, names, d) -> Sensitivities:
    chain = scene.chain()
    share = wall_share(chain.links, chain.link_length, chain.free_nodes)
    fu = np.asarray(result.forces, dtype=float)
    fl = np.zeros_like(fu) if result.forces_lower is None else np.asarray(result.forces_lower)
    pressure = (fu + fl) / share
    peak = int(np.argmax(pressure)) if pressure.size else -1
    total, forces, lower, heights, peak_d = {}, {}, {}, {}, {}
    for p in names:
        dfu, dfl, du = d[p]
        total[p] = float(np.sum(dfu))
        forces[p], lower[p], heights[p] = dfu, dfl, du
        peak_d[p] = float((dfu[peak] + dfl[peak]) / share[peak]) if peak >= 0 else 0.0
    return Sensitivities(names, total, forces, lower if scene.channel else None, heights, peak_d,
                         np.asarray(d["_one_sided"], dtype=np.int64))


def _banded_matvec(bands: np.ndarray, x: np.ndarray) -> np.ndarray:
    """H x for H in lower band storage (3, n) (bands[p, i] = H[i + p, i])."""
    from ..linalg import banded_matvec

    return banded_matvec(bands, x)
