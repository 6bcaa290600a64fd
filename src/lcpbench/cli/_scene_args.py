"""The scene and back-end options shared by ``solve``, ``export`` and ``select``.

One block of arguments describes an :class:`~lcpbench.problems.scenes.ActuatorScene`
(``--theta`` or ``--pressure`` with ``--actuator``/``--fit``, ``--height``,
``--links``, ``--length``, ``--EI``, ``--weight``, ``--channel``);
:func:`scene_from` turns the parsed block back into the scene. The defaults
are read from their owners (the scene's dataclass fields and the signature of
:func:`lcpbench.solve`) rather than repeated here.
"""

from __future__ import annotations

import argparse
import inspect
import math
import sys

from ..api import PAPER_TOL, solve
from ..errors import ProblemError
from ..problems.scenes import (
    DEFAULT_EI,
    DEFAULT_LENGTH,
    DEFAULT_LINKS,
    DEFAULT_WEIGHT,
    MIN_LINKS,
    ActuatorScene,
)
from ..solvers.base import PROFILES
from ._friction_args import friction_kw, with_friction
from ._units import implausible, quantity_type

_FIELDS = ActuatorScene.__dataclass_fields__
DEFAULT_THETA = _FIELDS["theta"].default
DEFAULT_HEIGHT = _FIELDS["height"].default
_SOLVE = inspect.signature(solve).parameters
DEFAULT_TOL = PAPER_TOL
DEFAULT_SOLVER = _SOLVE["solver"].default
DEFAULT_METHOD = _SOLVE["method"].default


def links_arg(text: str) -> int | str:
    """Argument type of ``--links``: an integer or ``'auto'``.

    Parameters
    ----------
    text : str
        The word given on the command line.

    Returns
    -------
    int or str
        The number of links, or ``"auto"``.
    """
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"links must be an integer >= {MIN_LINKS} or 'auto', got {text!r}"
        ) from None


def add_scene_options(parser) -> None:
    """Add the options that describe one actuator scene.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser; :func:`scene_from` reads the result.
    """
    a = parser.add_argument
    a("--theta", type=quantity_type("angle", "theta"), default=None, metavar="DEG",
      help=f"unconstrained bend angle in (0, 360) degrees; a bare number is degrees, or "
           f"give the unit: 150deg, 2.618rad (default {DEFAULT_THETA:g})")
    a("--pressure", type=float, default=None, metavar="KPA",
      help="input pressure instead of --theta: theta from the actuator's "
           "calibration (eqs. 40-42 of the paper, kPa)")
    a("--actuator", default="1", metavar="1|2|3",
      help="which of the paper's calibrations --pressure uses (default 1)")
    a("--fit", default=None, metavar="SLOPE,INTERCEPT",
      help="your own calibration theta = SLOPE * P + INTERCEPT (degrees, P in "
           "the unit of --pressure) instead of --actuator")
    # default None, so that a --height given beside --wall-profile can be refused
    a("--height", type=quantity_type("length", "height"), default=None,
      metavar="MM", help=f"wall height above the pins; a bare number is mm, or give the "
                         f"unit: 3mm, 0.003m (default {DEFAULT_HEIGHT:g}; not with "
                         f"--wall-profile)")
    a("--links", type=links_arg, default=None, metavar="N|auto",
      help=f"number of links, or 'auto' (default {DEFAULT_LINKS}; with --sections N over "
           f"the whole length, default {DEFAULT_LINKS} per {DEFAULT_LENGTH:g} mm)")
    a("--length", type=quantity_type("length", "length"), default=DEFAULT_LENGTH,
      metavar="MM", help=f"section length; bare: mm, or 30mm, 0.03m (default "
                         f"{DEFAULT_LENGTH:g})")
    a("--EI", type=quantity_type("stiffness", "EI"), default=DEFAULT_EI, metavar="NMM2",
      help=f"bending stiffness; bare: N*mm^2, or 32.01N*mm^2, 3.2e-5N*m^2 (default "
           f"{DEFAULT_EI:g})")
    a("--weight", type=quantity_type("weight", "weight"), default=DEFAULT_WEIGHT,
      metavar="NPMM", help=f"weight per length; bare: N/mm, or 0.245N/m; 0 turns gravity "
                           f"off (default {DEFAULT_WEIGHT:g})")
    a("--channel", action="store_true", help="a second wall at -height (the paper's fixture)")


def add_section_options(parser) -> None:
    """Add ``--sections`` and ``--gravity``: a row of sections instead of one.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser; :func:`scene_from` reads the result.
    """
    from ..problems.sections import SECTIONS_SYNTAX

    parser.add_argument(
        "--sections", default=None, metavar="SPEC",
        help=f"a row of bending sections pinned at its two ends (SectionedScene): "
             f"{SECTIONS_SYNTAX}; e.g. 150:30,-90:20:40 (fields left out take --length, "
             f"--EI, --weight). 'anchoring' is the paper's 3-section actuator (Fig. 1b): "
             f"sections -theta, +theta, -theta of --length each, theta from --theta or "
             f"--pressure, always in the channel (walls at +-height)")
    parser.add_argument(
        "--gravity", choices=("away", "toward"), default="away",
        help="with --sections: the self-weight acts away from the upper wall (default, the "
             "paper's model) or toward it")


