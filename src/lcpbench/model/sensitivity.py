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
its compliance form; all of it in :mod:`lcpbench.model.sensitivity_kernel`), O(N): du = du₀ − (H + T)_face⁻¹ r with du₀ = dh on the held
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
``one_sided`` lists the node. Covered: actuator scenes with flat walls (one wall or
a channel, rigid or elastic), the cantilever of Sec. III-G (its load q in N/mm in
place of θ and w: ``load``) and rows of sections (:class:`SectionedScene`: per
section k ``theta_deg[k]``, ``EI[k]``, ``weight[k]``; a joint on a boundary has the
series spring 2 EI_l EI_r / (a (EI_l + EI_r)) and the rest angle of both halves, so
∂k/∂EI_l = 2 EI_r² / (a (EI_l + EI_r)²) and ∂φ*/∂θ_k = −1/(2 n_k) there; ``length_mm``
scales every section's length together: ℓ ∂F/∂ℓ = −2F − h F_h + 3 Σ_k w_k F_{w_k}).
Walls of any profile (``height_mm``: both walls moved apart): a banded KKT solve with
the nodes' x lifted into it, :mod:`lcpbench.model.sensitivity_profile`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ProblemError
from ..problems.cantilever import CantileverScene
from ..problems.scenes import ActuatorScene
from ..problems.sections import SectionedScene
from ..problems.templates import wall_share
from ..thresholds import NODE_SHARE
from .judge import force_tol
from .sensitivity_profile import OF_PROFILE, profile_derivatives

#: the parameters (and their units) a sensitivity is taken with respect to
PARAMETERS = {"theta_deg": "deg", "height_mm": "mm", "EI": "N mm²", "weight": "N/mm",
              "length_mm": "mm", "wall_stiffness": "N/mm²", "load": "N/mm"}
#: the parameters of each scene kind covered (a row of sections: one θ, EI and w per
#: section, ``theta_deg[k]``, …, see :func:`parameters`)
OF_SCENE = {ActuatorScene: ("theta_deg", "height_mm", "EI", "weight", "length_mm",
                            "wall_stiffness"),
            CantileverScene: ("height_mm", "EI", "load", "length_mm", "wall_stiffness")}


def unit(name: str) -> str:
    """The unit of parameter ``name`` (a per-section name ``EI[1]`` has EI's)."""
    return PARAMETERS[name.split("[", 1)[0]]


def parameters(scene) -> tuple[str, ...]:
    """The parameters :func:`sensitivities` covers for ``scene`` (all that apply)."""
    if isinstance(scene, SectionedScene):
        m = len(scene.sections)
        return (*(f"theta_deg[{i}]" for i in range(m)), "height_mm",
                *(f"EI[{i}]" for i in range(m)), *(f"weight[{i}]" for i in range(m)),
                "length_mm")
    if getattr(scene, "wall_profile", None) is not None:
        return OF_PROFILE
    elastic = not math.isinf(scene.wall_stiffness)
    return tuple(p for p in OF_SCENE[type(scene)] if elastic or p != "wall_stiffness")


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
               "units": {k: unit(k) for k in self.wrt},
               "one_sided_nodes": self.one_sided.tolist()}
        if self.forces_lower is not None:
            out["forces_lower"] = {k: v.tolist() for k, v in self.forces_lower.items()}
        return out


def unsupported(scene) -> str | None:
    """Why :func:`sensitivities` does not cover ``scene``, or None."""
    if getattr(scene, "frictional", False):
        return ("sensitivities cover the frictionless model (both ends pinned, no friction "
                "or pull); a frictional answer depends on its path and has none here yet")
    if isinstance(scene, (CantileverScene, SectionedScene, ActuatorScene)):
        return None
    return ("sensitivities cover actuator scenes (flat walls, one wall or a channel, rigid "
            "or elastic, or walls of any profile), rows of sections and the cantilever; got "
            f"{type(scene).__name__}")


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
    elastic = not math.isinf(getattr(scene, "wall_stiffness", math.inf))
    own = parameters(scene)
    names = own if wrt is None else tuple(wrt)
    for p in names:
        if p not in own:
            raise ProblemError(f"wrt must name parameters among {', '.join(own)}; got {p!r}")
    if getattr(scene, "wall_profile", None) is not None:
        from .kernel_call import kernel_args

        chain = scene.chain()
        _, _, _, _, k, rest, _, nodal_load, *_ = kernel_args(chain)
        drest, dk, unit_load, _ = _parameter_rows(scene, chain, rest, k, nodal_load)
        d = profile_derivatives(result, scene, set(names), _contact_threshold(result, scene),
                                (drest[0], dk[0], unit_load[0]))
        return _collect(result, scene, names, d)
    need = {p for p in names if p != "length_mm"}
    if "length_mm" in names:  # from the others, by dimensional analysis
        need |= {"height_mm", *_loads(scene)} | ({"wall_stiffness"} if elastic else set())
    d = _derivatives(result, scene, need, elastic)
    if "length_mm" in names:
        d["length_mm"] = _by_dimensions(result, scene, d, elastic)
    return _collect(result, scene, names, d)


