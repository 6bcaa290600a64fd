"""Scenes: what is being modelled, in the user's units (mm, N, N·mm², degrees).

A scene knows its physical parameters and how to describe itself as a
:class:`~lcpbench.model.chain.Chain` (links, springs, loads, walls). It knows
nothing of solvers. Every scene validates its inputs and raises
:class:`~lcpbench.errors.ProblemError` naming the parameter and the allowed
range.

Two scenes:

* :class:`ActuatorScene` — the paper's bending section: pinned–pinned, the
  right pin sliding along x, unconstrained shape a circular arc of angle θ
  (eq. 2), pressed by a wall at ``y = +h`` (or a channel of walls at ±h),
  self-weight acting away from the wall (the direction of the reaction).
* :class:`CantileverScene` — Sec. III-G: clamped–free, a uniform load per
  length pushing the beam toward a wall at ``y = +h``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import ProblemError

MIN_LINKS = 4
MAX_LINKS = 100_000

# Paper defaults (Sec. III-D, IV-B).
DEFAULT_LENGTH = 30.0  # mm
DEFAULT_EI = 32.01  # N·mm²
DEFAULT_WEIGHT = 2.45e-4  # N/mm
DEFAULT_LINKS = 140


def _finite(name: str, value: float) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"{name} must be a number, got {value!r}") from exc
    if not math.isfinite(value):
        raise ProblemError(f"{name} must be finite, got {value}")
    return value


def _positive(name: str, value: float, unit: str) -> float:
    value = _finite(name, value)
    if value <= 0:
        raise ProblemError(f"{name} must be > 0 {unit}, got {value:g}")
    return value


def _links(value) -> int | str:
    if isinstance(value, str):
        if value == "auto":
            return value
        raise ProblemError(f"links must be an integer >= {MIN_LINKS} or 'auto', got {value!r}")
    if isinstance(value, bool) or not float(value).is_integer():
        raise ProblemError(f"links must be an integer >= {MIN_LINKS} or 'auto', got {value!r}")
    n = int(value)
    if not MIN_LINKS <= n <= MAX_LINKS:
        raise ProblemError(
            f"links must be between {MIN_LINKS} and {MAX_LINKS} (to form a chain), got {n}"
        )
    return n


@dataclass(frozen=True)
class Chain:
    """A Hencky bar chain as the model sees it (all lengths in mm, forces in N).

    Attributes
    ----------
    links : int
        N, the number of rigid links; nodes are numbered 1..N+1.
    link_length : float
        a = ℓ/N (eq. 12).
    rest_alpha : ndarray (N,)
        Unconstrained link angles α* (rad), also the starting configuration.
    joint_stiffness : ndarray (J,)
        Torsional spring stiffness of each joint (N·mm/rad).
    joint_links : ndarray (J, 2) of int
        For each joint, the 0-based indices of the links on its left and
        right; -1 stands for the clamp (a fixed horizontal reference).
    rest_joint : ndarray (J,)
        Rest joint angles φ* (rad).
    link_load : ndarray (N,)
        Vertical force on each link at its centre (N, +y up).
    free_nodes : ndarray of int
        0-based indices of nodes whose height is unknown (pinned nodes
        are held at y = 0).
    upper : ndarray (len(free_nodes),)
        Height of the upper wall above each free node (+inf: no wall row).
    lower : ndarray (len(free_nodes),)
        Height of the lower wall (−inf: no wall row).
    """

    links: int
    link_length: float
    rest_alpha: np.ndarray
    joint_stiffness: np.ndarray
    joint_links: np.ndarray
    rest_joint: np.ndarray
    link_load: np.ndarray
    free_nodes: np.ndarray
    upper: np.ndarray
    lower: np.ndarray
    force_scale: float = 1.0  # EI/ℓ², for reporting dimensionless residuals
    length: float = 1.0
    wall: float = np.inf  # height of the upper wall (mm), for the gaps of every node
    channel: bool = False  # a second wall at −wall

    @property
    def nodal_load(self) -> np.ndarray:
        """Link loads lumped half to each end node (exact for rigid links)."""
        f = np.zeros(self.links + 1)
        f[:-1] += 0.5 * self.link_load
        f[1:] += 0.5 * self.link_load
        return f[self.free_nodes]


def reachable(node_arclength: np.ndarray, length: float, height: float, ends: str) -> np.ndarray:
    """Which nodes can reach a wall at distance ``height`` from the supports.

    The chain is inextensible and its supports sit on y = 0, so a node at arc
    length s can be at most s from a pin (and ℓ − s from the other pin, when
    both ends are pinned). Nodes that cannot reach the wall get no contact row.
    """
    reach = node_arclength.copy()
    if ends == "pinned-pinned":
        reach = np.minimum(reach, length - node_arclength)
    return reach >= height * (1.0 - 1e-12)


@dataclass(frozen=True)
class ActuatorScene:
    """An actuator bending section pinned at both ends against a rigid wall.

    Parameters
    ----------
    theta : float
        Unconstrained bend angle θ in degrees, in (0, 360).
    height : float
        Wall height h above the pin line (mm), > 0. With ``channel=True`` a
        second wall sits at −h.
    links : int or "auto"
        Number of links N (>= 4), or "auto" for the discretisation study of
        Sec. III-D (the smallest N whose force changes by < 0.01 %).
    length : float
        Section length ℓ (mm).
    EI : float
        Bending stiffness (N·mm²).
    weight : float
        Weight per length w (N/mm), >= 0; 0 turns gravity off. It acts away
        from the wall (the direction of the reaction), as in eqs. (3), (8).
    channel : bool
        Two walls, at +h and −h (the paper's fixture).
    """

    theta: float = 150.0
    height: float = 3.0
    links: int | str = DEFAULT_LINKS
    length: float = DEFAULT_LENGTH
    EI: float = DEFAULT_EI
    weight: float = DEFAULT_WEIGHT
    channel: bool = False

    def __post_init__(self):
        theta = _finite("theta", self.theta)
        if not 0.0 < theta < 360.0:
            raise ProblemError(f"theta must be in (0, 360) degrees, got {theta:g}")
        object.__setattr__(self, "theta", theta)
        height = _finite("height", self.height)
        if height <= 0:
            raise ProblemError(
                f"height must be > 0 mm (the pins sit on y = 0, so a wall at {height:g} "
                "already crosses them)"
            )
        object.__setattr__(self, "height", height)
        object.__setattr__(self, "links", _links(self.links))
        object.__setattr__(self, "length", _positive("length", self.length, "mm"))
        object.__setattr__(self, "EI", _positive("EI", self.EI, "N·mm²"))
        weight = _finite("weight", self.weight)
        if weight < 0:
            raise ProblemError(f"weight must be >= 0 N/mm, got {weight:g}")
        object.__setattr__(self, "weight", weight)
        if not isinstance(self.channel, (bool, np.bool_)):
            raise ProblemError(f"channel must be True or False, got {self.channel!r}")

    # -- geometry of the unconstrained arc (eq. 2) ---------------------------
    @property
    def radius(self) -> float:
        """Bend radius r = ℓ/θ of the unconstrained arc (mm), eq. (2)."""
        return self.length / math.radians(self.theta)

    @property
    def arc_height(self) -> float:
        """Largest height of the continuous unconstrained arc above the pins (mm)."""
        return self.radius * (1 - math.cos(math.radians(self.theta) / 2))

    def with_links(self, links: int) -> ActuatorScene:
        return replace(self, links=links)

    def chain(self) -> Chain:
        """The Hencky bar chain of this scene (needs an integer ``links``)."""
        if self.links == "auto":
            raise ProblemError("links='auto' must be resolved first (lcpbench.solve does this)")
        n = int(self.links)
        a = self.length / n
        th = math.radians(self.theta)
        rest_alpha = th / 2 - (np.arange(n) + 0.5) * th / n
        joints = np.column_stack([np.arange(n - 1), np.arange(1, n)])
        interior = np.arange(1, n)  # nodes 2..N
        s = interior * a
        can = reachable(s, self.length, self.height, "pinned-pinned")
        upper = np.where(can, self.height, np.inf)
        lower = np.where(can, -self.height, -np.inf) if self.channel else np.full(n - 1, -np.inf)
        return Chain(
            links=n,
            link_length=a,
            rest_alpha=rest_alpha,
            joint_stiffness=np.full(n - 1, self.EI / a),
            joint_links=joints,
            rest_joint=np.full(n - 1, -th / n),
            link_load=np.full(n, -self.weight * a),  # μ = wℓ/N (eq. 5), away from the wall
            free_nodes=interior,
            upper=upper,
            lower=lower,
            force_scale=self.EI / self.length**2,
            length=self.length,
            wall=self.height,
            channel=bool(self.channel),
        )


@dataclass(frozen=True)
class CantileverScene:
    """Sec. III-G: a clamped–free beam, uniform load toward a wall at distance h.

    Parameters
    ----------
    load : float
        Distributed load F (N/mm) pushing the beam toward the wall, >= 0.
    height : float
        Distance h from the undeformed beam to the wall (mm), > 0.
    links, length, EI :
        As for :class:`ActuatorScene`.

    Notes
    -----
    The clamp is a torsional spring of stiffness 2EI/a holding link 1 toward
    the horizontal: it stands for the half-link [0, a/2] between the clamp and
    the first link's centre, which makes the chain second-order accurate (the
    paper does not say which stiffness it used).
    """

    load: float = 0.001
    height: float = 1.0
    links: int = DEFAULT_LINKS
    length: float = DEFAULT_LENGTH
    EI: float = DEFAULT_EI

    def __post_init__(self):
        load = _finite("load", self.load)
        if load < 0:
            raise ProblemError(f"load must be >= 0 N/mm, got {load:g}")
        object.__setattr__(self, "load", load)
        object.__setattr__(self, "height", _positive("height", self.height, "mm"))
        links = _links(self.links)
        if links == "auto":
            raise ProblemError("links must be an integer for the cantilever scene")
        object.__setattr__(self, "links", links)
        object.__setattr__(self, "length", _positive("length", self.length, "mm"))
        object.__setattr__(self, "EI", _positive("EI", self.EI, "N·mm²"))

    def chain(self) -> Chain:
        n = int(self.links)
        a = self.length / n
        joints = np.column_stack([np.arange(-1, n - 1), np.arange(n)])
        stiffness = np.full(n, self.EI / a)
        stiffness[0] = 2 * self.EI / a
        free = np.arange(1, n + 1)  # nodes 2..N+1 (the tip is free)
        can = reachable(free * a, self.length, self.height, "clamped-free")
        return Chain(
            links=n,
            link_length=a,
            rest_alpha=np.zeros(n),
            joint_stiffness=stiffness,
            joint_links=joints,
            rest_joint=np.zeros(n),
            link_load=np.full(n, self.load * a),
            free_nodes=free,
            upper=np.where(can, self.height, np.inf),
            lower=np.full(n, -np.inf),
            force_scale=self.EI / self.length**2,
            length=self.length,
            wall=self.height,
        )

    # -- Euler–Bernoulli theory, eqs. (33)–(37) ------------------------------
    def theory_force(self) -> float:
        """Tip reaction R_t from linear beam theory (N), eqs. (34)–(37); 0 if no contact."""
        F, h, ell, EI = self.load, self.height, self.length, self.EI
        f_c = 8 * EI * h / ell**4  # (34)
        f_r = F - f_c  # (35)
        if f_r <= 0:
            return 0.0
        dy_r = f_r * ell**4 / (8 * EI)  # (36)
        return 3 * EI * dy_r / ell**3  # (37)

    def theory_deflection(self, x: np.ndarray) -> np.ndarray:
        """Unconstrained deflection Δy(x) = F x²(x² − 4ℓx + 6ℓ²)/(24 EI), eq. (33)."""
        F, ell, EI = self.load, self.length, self.EI
        return F * x**2 * (x**2 - 4 * ell * x + 6 * ell**2) / (24 * EI)
