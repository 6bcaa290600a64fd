"""Scenes of any section layout: the whole multi-section actuator (issue 17, item 1).

A soft actuator is a row of bending sections (Fig. 1b of the paper): each is
a strain-limited stretch of tube of length ℓ_k that bends into a circular arc
of signed angle θ_k when pressurised (eq. 2, one θ per section). The paper
models one section, pinned at both ends (:class:`~.scenes.ActuatorScene`);
:class:`SectionedScene` models any row of them, pinned at the two ends of the
whole row, between the same walls.

Conventions (docs/sections.md):

* **sign of θ** — θ > 0 bends toward +y, the upper wall at +h (the paper's
  single section, the wall of :class:`~.scenes.ActuatorScene`); θ < 0 toward
  −y (the lower wall of a channel); θ = 0 is straight.
* **links** — one link length a = L/N over the whole length L = Σℓ_k, so
  every section boundary must fall on a node: N ℓ_k / L must be an integer for
  every section (checked; the error names the nearest N that works).
  ``links=None`` takes the paper's density, 140 links per 30 mm (raised to
  the next N that fits).
* **rest shape** — link k's rest angle is the tangent of the unconstrained
  curve at the link's centre (the arcs of the sections joined tangentially),
  turned as a whole so the chord from the left pin to the right pin is
  horizontal (both pins on y = 0). A turn below 1e-13 rad is not made, so a
  symmetric layout, the single section included, keeps its exact angles.
* **a joint inside section k**: stiffness EI_k/a, rest angle −θ_k/n_k (the
  paper's, eq. 18); **a joint on a boundary** between sections k and k+1
  joins the half-links on either side: its spring is the two half-link
  springs in series, 1/k = (a/2)/EI_k + (a/2)/EI_{k+1} (the harmonic mean of
  the two EI over a), and its rest angle is the turn of the rest curve
  between the two link centres, −(θ_k/(2n_k) + θ_{k+1}/(2n_{k+1})).
* **self-weight** — per section (w_k), acting toward −y (``gravity="-y"``,
  the paper's model: away from the upper wall, eqs. 3 and 8) or toward +y
  (``gravity="+y"``).

With one section the chain is :class:`~.scenes.ActuatorScene`'s, array for
array (tests check equality of every array and of the solve).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import cast

import numpy as np

from ..errors import ProblemError
from .cantilever import CantileverScene
from .checks import check_choice, check_flag, check_number, describe
from .friction import FrictionOptions
from .scenes import (
    DEFAULT_EI,
    DEFAULT_LENGTH,
    DEFAULT_LINKS,
    DEFAULT_WEIGHT,
    EI_RANGE,
    HEIGHT_RANGE,
    LENGTH_RANGE,
    MAX_LINKS,
    MIN_LINKS,
    WEIGHT_RANGE,
    ActuatorScene,
    Chain,
    new_chain,
    paper_options,
)
from .templates import filled, flat_walls, pinned_frame, uniform_load

#: Rest shapes turned by less than this (rad) to level their chord are left as they are.
LEVEL_TOL = 1e-13
_add_reduce = np.add.reduce
#: Relative tolerance on N ℓ_k / L being an integer, and on Σℓ_k = length.
FIT_TOL = 1e-9
GRAVITY = ("-y", "+y")
SECTION_THETA_RANGE = (-360.0, 360.0)  # degrees, signed, both ends open


@dataclass(frozen=True)
class Section:
    """One bending section (Fig. 1c): signed bend angle, length, stiffness, weight.

    Parameters
    ----------
    theta : float
        Signed unconstrained bend angle θ (degrees), in (−360, 360): > 0 bends
        toward +y (the upper wall), < 0 toward −y, 0 is straight.
    length : float
        Section length ℓ (mm), in [1e-3, 1e5].
    EI : float
        Bending stiffness (N·mm²), in [1e-6, 1e9].
    weight : float
        Weight per length w (N/mm), in [0, 1e3].
    """

    theta: float
    length: float = DEFAULT_LENGTH
    EI: float = DEFAULT_EI
    weight: float = DEFAULT_WEIGHT

    def __post_init__(self):
        self._check("section")

    def _check(self, where: str) -> None:
        d = self.__dict__
        if _plain_section(d["theta"], d["length"], d["EI"], d["weight"]):
            return  # (every field a float in range: the checks would change nothing)
        put = object.__setattr__
        put(self, "theta", check_number(f"{where}.theta", self.theta,
                                        low=SECTION_THETA_RANGE[0], high=SECTION_THETA_RANGE[1],
                                        low_open=True, high_open=True, unit="degrees"))
        put(self, "length", check_number(f"{where}.length", self.length, low=LENGTH_RANGE[0],
                                         high=LENGTH_RANGE[1], unit="mm"))
        put(self, "EI", check_number(f"{where}.EI", self.EI, low=EI_RANGE[0], high=EI_RANGE[1],
                                     unit="N·mm²"))
        put(self, "weight", check_number(f"{where}.weight", self.weight, low=WEIGHT_RANGE[0],
                                         high=WEIGHT_RANGE[1], unit="N/mm"))


def _plain_section(theta, length, ei, weight) -> bool:
    """Whether a section's fields are Python floats inside their ranges (what
    :meth:`Section._check` returns for them, without an error); otherwise they are
    checked."""
    return (type(theta) is float and SECTION_THETA_RANGE[0] < theta < SECTION_THETA_RANGE[1]
            and type(length) is float and LENGTH_RANGE[0] <= length <= LENGTH_RANGE[1]
            and type(ei) is float and EI_RANGE[0] <= ei <= EI_RANGE[1]
            and type(weight) is float and WEIGHT_RANGE[0] <= weight <= WEIGHT_RANGE[1])


def _section(k: int, item) -> Section:
    """Item ``k`` of ``sections`` as a Section: a Section, a mapping or (θ, ℓ[, EI[, w]])."""
    where = f"sections[{k}]"
    try:
        if isinstance(item, Section):
            return item
        if type(item) is tuple and 1 <= len(item) <= 4:  # (before the Mapping check, a
            return _from_values(item, where)  # slow one: a tuple is none)
        if isinstance(item, Mapping):
            unknown = set(item) - {"theta", "length", "EI", "weight"}
            if unknown or "theta" not in item:
                raise ProblemError(f"{where} must have a theta and only theta, length, EI, "
                                   f"weight; got keys {sorted(item)}")
            sec = Section.__new__(Section)
            for name, default in (("theta", None), ("length", DEFAULT_LENGTH),
                                  ("EI", DEFAULT_EI), ("weight", DEFAULT_WEIGHT)):
                object.__setattr__(sec, name, item.get(name, default))
            sec._check(where)
            return sec
        if isinstance(item, (tuple, list)) and 1 <= len(item) <= 4:
            return _from_values(item, where)
    except ProblemError as exc:
        raise ProblemError(str(exc).replace("section.", f"{where}.")) from None
    raise ProblemError(f"{where} must be a Section, a dict or a tuple (theta, length[, EI"
                       f"[, weight]]), got {describe(item)}")


def _from_values(item, where: str) -> Section:
    """The Section of (θ, ℓ[, EI[, w]]), its fields checked (``where``: its name)."""
    sec = Section.__new__(Section)
    values = list(item) + [DEFAULT_LENGTH, DEFAULT_EI, DEFAULT_WEIGHT][len(item) - 1:]
    sec.__dict__.update(zip(("theta", "length", "EI", "weight"), values, strict=True))
    sec._check(where)
    return sec


@dataclass(frozen=True)
class SectionedScene(FrictionOptions):
    """A row of bending sections, pinned at both ends, against a wall or in a channel.

    Parameters
    ----------
    sections : sequence of Section (or dicts, or tuples (θ, ℓ[, EI[, w]]))
        The sections from the left pin to the right pin; at least one.
    height : float
        Wall height h above the pin line (mm), in [1e-6, 1e6]. With
        ``channel=True`` a second wall sits at −h.
    links : int or None
        N over the whole length, in [4, 100000], such that every section
        boundary falls on a node (N ℓ_k / L an integer). None: the paper's
        density, round(140 L / 30 mm), raised to the next N that fits.
    channel : bool
        Two walls, at +h and −h (the paper's fixture).
    length : float or None
        The total length L (mm), if given checked against Σℓ_k (to 1e-9);
        None: Σℓ_k. After construction it always holds L.
    gravity : "-y" or "+y"
        Direction of the self-weight: "-y" (default, the paper's model, away
        from the upper wall) or "+y" (toward it).
    friction, left_end, right_end, pull :
        Coulomb walls, end conditions and an axial pull on the right end, as for
        :class:`~.scenes.ActuatorScene` (issue 39, docs/friction.md); solved along a
        loading path, :func:`lcpbench.solve_path`.

    Raises
    ------
    ProblemError
        Naming the field: no sections, a section field of the wrong type or
        out of range, lengths that do not add up to ``length``, an N that does
        not put the boundaries on nodes, or a rest shape that closes on itself.
    """

    sections: tuple = ()
    height: float = 3.0
    links: int | None = None
    channel: bool = False
    length: float | None = None
    gravity: str = "-y"
    friction: float | tuple[float, ...] = 0.0
    left_end: str = "pinned"
    right_end: str = "pinned"
    pull: float = 0.0

    def __post_init__(self):
        put = object.__setattr__
        items = self.sections
        if type(items) is not list and type(items) is not tuple and (  # (ABC checks: slow)
                isinstance(items, (str, bytes, Section, Mapping))
                or not isinstance(items, Sequence)):
            raise ProblemError(f"sections must be a list of sections, got {describe(items)}")
        if len(items) == 0:
            raise ProblemError("sections must list at least one section, got none")
        secs = tuple(_section(k, s) for k, s in enumerate(items))
        put(self, "sections", secs)
        put(self, "height", check_number("height", self.height, low=HEIGHT_RANGE[0],
                                         high=HEIGHT_RANGE[1], unit="mm"))
        put(self, "channel", check_flag("channel", self.channel))
        put(self, "gravity", check_choice("gravity", self.gravity, GRAVITY))
        total = math.fsum(s.length for s in secs) if len(secs) > 1 else secs[0].length
        if self.length is not None:
            given = check_number("length", self.length, low=LENGTH_RANGE[0],
                                 high=LENGTH_RANGE[1], unit="mm")
            if abs(given - total) > FIT_TOL * given:
                raise ProblemError(f"length: the sections add up to {total:g} mm, not the "
                                   f"{given:g} mm given")
        if not LENGTH_RANGE[0] <= total <= LENGTH_RANGE[1]:
            raise ProblemError(f"sections: the total length must be in [{LENGTH_RANGE[0]:g}, "
                               f"{LENGTH_RANGE[1]:g}] mm, got {total:g} mm")
        put(self, "length", total)
        links = self.links
        if links is None:
            links = _default_links(secs, total)
        else:
            links = check_number("links", links, low=MIN_LINKS, high=MAX_LINKS, integer=True)
        put(self, "links", int(links))
        self.section_links()  # boundaries on nodes, or ProblemError
        self.__dict__["_rest"] = self.rest_shapes([1.0])  # a chord, or ProblemError (kept
        # for the chain)
        if not paper_options(self.__dict__):  # (the defaults as written need no check)
            self._check_friction_options()

    # -- what the user reads --------------------------------------------------
    @property
    def theta(self) -> float:
        """The largest |θ_k| (degrees): the bend angle of the row's sharpest section."""
        return max(abs(s.theta) for s in self.sections)

    @property
    def EI(self) -> float:
        """EI of the sections (N·mm²); their length-weighted mean when they differ."""
        return self._mean("EI")

    @property
    def weight(self) -> float:
        """w of the sections (N/mm); their length-weighted mean when they differ."""
        return self._mean("weight")

    def _mean(self, name: str) -> float:
        values = [getattr(s, name) for s in self.sections]
        if all(v == values[0] for v in values):
            return float(values[0])
        return math.fsum(v * s.length for v, s in zip(values, self.sections,
                                                       strict=True)) / self._size()[1]

    def _size(self) -> tuple[int, float]:
        """(N, L) after construction (both are set by ``__post_init__``)."""
        return int(cast(int, self.links)), float(cast(float, self.length))

    def with_links(self, links: int) -> SectionedScene:
        return replace(self, links=links)

    def section_links(self) -> np.ndarray:
        """n_k, the links of each section (ints summing to N), or ProblemError. Found once
        per scene and kept (read only)."""
        kept = self.__dict__.get("_section_links")
        if kept is None:
            kept = self.__dict__["_section_links"] = self._fit_links()  # (frozen: not setattr)
            kept.setflags(write=False)
        return kept

    def _fit_links(self) -> np.ndarray:
        n, total = self._size()
        share = [n * s.length / total for s in self.sections]
        counts = [round(x) for x in share]  # (half to even, as np.rint)
        if all(abs(x - c) <= FIT_TOL * max(x, 1.0) and c >= 1
               for x, c in zip(share, counts, strict=True)):
            return np.array(counts, dtype=int)
        raise ProblemError(f"links: N = {n} does not put every section boundary on a node "
                           f"(the sections would span {', '.join(f'{x:.4g}' for x in share)} "
                           f"links); {_nearest(self.sections, total, n)}")

    def section_nodes(self) -> list[tuple[int, int]]:
        """(first, last) 0-based node of each section; section k spans links first..last−1."""
        ends = np.concatenate(([0], np.cumsum(self.section_links())))
        return [(int(ends[k]), int(ends[k + 1])) for k in range(len(self.sections))]

    def rest_alpha(self, fraction: float = 1.0) -> np.ndarray:
        """Link angles α* of the unconstrained row, chord levelled (rad), or ProblemError;
        with every bend angle θ_k scaled to s·θ_k (``fraction`` s) where given."""
        return self.rest_shapes([fraction])[0][0]

    def rest_shapes(self, fractions) -> tuple[np.ndarray, np.ndarray]:
        """(α*, φ*), one row per load fraction s of ``fractions``: the rest shape of the row
        with every bend angle θ_k scaled to s·θ_k, in one pass for a whole loading path
        (:meth:`chains_at`). α*: the link angles, chord levelled (rad), ProblemError where
        the rest shape closes on itself; φ*: the rest joint angles, minus the mean of the
        two links' turns θ_k/n_k."""
        frac = np.asarray(fractions, dtype=float)[:, None]
        th = np.radians(frac * np.array([s.theta for s in self.sections]))  # (path, k)
        counts = self.section_links()
        turn = th[:, 0] if th.shape[1] == 1 else np.array([math.fsum(r) for r in
                                                           th.tolist()])  # (floats)
        before, parts = np.zeros(th.shape[0]), []  # θ > 0 turns clockwise
        for k, (m, mid) in enumerate(zip(counts, self._link_middles(), strict=True)):
            parts.append(turn[:, None] / 2 - before[:, None] - mid * th[:, k:k + 1] / m)
            before = before + th[:, k]
        alpha = np.concatenate(parts, axis=1)
        n, total = self._size()
        a = total / n
        # (np.add.reduce: np.sum without its Python wrapper, the same sum)
        cx = a * _add_reduce(np.cos(alpha), axis=1)
        cy = a * _add_reduce(np.sin(alpha), axis=1)
        chord = np.hypot(cx, cy)
        if not (chord > 1e-6 * total).all():
            raise ProblemError(f"sections: the rest shape closes on itself (its ends are "
                               f"{chord[~(chord > 1e-6 * total)][0]:.3g} mm apart), so it "
                               "cannot be pinned at both ends; change the bend angles")
        tilt = np.array([math.atan2(y, x) for y, x in zip(cy.tolist(), cx.tolist(),
                                                          strict=True)])  # (libm's)
        alpha -= np.where(np.abs(tilt) > LEVEL_TOL, tilt, 0.0)[:, None]
        per_link = (th / counts).repeat(counts, axis=1)  # θ_k/n_k per link
        return alpha, -(0.5 * (per_link[:, :-1] + per_link[:, 1:]))

    # -- the model's view -------------------------------------------------------
    def chain(self) -> Chain:
        """The Hencky bar chain of the whole row (see the module notes).

        Built once per scene and kept, as :meth:`ActuatorScene.chain`: the scene and
        its Chain are immutable, so a second solve of the same scene gets the same
        object (and what the kernels derived from it)."""
        cached = self.__dict__.get("_chain")
        if cached is None:
            cached = self.__dict__["_chain"] = self._build_chain()  # (frozen: not setattr)
        return cached

    def __getstate__(self) -> dict:
        """Pickled without the kept Chain, section links, link middles and rest shape
        (rebuilt on demand)."""
        return {k: v for k, v in self.__dict__.items()
                if k not in ("_chain", "_section_links", "_middles", "_rest")}

    def chain_at(self, fraction: float) -> Chain:
        """The chain of the row with every bend angle θ_k scaled to s·θ_k (``fraction`` s):
        a step of the loading path (:mod:`lcpbench.model.ramp`). Only the rest shape
        (α*, φ*) depends on θ: the other arrays are the whole row's (:meth:`chain`,
        read only), and s = 1 gives that chain itself."""
        if fraction == 1.0:
            return self.chain()
        return self.chains_at([fraction])[0]

    def chains_at(self, fractions) -> list[Chain]:
        """:meth:`chain_at` of each load fraction of ``fractions``, their rest shapes in one
        pass (:meth:`rest_shapes`)."""
        whole = self.chain()
        alpha, joint = self.rest_shapes(fractions)
        return [whole if s == 1.0 else whole.with_rest_shape(alpha[k], joint[k])
                for k, s in enumerate(fractions)]

    def _link_middles(self) -> list[np.ndarray]:
        """Per section, its links' middles in links from its start (0.5, 1.5, …), kept
        with the scene (read only)."""
        kept = self.__dict__.get("_middles")
        if kept is None:
            kept = self.__dict__["_middles"] = [np.arange(m) + 0.5
                                                for m in self.section_links()]
            for mid in kept:
                mid.setflags(write=False)
        return kept

    def _build_chain(self) -> Chain:
        n, total = self._size()
        fr = pinned_frame(n, total)  # (a = L/N, the joints, the interior nodes)
        a = fr.a
        secs = self.sections
        ei0, w0 = secs[0].EI, secs[0].weight
        sign = -1.0 if self.gravity == "-y" else 1.0
        kept = None
        if all(s.EI == ei0 and s.weight == w0
               and math.copysign(1.0, s.weight) == math.copysign(1.0, w0) for s in secs):
            # one EI and one w (the same numbers, elementwise, as the arrays below)
            stiffness = filled(n - 1, ei0 / a).copy()
            load = (sign * w0) * a  # μ = w a (eq. 5)
            link_load = filled(n, load).copy()
            kept = uniform_load(n, load)
        else:
            counts = self.section_links()
            ei = np.repeat([s.EI for s in secs], counts)
            w = np.repeat([s.weight for s in secs], counts)
            left, right = ei[:-1], ei[1:]
            same = left == right
            stiffness = np.where(same, left / a, 2 * left * right / (a * (left + right)))
            link_load = (-w if self.gravity == "-y" else w) * a  # μ = w a (eq. 5)
        # the walls: ±h on the rows of the nodes that can reach them (:func:`reachable`)
        upper, lower = flat_walls(n, total, self.height, self.channel)
        (rest_alpha,), (rest_joint,) = self.__dict__.get("_rest") or self.rest_shapes([1.0])
        return new_chain({
            "links": n,
            "link_length": a,
            "rest_alpha": rest_alpha,
            "joint_stiffness": stiffness,
            "joint_links": fr.joints.copy(),
            "rest_joint": rest_joint,
            "link_load": link_load,
            "free_nodes": fr.interior.copy(),
            "upper": upper.copy(),
            "lower": lower.copy(),
            "force_scale": self.EI / total**2,
            "length": total,
            "wall": self.height,
            "channel": bool(self.channel),
            "upper_stiffness": None,
            "lower_stiffness": None,
            "upper_profile": None,
            "lower_profile": None,
            "consecutive": True,
            "increments": False,
        }, kept)


def _fitting(sections, total: float) -> np.ndarray:
    """Every N in [4, 100000] that puts every section boundary on a node."""
    lengths = np.array([s.length for s in sections]) / total
    m = np.arange(MIN_LINKS, MAX_LINKS + 1)
    share = np.outer(m, lengths)
    ok = np.all((np.abs(share - np.rint(share)) <= FIT_TOL * np.maximum(share, 1.0))
                & (np.rint(share) >= 1), axis=1)
    return m[ok]


def _default_links(sections, total: float) -> int:
    """The paper's density, 140 links per 30 mm, raised to the next N that fits."""
    target = max(MIN_LINKS, round(DEFAULT_LINKS * total / DEFAULT_LENGTH))
    fits = _fitting(sections, total)
    if fits.size == 0:
        raise ProblemError("sections: no N up to 100000 puts every boundary on a node; give "
                           "section lengths in a simpler ratio")
    above = fits[fits >= target]
    return int(above[0] if above.size else fits[-1])


def _nearest(sections, total: float, n: int) -> str:
    """Advice: the numbers of links near ``n`` that put every boundary on a node."""
    fits = _fitting(sections, total)
    if fits.size == 0:
        return "no N up to 100000 does: give section lengths in a simpler ratio"
    below, above = fits[fits < n], fits[fits > n]
    near = [int(below[-1])] if below.size else []
    near += [int(above[0])] if above.size else []
    return "the nearest that do: N = " + " or ".join(map(str, near))


#: The section layouts known by name (``lcpbench solve --sections NAME``).
PRESETS = ("anchoring",)
SECTIONS_SYNTAX = ("THETA:LENGTH[:EI[:WEIGHT]] per section, comma-separated (degrees, mm, "
                   "N*mm^2, N/mm; theta > 0 bends toward the upper wall), or "
                   + " or ".join(repr(p) for p in PRESETS))


def parse_sections(text: str, *, length: float = DEFAULT_LENGTH, EI: float = DEFAULT_EI,
                   weight: float = DEFAULT_WEIGHT) -> tuple[Section, ...]:
    """Sections from the compact text ``"150:30,-150:30:20,150"`` (θ[:ℓ[:EI[:w]]] each).

    A field left out takes ``length``, ``EI`` or ``weight``. Raises
    ProblemError naming ``sections`` (and the item) for anything else.
    """
    if not isinstance(text, str) or not text.strip():
        raise ProblemError(f"sections must be {SECTIONS_SYNTAX}, got {describe(text)}")
    out = []
    for k, item in enumerate(text.split(",")):
        fields = item.strip().split(":")
        try:
            if not 1 <= len(fields) <= 4 or not all(f.strip() for f in fields):
                raise ValueError
            values = [float(f) for f in fields]
        except ValueError:
            raise ProblemError(f"sections must be {SECTIONS_SYNTAX}; item {k + 1} is "
                               f"{item.strip()!r}") from None
        out.append(_section(k, tuple(values + [length, EI, weight][len(values) - 1:])))
    return tuple(out)


def sections_text(scene: SectionedScene) -> str:
    """The compact text of a scene's sections (θ:ℓ, with :EI:w where not the defaults)."""
    parts = []
    for s in scene.sections:
        item = f"{s.theta:g}:{s.length:g}"
        if s.EI != DEFAULT_EI or s.weight != DEFAULT_WEIGHT:
            item += f":{s.EI:g}:{s.weight:g}"
        parts.append(item)
    return ",".join(parts)



def anchoring_actuator(theta: float = 150.0, height: float = 5.5, *, links: int | None = None,
                       length: float = DEFAULT_LENGTH, EI: float = DEFAULT_EI,
                       weight: float = DEFAULT_WEIGHT, gravity: str = "-y",
                       sections: int = 3, **friction) -> SectionedScene:
    """The paper's 3-section anchoring actuator in its two-wall fixture (Fig. 1b, 14).

    Three identical sections of length ℓ bending alternately: the middle one
    toward the upper wall (+θ, the load cell's side, the wall of the paper's
    single-section model), the two end ones toward the lower wall (−θ). The
    pins are the barbed fittings at the two ends of the whole actuator (3ℓ),
    on the mid-line between walls at ±h (Fig. 14b: plate separation 2h, the
    bearing holder set so the pin sits halfway). docs/sections.md gives this
    reading of the fixture.

    Parameters
    ----------
    theta : float
        The bend angle θ of every section (degrees), in (0, 360).
    height : float
        h, the distance of each wall from the pin line (mm): 4.5, 5.5 or 6.5 mm
        in the paper.
    links : int or None
        N over the whole actuator, a multiple of ``sections`` (None: the
        paper's 140 per section, 420 for three).
    length, EI, weight, gravity :
        As for :class:`Section` and :class:`SectionedScene`.
    **friction :
        ``friction``, ``left_end``, ``right_end``, ``pull`` of :class:`SectionedScene`.
    sections : int
        How many alternating sections (odd, 1 to 15; default 3, the paper's):
        the middle one bends toward the upper wall, its neighbours away, and so
        on. One section is the paper's single-section model in the channel.
    """
    theta = check_number("theta", theta, low=0.0, high=360.0, low_open=True, high_open=True,
                         unit="degrees")
    count = int(check_number("sections", sections, low=1, high=15, integer=True))
    if count % 2 == 0:
        raise ProblemError(f"sections must be odd (a middle section toward the upper wall, "
                           f"the others alternating), got {count}")
    signs = [(-1.0) ** abs(k - count // 2) for k in range(count)]
    secs = tuple(Section(sign * theta, length, EI, weight) for sign in signs)
    bad = sorted(set(friction) - {"friction", "left_end", "right_end", "pull"})
    if bad:
        raise ProblemError(f"anchoring_actuator takes friction, left_end, right_end and pull "
                           f"besides its own parameters; got {', '.join(map(repr, bad))}")
    return SectionedScene(sections=secs, height=height, links=links, channel=True,
                          gravity=gravity, **friction)


#: every kind of scene lcpbench solves (here, the one module that sees all three)
SCENE_KINDS = (ActuatorScene, CantileverScene, SectionedScene)


def check_scene(scene) -> object:
    """``scene`` if it is a scene lcpbench can solve, else ProblemError.

    Raises
    ------
    ProblemError
        ``"scene must be an ActuatorScene, SectionedScene or CantileverScene, got
        {'theta': 150}"`` (the value as written) for None, a dict, a string, a class
        instead of an instance, or anything else.
    """
    if isinstance(scene, SCENE_KINDS):
        if getattr(scene, "frictional", False):  # (issue 39: friction, ends, a pull)
            raise ProblemError("this scene has friction, a slider or free end, or a pull: "
                               "solve it along a loading path, lcpbench.solve_path(scene, "
                               "states) (lcpbench.solve is the frictionless model)")
        return scene
    kind = describe(scene)
    if isinstance(scene, type):
        kind = f"the class {scene.__name__} (an instance is needed)"
    raise ProblemError(f"scene must be an ActuatorScene, SectionedScene or CantileverScene, "
                       f"got {kind}")
