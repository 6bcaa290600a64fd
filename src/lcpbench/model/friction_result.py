"""The result of a frictional state, and its judgement (issue 39, docs/friction.md).

The judge's friction checks (:func:`friction_verdict`) use the thresholds of the one
judge (:data:`lcpbench.model.judge.THRESHOLDS`: τ = force_tol(tol), NODE_SHARE,
GEOMETRY_TOL, SLIP_FACTOR) and its compiled residuals
(:func:`lcpbench.model.judge_friction.friction_checks`). A frictional answer is
converged only when the outer loop stopped by its criterion and every check passes.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, is_dataclass

import numpy as np

from ..jsonsafe import sanitise
from ..numba_cache import kept
from ..problems.scenes import ActuatorScene, Chain
from ..thresholds import NODE_SHARE
from .chain import node_positions
from .elastic import compliances
from .friction_driver import StateAnswer, datum, frictional_chain
from .friction_walls import gaps_at, tangential_slip, wall_frames, walls_at_x
from .judge import SLIP_FACTOR, SLIP_FLOOR, force_tol, penetration_allowed
from .result import ContactResult


@dataclass
class FrictionResult:
    """One state of a loading path (:func:`lcpbench.solve_path`).

    Per free node (nodes 2..N, as ``ContactResult.forces``): ``forces`` (normal
    reaction of the upper wall, N), ``forces_lower`` (the lower wall's, channel only),
    ``tangential_forces`` (T, N, on the chain along +x), ``slip`` (mm, x − x at the
    previous state) and ``stick`` (True: in contact, N > the judge's ε, and not
    sliding, |slip| <= the judge's ε_s). ``total_force``: ΣN over every wall. Against a
    wall of any profile N is along the wall's normal (its vertical part is N/√(1 + h'²)),
    T and the slip along its tangent (docs/friction.md, walls of any profile).
    ``route``: "frictionless" (today's :func:`lcpbench.solve`, kept in ``contact``)
    or "frictional" (:mod:`lcpbench.model.friction_driver`). ``judgement``: the
    friction checks' numbers and ``fails``, the checks that failed.
    """

    scene: object
    state: dict
    links: int
    x: np.ndarray
    y: np.ndarray
    alpha: np.ndarray
    forces: np.ndarray
    forces_lower: np.ndarray | None
    tangential_forces: np.ndarray
    slip: np.ndarray
    stick: np.ndarray
    total_force: float
    pull: float
    converged: bool
    reason: str
    outer_iterations: int
    tol: float
    time_s: float = 0.0
    route: str = "frictional"
    judgement: dict = field(default_factory=dict)
    contact: ContactResult | None = None
    #: the back-end of the frictional step ("lemke" by default; a ``lcp=`` function:
    #: "given"; the frictionless route: ``contact``'s)
    solver: str = "lemke"

    def __repr__(self) -> str:
        return (f"FrictionResult(N={self.links}, F={1e3 * self.total_force:.6g} mN, "
                f"ΣT={1e3 * float(np.sum(self.tangential_forces)):.6g} mN, "
                f"pull={1e3 * self.pull:.6g} mN, converged={self.converged})")

    def to_dict(self) -> dict:
        """A JSON-ready summary (N, mm)."""
        scene = scene_fields(self.scene)
        return sanitise({
            "scene": scene, "state": self.state, "route": self.route, "solver": self.solver,
            "converged": self.converged, "reason": self.reason,
            "total_force": self.total_force, "pull": self.pull,
            "forces": self.forces, "forces_lower": self.forces_lower,
            "tangential_forces": self.tangential_forces, "stick": self.stick,
            "slip": self.slip, "x": self.x, "y": self.y,
            "outer_iterations": self.outer_iterations, "tol": self.tol,
            "time_s": self.time_s, "judgement": self.judgement,
        })


def scene_fields(scene) -> dict:
    """The scene's fields for JSON: a wall profile as its name and x range."""
    out = asdict(scene) if is_dataclass(scene) and not isinstance(scene, type) else {}
    for key in ("wall_profile", "lower_profile"):
        if out.get(key) is not None:
            out[key] = getattr(scene, key).to_dict()
    return out


def from_contact(scene, state: dict, res: ContactResult, x_prev: np.ndarray | None
                 ) -> FrictionResult:
    """Today's frictionless answer as a state of a path (no tangential force)."""
    f = res.free_nodes if res.free_nodes is not None else np.arange(1, res.links)
    slip = res.x[f] - x_prev[f] if x_prev is not None else np.zeros(f.size)
    eps_s = max(SLIP_FACTOR * res.tol * scene.length / res.links, SLIP_FLOOR * scene.length)
    lower = res.forces_lower if res.forces_lower is not None else 0.0
    return FrictionResult(
        scene, state, res.links, res.x, res.y, res.alpha, res.forces, res.forces_lower,
        np.zeros(f.size), slip, (res.forces + lower > 0) & (np.abs(slip) <= eps_s),
        res.total_force,
        0.0, res.converged, res.reason, res.outer_iterations, res.tol, res.time_s,
        "frictionless", {}, res, res.solver)


_KERNEL: list = []  # the compiled checks (model/judge_friction.py), once loaded


def _checks():
    return kept(_KERNEL, "lcpbench.model.judge_friction", "friction_checks")


def friction_verdict(scene: ActuatorScene, chain: Chain, alpha: np.ndarray, x0: float,
                   fy: np.ndarray, fx: np.ndarray, normal: np.ndarray, limit: np.ndarray,
                   gap: np.ndarray, slip: np.ndarray, tol: float, left_pull: float = 0.0,
                   tangential: np.ndarray | None = None) -> dict:
    """The friction checks of an answer (docs/friction.md, the judge): numbers and fails;
    ``left_pull``: a force along x on the left end (a mirrored scene's pull). ``gap``:
    per wall row, the compliant gap g + N/k at an elastic wall (the Winkler law
    N = k (y − h)₊ holds when it is 0 where N > 0), the gap g at a rigid one; the
    penetration allowance is the frictionless judge's (:func:`~.judge.penetration_allowed`,
    with ε_R/k at an elastic wall). ``fx``, ``fy``: the wall forces on each free node
    (N); ``tangential``: T along the wall's tangent, per free node (``fx`` when None: flat
    walls), and ``slip`` the tangential slip, for the cone and stick/slip checks."""
    tau = force_tol(tol)
    F0 = max(abs(float(np.sum(normal))), chain.force_scale, abs(float(scene.pull)),
             abs(left_pull))
    eps_f = NODE_SHARE * tau * F0
    eps_s = max(SLIP_FACTOR * tol * chain.link_length, SLIP_FLOOR * chain.length)
    has_tau, right_datum = datum(scene)
    kern = _checks()
    stats = kern.friction_checks(
        alpha, float(x0), chain.link_length, chain.joint_links[:, 0].astype(np.int64),
        chain.joint_links[:, 1].astype(np.int64), chain.joint_stiffness, chain.rest_joint,
        chain.link_load, chain.free_nodes.astype(np.int64), fy, fx,
        fx if tangential is None else tangential, normal, limit, gap, slip,
        float(scene.pull), right_datum, scene.right_end != "free", eps_f, eps_s, chain.length,
        F0, float(left_pull))
    v = dict(zip(kern.FRICTION_STATS, (float(s) for s in stats)))
    v["relative_torque_residual"] = v["max_torque_residual"] / max(v["spring_max"],
                                                                   scene.EI / chain.length)
    fails = []
    if v["relative_torque_residual"] > max(10 * tol, 1e-6):
        fails.append("torque")
    if has_tau and abs(v["x_balance"]) > eps_f:
        fails.append("x balance")
    if v["cone_excess"] > eps_f:
        fails.append("cone")
    if v["slide_deficit"] > eps_f or v["slide_direction"] > eps_f or v["stick_slip"] > eps_s:
        fails.append("slip")
    c_up, c_lo = compliances(chain)
    if v["min_gap"] * chain.length < -penetration_allowed(tau, chain.length, eps_f, c_up,
                                                          c_lo):
        fails.append("penetration")
    if v["min_normal"] < -eps_f:
        fails.append("sign")
    if v["complementarity"] > NODE_SHARE * tau:
        fails.append("complementarity")
    v.update(tau=tau, F0=F0, eps_f=eps_f, eps_s=eps_s, fails=fails)
    return v


def build_result(scene: ActuatorScene, state: dict, ans: StateAnswer, x_prev: np.ndarray,
                 tol: float, y_prev: np.ndarray | None = None) -> FrictionResult:
    """A judged :class:`FrictionResult` from the outer loop's answer; slips from the
    previous node positions ``x_prev``, ``y_prev`` (``y_prev`` needed against a sloped
    wall only). Against a wall y = h(x) the normal force N acts along the wall's normal
    and T along its tangent at the answer's x (docs/friction.md, walls of any profile)."""
    chain = frictional_chain(scene)
    alpha, x0 = ans.state.alpha, ans.state.x0
    x, y = node_positions(chain, alpha)
    x = x + x0
    n = chain.free_nodes.size
    up, lo, T, limit = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    fs = ans.step
    if fs is not None and ans.normal.size:
        upper = fs.normal_sign < 0
        up[fs.normal_node[upper]] = ans.normal[upper]
        lo[fs.normal_node[~upper]] = ans.normal[~upper]
        T[fs.friction_node - chain.free_nodes[0]] = ans.tangential
        paired = fs.pair >= 0
        np.add.at(limit, fs.normal_node[paired], (fs.mu * ans.normal)[paired])
    # the walls' slopes at the answer's x: N along the normal, T along the tangent of the
    # wall each node's row is on (the upper one for a node without a row: T = 0 there)
    _, _, s_up, s_lo = walls_at_x(chain, x)
    on_lower = np.zeros(n, bool)
    if fs is not None and ans.normal.size:
        on_lower[fs.normal_node[fs.normal_sign > 0]] = True
    slope = np.where(on_lower, s_lo, s_up)
    n_up, n_lo = wall_frames(-np.ones(n), s_up), wall_frames(np.ones(n), s_lo)
    c = np.sqrt(1.0 + slope * slope)
    fx = up * n_up[:, 0] + lo * n_lo[:, 0] + T / c
    fy = up * n_up[:, 1] + lo * n_lo[:, 1] + T * slope / c
    # every wall row, both walls of a channel: the exact gaps and the normal forces
    g_up, g_lo = gaps_at(chain, x, y)
    rows_up, rows_lo = np.isfinite(g_up), np.isfinite(g_lo)
    normal = np.concatenate([up[rows_up], lo[rows_lo]])
    c_up, c_lo = compliances(chain)  # elastic walls: the compliant gap g + N/k
    gap = (np.concatenate([g_up[rows_up], g_lo[rows_lo]])
           + np.concatenate([c_up[rows_up], c_lo[rows_lo]]) * np.maximum(normal, 0.0))
    slip = tangential_slip(x, y, x_prev, y_prev, chain.free_nodes, slope)
    verdict = friction_verdict(scene, chain, alpha, x0, fy, fx, normal, limit, gap, slip,
                               tol, ans.left_pull, T)
    converged = ans.converged and not verdict["fails"]
    reason = ans.reason if not ans.converged else (
        "max|Δα| < tol; judged" if converged else "judge: " + ", ".join(verdict["fails"]))
    stick = (up + lo > verdict["eps_f"]) & (np.abs(slip) <= verdict["eps_s"])
    return FrictionResult(
        scene, state, chain.links, x, y, alpha, up, lo if chain.channel else None, T, slip,
        stick, float(up.sum() + lo.sum()), float(scene.pull), converged, reason,
        ans.iterations, tol, ans.time_s, "frictional", verdict)