def _derivatives(result, scene, names: set, elastic: bool) -> dict:
    """{parameter: (d forces_upper, d forces_lower, d heights)} by the compiled face solve
    (:func:`lcpbench.model.sensitivity_kernel.derivatives`), and the one-sided nodes."""
    from ..numba_cache import kernel_module  # numba at the first sensitivity
    from .kernel_call import kernel_args

    kern = kernel_module("lcpbench.model.sensitivity_kernel", "derivatives")
    chain = scene.chain()
    _, a, jl, jr, k, rest, _, nodal_load, fs, lo, hi, _, _, cu, cl = kernel_args(chain)
    alpha = np.ascontiguousarray(result.alpha, dtype=float)
    n = lo.size
    fu = np.ascontiguousarray(result.forces, dtype=float)
    fl = np.zeros(n) if result.forces_lower is None else \
        np.ascontiguousarray(result.forces_lower, dtype=float)
    eps_R = _contact_threshold(result, scene)
    drest, dk, unit_load, rows = _parameter_rows(scene, chain, rest, k, nodal_load)
    want = np.zeros(len(rows), bool)
    for p in names:
        want[rows[p]] = True
    code, du, dfu, dfl, u = kern.derivatives(alpha, a, jl, jr, k, rest, fs, nodal_load, lo, hi, cu,
                                          cl, fu, fl, float(eps_R), drest, dk, unit_load,
                                          float(getattr(scene, "wall_stiffness", math.inf)),
                                          want)
    if code != kern.OK:
        raise ProblemError("sensitivities: the Hessian on the answer's free nodes is not "
                           "positive definite (the contact set is not a stable one)")
    out = {p: (dfu[rows[p]], dfl[rows[p]], du[rows[p]]) for p in names}
    # a node touching its wall without force: at a change of contact set (one-sided)
    c_max = float(np.max(cu, initial=0.0)) if cu.size else 0.0
    touching = (hi - u <= max(1e-9 * scene.length, c_max * eps_R)) | \
        (u - lo <= 1e-9 * scene.length)
    out["_one_sided"] = np.flatnonzero(touching & ~((fu > eps_R) | (fl > eps_R)))
    out["_heights"] = u
    return out


def _contact_threshold(result, scene) -> float:
    """The judge's contact threshold ε_R = NODE_SHARE τ F₀ (model.judge.judge), without
    building a lazy result's judgement."""
    fu = np.asarray(result.forces, dtype=float)
    fl = np.zeros(0) if result.forces_lower is None else np.asarray(result.forces_lower)
    F0 = max(abs(float(fu.sum())), abs(float(fl.sum())), float(scene.chain().force_scale))
    return NODE_SHARE * force_tol(result.tol) * F0


def _parameter_rows(scene, chain, rest, k, nodal_load):
    """The kernel's per-parameter inputs: ∂φ*/∂θ_k (mt, nj) per degree, ∂k/∂EI_k (me, nj),
    the nodal load at unit w_k (mw, n), and {parameter: its output row}."""
    if isinstance(scene, SectionedScene):  # (the chain's data only: kept with it)
        return chain.derived("_section_rows", lambda: _section_rows(scene, chain, rest,
                                                                    nodal_load))
    return chain.derived("_parameter_rows", lambda: _scene_rows(scene, rest, k, nodal_load))


