"""Scenes: what is being modelled, in the user's units (mm, N, N·mm², degrees).

A scene knows its physical parameters and how to describe itself as a
:class:`~lcpbench.model.chain.Chain` (links, springs, loads, walls). It knows
nothing of solvers. Every scene validates its inputs and raises
:class:`~lcpbench.errors.ProblemError` naming the parameter and the allowed
range.

Here :class:`ActuatorScene`, the paper's bending section: pinned–pinned, the
right pin sliding along x, unconstrained shape a circular arc of angle θ (eq. 2),
pressed by a wall at ``y = +h`` (or a channel of walls at ±h), self-weight acting
away from the wall (the direction of the reaction); the :class:`Chain` every scene
builds; and the field checks the scenes share. Sec. III-G's clamped–free beam is
:class:`lcpbench.problems.cantilever.CantileverScene`; rows of sections are in
:mod:`lcpbench.problems.sections`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

from ..errors import ProblemError
from .checks import check_flag, check_number, describe
from .friction import FrictionOptions
from .templates import (
    filled,
    flat_walls,
    full,
    pinned_frame,
    uniform_load,
    within_reach,
)
from .walls import WallProfile

MIN_LINKS = 4
MAX_LINKS = 100_000

# Paper defaults (Sec. III-D, IV-B).
DEFAULT_LENGTH = 30.0  # mm
DEFAULT_EI = 32.01  # N·mm²
DEFAULT_WEIGHT = 2.45e-4  # N/mm
DEFAULT_LINKS = 140


#: Allowed ranges of the scene fields, in the user's units. Wide enough for every
#: scene in the paper, the tests and the benchmark grids (ℓ 10-90 mm, EI 1-1000,
#: h from 0.02 ℓ to 1e3 mm, N up to 1e5); narrow enough that the
#: nondimensionalised problem (lengths by ℓ, forces by EI/ℓ²) stays far from
#: overflow and underflow in double precision.
LENGTH_RANGE = (1e-3, 1e5)  # mm
HEIGHT_RANGE = (1e-6, 1e6)  # mm: h > 0 (the pins sit on y = 0), at least 1 nm
EI_RANGE = (1e-6, 1e9)  # N·mm²
THETA_RANGE = (0.0, 360.0)  # degrees, both ends open
WEIGHT_RANGE = (0.0, 1e3)  # N/mm; 0 turns gravity off
LOAD_RANGE = (0.0, 1e6)  # N/mm (the cantilever's distributed load)
_NOT_YET = object()  # a value :meth:`Chain.derived` has not kept yet


def links_value(value, *, auto: bool = True) -> int | str:
    """N: an integer in [MIN_LINKS, MAX_LINKS], or 'auto' when ``auto``."""
    if auto and isinstance(value, str) and value == "auto":
        return value
    return check_number("links", value, low=MIN_LINKS, high=MAX_LINKS, integer=True,
                        alternative="'auto'" if auto else "")


def in_range(name: str, value, bounds: tuple[float, float], unit: str) -> float:
    """``value`` as a float in ``bounds`` (inclusive, in ``unit``), or ProblemError naming
    ``name``."""
    return check_number(name, value, low=bounds[0], high=bounds[1], unit=unit)


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
    upper_stiffness, lower_stiffness : ndarray (len(free_nodes),) or None
        Elastic walls: the spring stiffness k_i (N/mm) of the wall at each free
        node (the Winkler foundation's k times the node's share of wall
        length, :func:`wall_share`); None, or +inf entries, for a rigid wall.
    upper_profile, lower_profile : WallProfile or None
        Walls of any profile y = h(x) (:mod:`lcpbench.problems.walls`). When
        given, ``upper``/``lower`` hold h at the nodes' x of ``rest_alpha``
        (finite on the rows that can reach the wall); the model evaluates
        h(x) at the current configuration (:mod:`lcpbench.model.profile`).
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
    # Elastic walls (issue 17): per free node, the stiffness k_i (N/mm) of the
    # upper / lower wall's spring, the Winkler k times the node's share of wall
    # length; None (or +inf entries) = a rigid wall. lcpbench.model.elastic.
    upper_stiffness: np.ndarray | None = None
    lower_stiffness: np.ndarray | None = None
    upper_profile: WallProfile | None = None
    lower_profile: WallProfile | None = None
    #: True when built with joint j between links j and j + 1 (or the clamp and link
    #: 0) and the free nodes contiguous from node 2 on: the layout the compiled
    #: kernels take (what the scenes build); None: not known, checked from the arrays
    consecutive: bool | None = None
    #: True: solved and judged in increments on the tridiagonal factor of H
    #: (:mod:`lcpbench.model.large_n`) whatever N, not only from ``LARGE_N`` links;
    #: :func:`lcpbench.solve` sets it where the round-off of the height formulation
    #: keeps the judge from certifying the asked tolerance
    increments: bool = False

    @property
    def elastic_walls(self) -> bool:
        """Whether a wall is given a stiffness (``upper_stiffness``/``lower_stiffness``)."""
        return self.upper_stiffness is not None or self.lower_stiffness is not None

    @property
    def profiled_walls(self) -> bool:
        """Whether a wall has a profile y = h(x) (``upper_profile``/``lower_profile``)."""
        return self.upper_profile is not None or self.lower_profile is not None

    def derived(self, key: str, make):
        """A value derived from the chain (``make()``), computed once and kept with it.

        The chain is immutable (``dataclasses.replace`` makes a new one, without
        the kept values), so whatever depends on its fields only (the compiled
        kernels' argument arrays, its layout, its load parameter) is computed at
        the first solve and reused by the next ones."""
        d = self.__dict__
        value = d.get(key, _NOT_YET)  # (a miss raises no KeyError: most are misses)
        if value is _NOT_YET:
            value = d[key] = make()  # (a frozen dataclass: not via setattr)
        return value

    def with_rest_shape(self, rest_alpha: np.ndarray, rest_joint: np.ndarray) -> Chain:
        """The same chain with another rest shape α*, φ* (a step of the loading path,
        :mod:`lcpbench.model.ramp`): ``dataclasses.replace`` without its per-field
        work, keeping the derived values that depend on the layout and the load only
        (:data:`LAYOUT_DERIVED`); the others are derived again."""
        new = object.__new__(Chain)
        d, own = new.__dict__, self.__dict__
        for name in _CHAIN_FIELDS:
            d[name] = own[name]
        d["rest_alpha"], d["rest_joint"] = rest_alpha, rest_joint
        for key in LAYOUT_DERIVED:
            if key in own:
                d[key] = own[key]
        return new

    @property
    def nodal_load(self) -> np.ndarray:
        """Link loads lumped half to each end node (exact for rigid links)."""
        f = np.zeros(self.links + 1)
        f[:-1] += 0.5 * self.link_load
        f[1:] += 0.5 * self.link_load
        return f[self.free_nodes]


#: the Chain's fields, in order
_CHAIN_FIELDS = tuple(f.name for f in fields(Chain))
#: the values a chain derives (:meth:`Chain.derived`) from its layout, walls and load,
#: not from its rest shape: :meth:`Chain.with_rest_shape` keeps them
LAYOUT_DERIVED = ("_angle_problem", "_free_nodes_below", "_in_reach", "_kernel_layout",
                  "_nodal_load", "_total_load")

STIFFNESS_RANGE = (1e-9, 1e12)  # N/mm per mm of wall (Winkler k); inf = rigid


def wall_stiffness(value, name: str = "wall_stiffness") -> float:
    """A Winkler stiffness k (N/mm per mm of wall): a number in [1e-9, 1e12], or
    +inf (a rigid wall, the default); ProblemError otherwise (NaN, negative, 0)."""
    if isinstance(value, (float, np.floating)) and math.isinf(value) and value > 0:
        return math.inf
    return check_number(name, value, low=STIFFNESS_RANGE[0], high=STIFFNESS_RANGE[1],
                        unit="N/mm per mm of wall", alternative="inf (rigid)")


def _plain_fields(d: dict) -> bool:
    """Whether an actuator scene's numbers and flag (``d``: its fields) are already what
    :meth:`ActuatorScene._check_fields` returns for them: Python floats inside their
    ranges (θ, h, ℓ, EI, w; k in its range or +inf), an int N in range, a bool
    ``channel``. Then the checks would change nothing and raise nothing; otherwise
    (an int height, a numpy number, NaN, a value out of range, 'auto'...) they run.
    It reads the same range constants as the checks; a check added to ``_check_fields``
    must be added here too, or the common scene skips it."""
    theta, height, links, length = d["theta"], d["height"], d["links"], d["length"]
    ei, weight, k = d["EI"], d["weight"], d["wall_stiffness"]
    return (type(theta) is float and THETA_RANGE[0] < theta < THETA_RANGE[1]
            and type(height) is float and HEIGHT_RANGE[0] <= height <= HEIGHT_RANGE[1]
            and type(links) is int and MIN_LINKS <= links <= MAX_LINKS
            and type(length) is float and LENGTH_RANGE[0] <= length <= LENGTH_RANGE[1]
            and type(ei) is float and EI_RANGE[0] <= ei <= EI_RANGE[1]
            and type(weight) is float and WEIGHT_RANGE[0] <= weight <= WEIGHT_RANGE[1]
            and type(k) is float and (k == math.inf
                                      or STIFFNESS_RANGE[0] <= k <= STIFFNESS_RANGE[1])
            and type(d["channel"]) is bool)


def paper_options(d: dict) -> bool:
    """Whether a scene's frictional options (``d``: its fields) are the paper's as the
    defaults write them: ``friction`` the float 0.0, both ends the str 'pinned', ``pull``
    the float 0.0. Their checks (:meth:`~.friction.FrictionOptions._check_friction_options`)
    would change nothing and raise nothing; any other value is checked."""
    mu, pull, left, right = d["friction"], d["pull"], d["left_end"], d["right_end"]
    return (type(mu) is float and mu == 0.0 and type(pull) is float and pull == 0.0
            and type(left) is str and left == "pinned"
            and type(right) is str and right == "pinned")


def node_stiffness(k: float, rows: np.ndarray, share: np.ndarray) -> np.ndarray | None:
    """k_i = Winkler k × share_i on the wall rows (inf elsewhere); None when rigid."""
    if math.isinf(k):
        return None
    return np.where(rows, k * share, np.inf)


def reachable(node_arclength: np.ndarray, length: float, height: float, ends: str) -> np.ndarray:
    """Which nodes can reach a wall at distance ``height`` from the supports.

    The chain is inextensible and its supports sit on y = 0, so a node at arc
    length s can be at most s from a pin (and ℓ − s from the other pin, when
    both ends are pinned). Nodes that cannot reach the wall get no contact row.
    """
    reach = node_arclength.copy()
    if ends == "pinned-pinned":
        reach = np.minimum(reach, length - node_arclength)
    return within_reach(reach, height)


@dataclass(frozen=True)
class ActuatorScene(FrictionOptions):
    """An actuator bending section pinned at both ends against a rigid wall.

    Parameters
    ----------
    theta : float
        Unconstrained bend angle θ in degrees, in (0, 360).
    height : float
        Wall height h above the pin line (mm), in [1e-6, 1e6] (h > 0: the pins
        sit on y = 0). With ``channel=True`` a second wall sits at −h.
    links : int or "auto"
        Number of links N (an integer in [4, 100000]), or "auto" for the discretisation study of
        Sec. III-D (the smallest N whose force changes by < 0.01 %).
    length : float
        Section length ℓ (mm), in [1e-3, 1e5].
    EI : float
        Bending stiffness (N·mm²), in [1e-6, 1e9].
    weight : float
        Weight per length w (N/mm), in [0, 1e3]; 0 turns gravity off. It acts away
        from the wall (the direction of the reaction), as in eqs. (3), (8).
    channel : bool
        Two walls, at +h and −h (the paper's fixture); a real bool.
    wall_stiffness : float
        Winkler stiffness k of the walls (N/mm per mm of wall, in [1e-9, 1e12]),
        or ``inf`` (default): rigid walls. An elastic wall (tissue) yields: its
        reaction at a node is R_i = k · share_i · indentation (issue 17;
        :mod:`lcpbench.model.elastic`).
    wall_profile : WallProfile or None
        An upper wall of any profile y = h(x) (mm; :mod:`lcpbench.problems.walls`)
        instead of the flat wall at +h; ``height`` is then not used. It must
        cover the chain's x range (0 to ℓ; below 0 too for θ > 180°) and stay
        above the pin line y = 0 there.
    lower_profile : WallProfile or None
        With ``channel=True`` and a ``wall_profile``: the lower wall's profile
        (below y = 0). Default: the mirror image y = −h(x) of the upper wall
        (a symmetric narrowing).
    friction : float or tuple
        Coulomb coefficient μ of the walls (issue 39, docs/friction.md), in [0, 1e3]:
        one number, or one per wall (upper, lower). 0 (default): the paper's
        frictionless walls.
    left_end, right_end : str
        "pinned" (default; both pinned is the paper's support, the right pin on a
        roller), "slider" (held in y, free along x) or "free".
    pull : float
        Axial force P on the right end (N, along +x), which must then be a slider
        or free. A scene with friction, another end or a pull is solved along a
        loading path, :func:`lcpbench.solve_path`.

    Raises
    ------
    ProblemError
        For any field of the wrong type (bools for numbers, strings, arrays,
        complex values, None) or outside its range, naming the field and
        what is allowed (see :mod:`lcpbench.problems.checks`).
    """

    theta: float = 150.0
    height: float = 3.0
    links: int | str = DEFAULT_LINKS
    length: float = DEFAULT_LENGTH
    EI: float = DEFAULT_EI
    weight: float = DEFAULT_WEIGHT
    channel: bool = False
    wall_stiffness: float = math.inf
    wall_profile: WallProfile | None = None
    lower_profile: WallProfile | None = None
    friction: float | tuple[float, ...] = 0.0
    left_end: str = "pinned"
    right_end: str = "pinned"
    pull: float = 0.0

    def __post_init__(self):
        d = self.__dict__
        if not _plain_fields(d):  # (the common case: every field already what the checks
            self._check_fields()  # return, checked in a few comparisons)
        if d["wall_profile"] is not None or d["lower_profile"] is not None:
            self._check_profiles()
        if not paper_options(d):
            self._check_friction()

    def _check_fields(self) -> None:
        """Check and normalise the numbers and the flag, in the order of the fields'
        errors: the first bad one raises."""
        object.__setattr__(self, "wall_stiffness", wall_stiffness(self.wall_stiffness))
        theta = check_number("theta", self.theta, low=THETA_RANGE[0], high=THETA_RANGE[1],
                             low_open=True, high_open=True, unit="degrees")
        object.__setattr__(self, "theta", theta)
        object.__setattr__(self, "height", in_range("height", self.height, HEIGHT_RANGE, "mm"))
        object.__setattr__(self, "links", links_value(self.links))
        object.__setattr__(self, "length", in_range("length", self.length, LENGTH_RANGE, "mm"))
        object.__setattr__(self, "EI", in_range("EI", self.EI, EI_RANGE, "N·mm²"))
        object.__setattr__(self, "weight", in_range("weight", self.weight, WEIGHT_RANGE, "N/mm"))
        object.__setattr__(self, "channel", check_flag("channel", self.channel))

    def _check_friction(self) -> None:
        self._check_friction_options()
        if self.wall_profile is not None and "free" in (self.left_end, self.right_end):
            raise ProblemError("a free end cannot be combined with wall_profile yet: with a "
                               "wall of any profile the ends are 'pinned' or 'slider'")

    def _check_profiles(self) -> None:
        for name in ("wall_profile", "lower_profile"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, WallProfile):
                raise ProblemError(f"{name} must be a WallProfile (lcpbench.problems.walls) "
                                   f"or None, got {describe(value)}")
        if self.lower_profile is not None and not (self.channel and self.wall_profile):
            raise ProblemError("lower_profile needs channel=True and a wall_profile")
        if self.wall_profile is not None and math.isfinite(self.wall_stiffness):
            raise ProblemError("wall_stiffness (an elastic wall) and wall_profile (a wall of "
                               "any profile) cannot be combined yet: give one of them")
        lo, hi = self.x_reach
        if self.wall_profile is not None:
            self.wall_profile.check_for(lo, hi, side="upper", parameter="wall_profile")
        if self.lower_profile is not None:
            self.lower_profile.check_for(lo, hi, side="lower", parameter="lower_profile")

    @property
    def profiles(self) -> tuple[WallProfile | None, WallProfile | None]:
        """(upper, lower) wall profiles of the chain: the lower is the given one, the
        mirror of the upper in a channel, or None."""
        up = self.wall_profile
        if up is None:
            return None, None
        if not self.channel:
            return up, None
        return up, (self.lower_profile if self.lower_profile is not None else up.mirrored())

    @property
    def x_reach(self) -> tuple[float, float]:
        """The x range a node of the pinned chain can occupy here (mm): [0, ℓ], and
        below 0 as far as the unconstrained arc reaches when θ > 180°."""
        half = math.radians(self.theta) / 2
        low = min(0.0, self.radius * (math.sin(half) - 1.0)) if half > math.pi / 2 else 0.0
        return low, float(self.length)

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
        """The Hencky bar chain of this scene (needs an integer ``links``).

        Built once per scene and kept: a scene is immutable, and so is its Chain
        (a frozen dataclass whose arrays nobody writes to), so a second call, or a
        second solve of the same scene, gets the same object."""
        cached = self.__dict__.get("_chain")
        if cached is None:
            cached = self._build_chain()
            self.__dict__["_chain"] = cached  # (a frozen dataclass: not via setattr)
        return cached

    def chain_at(self, fraction: float) -> Chain:
        """The chain with the bend angle θ scaled to s·θ (``fraction`` s): a step of the
        loading path (:mod:`lcpbench.model.ramp`); s = 1 gives :meth:`chain` itself. Built
        as the scene at s·θ: a wall profile's rows and heights follow the arc's x."""
        if fraction == 1.0:
            return self.chain()
        return replace(self, theta=fraction * self.theta).chain()

    def __getstate__(self) -> dict:
        """Pickled without the kept Chain (rebuilt on demand)."""
        return {k: v for k, v in self.__dict__.items() if k != "_chain"}

    def _build_chain(self) -> Chain:
        if self.links == "auto":
            raise ProblemError("links='auto' must be resolved first "
                               "(lcpbench.studies.discretisation.auto_links gives N)")
        n = int(self.links)
        length = float(self.length)
        fr = pinned_frame(n, length)
        a = fr.a
        th = math.radians(self.theta)
        rest_alpha = fr.half_index * th  # th / 2 − half_index · th / n, in place
        rest_alpha /= n
        np.subtract(th / 2, rest_alpha, out=rest_alpha)
        interior = fr.interior  # nodes 2..N
        prof_up, prof_lo = self.profiles
        if prof_up is None:
            up, lo = flat_walls(n, length, self.height, self.channel)
            upper, lower, can = up.copy(), lo.copy(), None
        else:  # rows for the nodes that can reach the wall's lowest point; h at the arc's x
            # x of nodes 2..N: the first N − 1 partial sums of a cos α (np.add.accumulate
            # is sequential: the sums of [0, cumsum][1:N], without the copies)
            x = np.cumsum(a * np.cos(rest_alpha))[:-1]
            # (in a channel, the same rows for both walls: the LCP form pairs them)
            near = prof_up.extremes(*self.x_reach)[0]  # (on a grid, kept with the profile)
            if prof_lo is not None:
                near = min(near, -prof_lo.extremes(*self.x_reach)[1])
            can = within_reach(fr.reach, near)  # (:func:`reachable`, "pinned-pinned")
            upper = np.where(can, prof_up(x), np.inf)
            lower = np.where(can, prof_lo(x), -np.inf) if prof_lo is not None else \
                filled(n - 1, -np.inf).copy()
        k = self.wall_stiffness
        upper_k = lower_k = None
        if k != math.inf:  # elastic walls: k_i = k × share_i on the wall rows
            if can is None:
                can = within_reach(fr.reach, self.height)  # (the rows of flat_walls)
            upper_k = node_stiffness(k, can, fr.share)
            lower_k = upper_k.copy() if self.channel else None
        load = -self.weight * a  # μ = wℓ/N (eq. 5), away from the wall
        return new_chain({
            "links": n,
            "link_length": a,
            "rest_alpha": rest_alpha,
            "joint_stiffness": filled(n - 1, self.EI / a).copy(),
            "joint_links": fr.joints.copy(),
            "rest_joint": full(n - 1, -th / n),
            "link_load": filled(n, load).copy(),
            "free_nodes": interior.copy(),
            "upper": upper,
            "lower": lower,
            "force_scale": self.EI / self.length**2,
            "length": self.length,
            "wall": self.height,
            "channel": bool(self.channel),
            "upper_stiffness": upper_k,
            "lower_stiffness": lower_k,
            "upper_profile": prof_up,
            "lower_profile": prof_lo,
            "consecutive": True,
            "increments": False,
        }, uniform_load(n, load))


_CHAIN_FIELDS = frozenset(f.name for f in fields(Chain))


def new_chain(values: dict, kept: dict | None = None) -> Chain:
    """``Chain(**values)`` with every field given, set at once (a frozen dataclass sets
    them one by one through ``object.__setattr__``: a seventh of a scene's chain);
    ``kept``: values derived from it, kept with it (:meth:`Chain.derived`)."""
    if values.keys() != _CHAIN_FIELDS:
        raise TypeError(f"new_chain needs every field of Chain: "
                        f"{sorted(_CHAIN_FIELDS.symmetric_difference(values))}")
    chain = object.__new__(Chain)
    chain.__dict__.update(values)
    if kept:
        chain.__dict__.update(kept)
    return chain