def add_profile_options(parser) -> None:
    """Add ``--wall-profile FILE.csv``, ``--lower-profile FILE.csv`` and ``--profile-kind``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser (``solve``); :func:`scene_from` reads them.
    """
    a = parser.add_argument
    a("--wall-profile", default=None, metavar="FILE.csv",
      help="upper wall of any profile y = h(x) instead of the flat wall at --height: a CSV "
           "with a header line, then x,y rows in mm covering 0..length, y > 0")
    a("--lower-profile", default=None, metavar="FILE.csv",
      help="with --channel and --wall-profile: the lower wall's profile (y < 0); default "
           "the mirror image y = -h(x) of the upper wall")
    a("--profile-kind", choices=("pchip", "linear", "cubic"), default="pchip",
      help="interpolation of the profile tables: pchip (C1, no overshoot; default), "
           "linear (piecewise linear: kinks), cubic (natural spline, C2)")


def add_wall_options(parser) -> None:
    """Add ``--wall-stiffness`` and ``--pressure-limit`` (elastic, tissue-like walls).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser (``solve``).
    """
    add_wall_stiffness_option(parser)
    a = parser.add_argument
    a("--pressure-limit", type=float, default=None, metavar="NPMM",
      help="safety threshold on the contact pressure per length, N/mm: the run says "
           "when the largest pressure passes it")


def add_wall_stiffness_option(parser) -> None:
    """Add ``--wall-stiffness`` (elastic, tissue-like walls; ``solve`` and ``anchor``)."""
    parser.add_argument("--wall-stiffness", type=float, default=math.inf, metavar="K",
                        help="Winkler stiffness of the walls, N/mm per mm of wall; 'inf' is "
                             "a rigid wall (default inf)")


def add_tol_option(parser, what: str = "convergence threshold on max|d alpha|",
                   by_settings: bool = True) -> None:
    """Add ``--tol RAD``, the driver's convergence threshold (default None: the
    ``--settings`` profile's ``driver_tol``, :data:`lcpbench.solvers.base.PROFILES`).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser.
    what : str
        The start of the help text.
    by_settings : bool
        Whether the command has ``--settings`` (the help names the profiles' tols).
    """
    said = ("the --settings profile's: " + ", ".join(
        f"{n} {s.driver_tol:g}" for n, s in PROFILES.items())) if by_settings \
        else f"{DEFAULT_TOL:g}"
    parser.add_argument("--tol", type=float, default=None, metavar="RAD",
                        help=f"{what}, rad (default {said})")


def add_solver_options(parser, default: str | None = DEFAULT_SOLVER,
                       default_help: str | None = None) -> None:
    """Add ``--solver NAME`` and ``--settings PROFILE``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser.
    default : str or None
        The default back-end (None: the command chooses).
    default_help : str, optional
        What the help says the default is (default: its name).
    """
    said = default if default_help is None else default_help
    parser.add_argument("--solver", default=default, metavar="NAME",
                        help=f"back-end (default {said}; `lcpbench solvers` lists them)")
    parser.add_argument("--settings", choices=tuple(PROFILES), default="default",
                        help="accuracy profile, one for the whole solve (back-end "
                             "tolerance and driver --tol): default (the back-end's own "
                             "defaults, 1e-3 rad), low 1e-3, mid 1e-6, high 1e-9 "
                             "(default: default)")


def scene_from(args, *, resolve_links: bool = True):
    """The scene described by the options of :func:`add_scene_options`.

    ``--links auto`` runs the discretisation study of Sec. III-D (several
    solves) and says on stderr which N it picked, unless ``resolve_links`` is
    False (``select`` refuses it: its kind of scene includes N).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    ActuatorScene or SectionedScene
        With theta from ``--theta``, or from ``--pressure`` through the
        calibration of ``--actuator`` or ``--fit``; a SectionedScene with
        ``--sections`` (where the parser has it).

    Raises
    ------
    ProblemError
        When the options contradict each other or a value is out of range.
    """
    scene = _scene_as_given(args)
    if scene.links != "auto" or not resolve_links:
        return scene
    from ..api import check_tol
    from ..solvers.registry import get_backend
    from ..studies.discretisation import auto_links

    solver = getattr(args, "solver", "auto")
    get_backend(solver)  # a bad --solver or --tol fails before the study's solves
    if getattr(args, "tol", None) is not None:
        check_tol(args.tol)
    n = auto_links(scene, solver=solver)
    print(f"links auto: the discretisation study (Sec. III-D) picked N = {n}", file=sys.stderr)
    return scene.with_links(n)