def _scene_rows(scene, rest, k, nodal_load):
    """:func:`_parameter_rows` of an actuator or a cantilever (one row of each)."""
    # φ* = −θ/N per joint, k = EI/a, the loads ∝ w (the cantilever's: ∝ q): their
    # derivatives (the cantilever has no rest curvature)
    theta = getattr(scene, "theta", None)
    n = nodal_load.size
    drest = np.zeros(rest.size) if theta is None else (
        rest / theta if theta else np.full(rest.size, -math.pi / 180 / n))
    field_ = "load" if isinstance(scene, CantileverScene) else "weight"
    w = getattr(scene, field_)
    unit_load = nodal_load / w if w else np.ascontiguousarray(
        replace(scene, **{field_: 1.0}).chain().nodal_load, dtype=float)
    rows = {"theta_deg": 0, "height_mm": 1, "EI": 2, "weight": 3, "load": 3,
            "wall_stiffness": 4}
    return drest[None, :], (k / scene.EI)[None, :], unit_load[None, :], rows


def _section_rows(scene, chain, rest, nodal_load):
    """:func:`_parameter_rows` of a row of sections: θ_k, EI_k, w_k per section."""
    counts = scene.section_links()
    m, a = counts.size, chain.link_length
    section = np.repeat(np.arange(m), counts)  # of each link
    left, right = section[:-1], section[1:]
    ei = np.array([s.EI for s in scene.sections])[section]
    el, er = ei[:-1], ei[1:]
    drest = np.empty((m, rest.size))
    dk = np.empty((m, rest.size))
    unit_load = np.empty((m, nodal_load.size))
    sign = -1.0 if scene.gravity == "-y" else 1.0
    for i in range(m):  # φ*_j = −(t_l + t_r)/2, t = θ_k/n_k per link (rad)
        drest[i] = -0.5 * math.pi / 180 / counts[i] * ((left == i) * 1.0 + (right == i))
        # k_j = 2 EI_l EI_r / (a (EI_l + EI_r)) (EI_k / a inside a section)
        dk[i] = (2 * ((left == i) * er**2 + (right == i) * el**2) / (a * (el + er) ** 2))
        unit_load[i] = replace(chain, link_load=sign * a * (section == i)).nodal_load
    names = ([f"theta_deg[{i}]" for i in range(m)] + ["height_mm"]
             + [f"EI[{i}]" for i in range(m)] + [f"weight[{i}]" for i in range(m)]
             + ["wall_stiffness"])
    return drest, dk, unit_load, {p: r for r, p in enumerate(names)}


def _loads(scene) -> tuple[str, ...]:
    """The names of the scene's weights (the cantilever: its load q)."""
    if isinstance(scene, SectionedScene):
        return tuple(f"weight[{i}]" for i in range(len(scene.sections)))
    return ("load",) if isinstance(scene, CantileverScene) else ("weight",)


def _by_dimensions(result, scene, d: dict, elastic: bool):
    """∂/∂ℓ from dimensional analysis: ℓ ∂F/∂ℓ = −2F − h F_h + 3 Σ w_k F_{w_k} (+ 4k F_k);
    the cantilever's load q (N/mm) scales as w; a row of sections is scaled whole."""
    L, h = scene.length, scene.height
    weights = ([s.weight for s in scene.sections] if isinstance(scene, SectionedScene)
               else [getattr(scene, _loads(scene)[0])])
    fu = np.asarray(result.forces, dtype=float)
    fl = np.zeros_like(fu) if result.forces_lower is None else np.asarray(result.forces_lower)
    u = d["_heights"]
    parts = [("height_mm", -h)] + [(p, 3 * w) for p, w in zip(_loads(scene), weights,
                                                               strict=True)]
    parts += [("wall_stiffness", 4 * scene.wall_stiffness)] if elastic else []
    dfu, dfl, du = -2.0 * fu, -2.0 * fl, np.asarray(u, dtype=float).copy()
    for name, factor in parts:
        a, b, c = d[name]
        dfu, dfl, du = dfu + factor * a, dfl + factor * b, du + factor * c
    return dfu / L, dfl / L, du / L


def _collect(result, scene, names, d) -> Sensitivities:
    chain = scene.chain()
    share = chain.derived("_wall_share", lambda: wall_share(chain.links, chain.link_length,
                                                            chain.free_nodes))
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
    channel = getattr(scene, "channel", False)
    return Sensitivities(names, total, forces, lower if channel else None, heights, peak_d,
                         np.asarray(d["_one_sided"], dtype=np.int64))
