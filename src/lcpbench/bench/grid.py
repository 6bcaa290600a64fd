"""Test sets of the benchmark: grids of scenes over θ × h (× N, EI, w, ℓ).

A grid is data: tuples of values per parameter, expanded into
:class:`~lcpbench.problems.scenes.ActuatorScene` objects in a fixed order
(:func:`anchoring_scenes`: the paper's 3-section actuator,
:class:`~lcpbench.problems.sections.SectionedScene`, over θ × h).
Ranges come from the command line as ``start:stop:step`` (stop included,
like the paper's "10° to 180° by 10°"), a comma list ``2,3,5`` or one value.
"""

from __future__ import annotations

import itertools
import json
import math
from dataclasses import asdict, dataclass

from ..errors import ProblemError
from ..problems.scenes import (
    DEFAULT_EI,
    DEFAULT_LENGTH,
    DEFAULT_LINKS,
    DEFAULT_WEIGHT,
    ActuatorScene,
)
from ..problems.sections import SectionedScene, anchoring_actuator

MAX_POINTS = 10_000  # per range: a typo like 0:180:1e-6 is an error, not a hang


def parse_range(text: str, name: str, *, integer: bool = False) -> tuple[float, ...]:
    """Values of a ``start:stop:step`` range (stop included), a comma list, or a number.

    Raises :class:`ProblemError` naming ``name`` for anything else: a
    decreasing or empty range (``10:5:1``), a step <= 0, a non-number
    (``a:b``), or more than :data:`MAX_POINTS` values.
    """
    text = str(text).strip()
    allowed = (f"{name} must be a number, a comma list (2,3,5) or a range start:stop:step "
               "with start <= stop and step > 0")
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) not in (2, 3):
                raise ValueError
            start, stop = float(parts[0]), float(parts[1])
            step = float(parts[2]) if len(parts) == 3 else 1.0
            if not all(math.isfinite(v) for v in (start, stop, step)):
                raise ValueError
            if step <= 0 or stop < start:
                raise ProblemError(f"{allowed}, got {text!r}")
            count = int(math.floor((stop - start) / step * (1 + 1e-12) + 1e-9)) + 1
            if count > MAX_POINTS:
                raise ProblemError(f"{name} range {text!r} has {count} points; at most "
                                   f"{MAX_POINTS} are allowed")
            values = [start + k * step for k in range(count)]
            values = [round(v, 12) for v in values]
        else:
            values = [float(v) for v in text.split(",") if v.strip()]
            if not values or not all(math.isfinite(v) for v in values):
                raise ValueError
    except ValueError:
        raise ProblemError(f"{allowed}, got {text!r}") from None
    if integer:
        if any(v != int(v) for v in values):
            raise ProblemError(f"{name} must be integers, got {text!r}")
        values = [int(v) for v in values]
    return tuple(dict.fromkeys(values))  # drop repeats, keep order


@dataclass(frozen=True)
class Grid:
    """A grid of actuator scenes: every combination of the listed values.

    Attributes
    ----------
    theta : bend angles θ (degrees).
    height : wall heights h (mm).
    links : numbers of links N.
    EI : bending stiffnesses (N·mm²).
    weight : weights per length w (N/mm).
    length : section lengths ℓ (mm).
    channel : two walls (±h) instead of one.
    wall_stiffness : Winkler stiffnesses k of the walls (N/mm per mm; inf: rigid).
    """

    theta: tuple[float, ...]
    height: tuple[float, ...]
    links: tuple[int, ...] = (DEFAULT_LINKS,)
    EI: tuple[float, ...] = (DEFAULT_EI,)
    weight: tuple[float, ...] = (DEFAULT_WEIGHT,)
    length: tuple[float, ...] = (DEFAULT_LENGTH,)
    channel: bool = False
    wall_stiffness: tuple[float, ...] = (math.inf,)

    def __post_init__(self):
        for name in ("theta", "height", "links", "EI", "weight", "length", "wall_stiffness"):
            if len(getattr(self, name)) == 0:
                raise ProblemError(f"the grid is empty: {name} has no values")

    def scenes(self) -> list[ActuatorScene]:
        """Every scene of the grid (validated), θ varying fastest."""
        combos = itertools.product(self.wall_stiffness, self.links, self.length, self.EI,
                                   self.weight, self.height, self.theta)
        return [ActuatorScene(theta=t, height=h, links=n, length=ell, EI=ei, weight=w,
                              channel=self.channel, wall_stiffness=k)
                for k, n, ell, ei, w, h, t in combos]

    def __len__(self) -> int:
        return math.prod(len(getattr(self, k)) for k in
                         ("theta", "height", "links", "EI", "weight", "length",
                          "wall_stiffness"))