def _scene_as_given(args):
    sections = getattr(args, "sections", None)
    if sections is not None and (getattr(args, "wall_profile", None) is not None
                                 or getattr(args, "lower_profile", None) is not None):
        raise ProblemError("--sections takes flat walls at +-height: drop --wall-profile and "
                           "--lower-profile (a wall profile is for one section)")
    if args.height is not None and getattr(args, "wall_profile", None) is not None:
        raise ProblemError("--height sets the height of a flat wall and --wall-profile gives "
                           "the wall instead (--height would be ignored): drop one of them")
    height = DEFAULT_HEIGHT if args.height is None else args.height
    if sections is not None and getattr(args, "wall_stiffness", math.inf) != math.inf:
        raise ProblemError("--wall-stiffness (elastic walls) is for one section: drop it or "
                           "--sections")
    if sections is not None and sections.strip() != "anchoring":
        return _sectioned(args, sections, height)
    if getattr(args, "gravity", "away") != "away" and sections is None:
        raise ProblemError("--gravity needs --sections (the single section's weight acts "
                           "away from the wall, as in the paper)")
    for warning in implausible(args.theta, height, args.length):
        print(f"lcpbench: warning: {warning}", file=sys.stderr)
    links = DEFAULT_LINKS if args.links is None else args.links
    kw = {"height": height, "links": links, "length": args.length, "EI": args.EI,
          "weight": args.weight, "channel": args.channel, **_profiles(args),
          **friction_kw(args)}
    if getattr(args, "wall_stiffness", math.inf) != math.inf:
        kw["wall_stiffness"] = args.wall_stiffness
    if sections is not None:  # the anchoring preset: theta as for one section
        if args.links == "auto":
            raise ProblemError("--links auto is for one section; give N (a multiple of 3) "
                               "with --sections anchoring")
        one = _single(args, {**kw, "links": DEFAULT_LINKS})
        from ..problems.sections import anchoring_actuator

        return with_friction(anchoring_actuator(one.theta, height, links=args.links,
                                                length=args.length, EI=args.EI,
                                                weight=args.weight,
                                                gravity=_GRAVITY[args.gravity]), args)
    return _single(args, kw)


_GRAVITY = {"away": "-y", "toward": "+y"}


def _sectioned(args, text: str, height: float):
    """``--sections THETA:LENGTH,...``: the SectionedScene it describes."""
    from ..problems.sections import SectionedScene, parse_sections

    if args.theta is not None or args.pressure is not None:
        raise ProblemError("--sections gives every section its own theta: drop --theta and "
                           "--pressure (or use --sections anchoring)")
    if args.links == "auto":
        raise ProblemError("--links auto is for one section; give N with --sections")
    secs = parse_sections(text, length=args.length, EI=args.EI, weight=args.weight)
    return with_friction(SectionedScene(sections=secs, height=height, links=args.links,
                                        channel=args.channel,
                                        gravity=_GRAVITY[args.gravity]), args)


def _single(args, kw: dict) -> ActuatorScene:
    if args.pressure is None:
        if args.fit is not None:
            raise ProblemError("--fit needs --pressure")
        theta = DEFAULT_THETA if args.theta is None else args.theta
        return ActuatorScene(theta=theta, **kw)
    from ..problems.calibrations import scene_from_pressure

    if args.theta is not None:
        raise ProblemError("give --theta or --pressure, not both (the calibration sets theta)")
    return scene_from_pressure(args.pressure, calibration_from(args), **kw)


def calibration_from(args):
    """The calibration θ(P) of ``--fit SLOPE,INTERCEPT``, else of ``--actuator``."""
    from ..problems.calibrations import get_calibration, linear_calibration

    if args.fit is None:
        return get_calibration(args.actuator, param="actuator")
    try:
        slope, intercept = (float(v) for v in args.fit.split(","))
    except ValueError:
        raise ProblemError(f"fit must be SLOPE,INTERCEPT (two numbers), got "
                           f"{args.fit!r}") from None
    return linear_calibration(slope, intercept)


def _profiles(args) -> dict:
    """The wall profiles of ``--wall-profile``/``--lower-profile`` as scene fields."""
    upper = getattr(args, "wall_profile", None)
    lower = getattr(args, "lower_profile", None)
    if upper is None and lower is None:
        return {}
    from ..problems.walls import load_profile_csv

    if upper is None:
        raise ProblemError("--lower-profile needs --wall-profile and --channel")
    if lower is not None and not args.channel:
        raise ProblemError("--lower-profile needs --channel")
    kind = getattr(args, "profile_kind", "pchip")
    out = {"wall_profile": load_profile_csv(upper, kind, parameter="--wall-profile")}
    if lower is not None:
        out["lower_profile"] = load_profile_csv(lower, kind, parameter="--lower-profile")
    return out