#: The paper's grid (Sec. IV, Fig. 8a): θ 10°–180° by 10°, h 2–7 mm by 1, N = 140.
PAPER_GRID = Grid(theta=parse_range("10:180:10", "theta"), height=parse_range("2:7:1", "height"))


#: The tissue grid (issue 17): the paper's heights (Sec. V-C) and pressures (0-25 psi
#: in 2.5-psi steps, θ by actuator 1's calibration, eq. 40) against elastic walls
#: from very soft to rigid, Winkler k in N/mm per mm of wall.
TISSUE_HEIGHTS = (4.5, 5.5, 6.5)
TISSUE_STIFFNESS = (0.01, 0.1, 1.0, math.inf)
TISSUE_PRESSURES = tuple(round(2.5 * i * 6.894757293168361, 2) for i in range(1, 11))  # kPa


def tissue_grid(stiffness: tuple[float, ...] = TISSUE_STIFFNESS,
                heights: tuple[float, ...] = TISSUE_HEIGHTS, *, channel: bool = True,
                links: int = DEFAULT_LINKS) -> Grid:
    """The tissue grid: θ from the paper's pressures (actuator 1, eq. 40) × h × k.

    The paper's fixture is a channel (walls at ±h); both walls get the same k.
    """
    from ..problems.calibrations import get_calibration

    cal = get_calibration(1)
    thetas = tuple(round(float(cal.theta(p)), 9) for p in TISSUE_PRESSURES)
    return Grid(theta=thetas, height=tuple(heights), links=(links,), channel=channel,
                wall_stiffness=tuple(stiffness))


def scene_key(scene: ActuatorScene | SectionedScene) -> str:
    """A canonical text key of a scene (its parameters as sorted JSON).

    A :class:`SectionedScene` keys by its list of sections (a ``"sections"``
    entry no single-section key has), so the two kinds never collide. A rigid
    wall (``wall_stiffness`` inf, the default) is left out of the key, so the
    keys of stores written before elastic walls existed still match; an elastic
    one is in it, so each stiffness is a scene of its own.
    """
    d = asdict(scene)
    for k in ("wall_profile", "lower_profile"):  # flat walls: the key as before profiles
        if d.get(k, "absent") is None:
            del d[k]
        elif k in d:
            raise ProblemError(f"{k}: the benchmark's scenes have flat walls (a scene key "
                               f"cannot hold a wall profile)")
    if getattr(scene, "frictional", False):
        raise ProblemError("friction, a slider or free end, or a pull: the benchmark's scenes "
                           "are frictionless (a scene key cannot hold them)")
    for k in ("friction", "left_end", "right_end", "pull"):  # the key as before friction
        d.pop(k, None)
    d["links"] = int(d["links"])
    if isinstance(scene, SectionedScene):
        d["sections"] = [{k: float(repr_float(v)) for k, v in sec.items()}
                         for sec in d["sections"]]
        for k in ("height", "length"):
            d[k] = float(repr_float(d[k]))
        return json.dumps(d, sort_keys=True)
    for k in ("theta", "height", "length", "EI", "weight"):
        d[k] = float(repr_float(d[k]))
    k = d.pop("wall_stiffness", math.inf)
    if math.isfinite(k):
        d["wall_stiffness"] = float(repr_float(k))
    return json.dumps(d, sort_keys=True)


def repr_float(v: float) -> str:
    """Shortest text that reads back to ``v`` after rounding to 12 significant digits."""
    return repr(float(f"{float(v):.12g}"))


def scene_from_key(key: str) -> ActuatorScene | SectionedScene:
    d = json.loads(key)
    if "sections" in d:
        return SectionedScene(**d)
    return ActuatorScene(**d)


def scene_params(key: str) -> dict:
    """A scene key's parameters, flat: a SectionedScene's as its sharpest θ (the
    anchoring actuator's θ), height, links, total length, EI, w and channel, plus
    ``sections`` (their count), so reports group and label both kinds alike."""
    d = json.loads(key)
    if "sections" not in d:
        return d
    scene = scene_from_key(key)
    return {"theta": scene.theta, "height": scene.height, "links": scene.links,
            "length": scene.length, "EI": scene.EI, "weight": scene.weight,
            "channel": scene.channel, "sections": len(scene.sections)}


#: ``lcpbench sweep --grid anchoring`` defaults: numbers of alternating sections, h (mm),
#: and the paper's pressures (kPa, θ by actuator 1's calibration, eq. 40); ``--theta``
#: gives θ instead. N is 140 per section unless given.
ANCHORING_SECTIONS = (1, 3)
ANCHORING_HEIGHT = "4.5,5.5,6.5"
ANCHORING_LINKS = 3 * DEFAULT_LINKS


def anchoring_scenes(theta: tuple[float, ...] | None, height: tuple[float, ...],
                     links: tuple[int | None, ...] = (None,),
                     EI: tuple[float, ...] = (DEFAULT_EI,),
                     weight: tuple[float, ...] = (DEFAULT_WEIGHT,),
                     length: tuple[float, ...] = (DEFAULT_LENGTH,), *,
                     sections: tuple[int, ...] = (3,),
                     pressure: tuple[float, ...] | None = None,
                     actuator: int = 1) -> list[SectionedScene]:
    """The anchoring actuator over sections × heights × pressures (or θ), θ fastest.

    ``sections``: numbers of alternating sections (odd; 3 is the paper's
    actuator, 1 its single-section model in the same channel). ``pressure``
    (kPa): θ from the calibration of ``actuator`` (eq. 40), instead of
    ``theta``. ``links`` is N over the whole actuator (a multiple of the
    number of sections; None: 140 per section), ``length`` the length of each
    section (:func:`~lcpbench.problems.sections.anchoring_actuator`).
    """
    if (theta is None) == (pressure is None):
        raise ProblemError("the anchoring grid takes bend angles or pressures (one of them)")
    if pressure is not None:
        from ..problems.calibrations import get_calibration

        cal = get_calibration(actuator)
        theta = tuple(round(float(cal.theta(p)), 9) for p in pressure)
    assert theta is not None
    combos = itertools.product(sections, links, length, EI, weight, height, theta)
    return [anchoring_actuator(t, h, links=n, length=ell, EI=ei, weight=w, sections=k)
            for k, n, ell, ei, w, h, t in combos]


def _grazing_height(theta: float, links: int) -> float:
    """Height of the highest node of the weightless unconstrained chain (mm)."""
    from ..model.chain import heights

    chain = ActuatorScene(theta=theta, height=1e3, links=links, weight=0.0).chain()
    return float(heights(chain, chain.rest_alpha).max())


def hard_scenes() -> list[ActuatorScene]:
    """The hard-case suite (issue 5): where back-ends and the undamped driver break.

    θ from 170° to 180°; h down to 0.02·ℓ; N from 10 to 2000; grazing contact
    (the wall 1e-9 mm above and below the highest node of a weightless arc);
    no contact; a heavy chain that sags off the wall; EI from 1 to 1000
    N·mm²; the two-wall channel.
    """
    ell = DEFAULT_LENGTH
    graze = _grazing_height(120.0, DEFAULT_LINKS)
    return [
        ActuatorScene(theta=170.0, height=3.0),
        ActuatorScene(theta=175.0, height=3.0),
        ActuatorScene(theta=180.0, height=3.0),
        ActuatorScene(theta=180.0, height=1.0),
        ActuatorScene(theta=150.0, height=0.02 * ell),
        ActuatorScene(theta=180.0, height=0.02 * ell),
        ActuatorScene(theta=180.0, height=0.02 * ell, links=10),
        ActuatorScene(theta=150.0, height=3.0, links=2000),
        ActuatorScene(theta=180.0, height=0.02 * ell, links=2000),
        ActuatorScene(theta=120.0, height=graze + 1e-9, weight=0.0),  # grazing, just clear
        ActuatorScene(theta=120.0, height=graze - 1e-9, weight=0.0),  # grazing, just touching
        ActuatorScene(theta=40.0, height=3.0),  # no contact
        ActuatorScene(theta=150.0, height=3.0, weight=0.05),  # heavy: sags off the wall
        ActuatorScene(theta=150.0, height=3.0, EI=1.0),
        ActuatorScene(theta=150.0, height=3.0, EI=1000.0),
        ActuatorScene(theta=180.0, height=1.0, channel=True),
    ]
