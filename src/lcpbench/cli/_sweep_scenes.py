"""The scenes of ``lcpbench sweep`` and ``lcpbench export-testset``: ``--grid`` and its lists.

``--grid paper`` (θ × h × N, EI, w, ℓ, walls), ``hard`` (the fixed hard-case
suite), ``anchoring`` (rows of alternating sections × heights × pressures or
θ) and ``tissue`` (elastic walls: the paper's pressures × h × k). Every scene
is validated before anything runs.
"""

from __future__ import annotations

from ..errors import ProblemError
from ..problems.scenes import DEFAULT_LINKS

#: the unit table (cli/_units.py) of each sweep list that takes unit suffixes
_RANGE_UNITS = {"theta": "angle", "height": "length", "length": "length",
                "EI": "stiffness", "weight": "weight"}


def in_model_units(text: str | None, name: str) -> str | None:
    """A range or list whose items may carry units (``2mm:7mm:1mm``, ``0.17rad,2.6rad``),
    rewritten in the model's units for :func:`~lcpbench.bench.grid.parse_range`."""
    import argparse
    import re

    from ._units import parse_quantity

    if text is None or name not in _RANGE_UNITS:
        return text
    items = re.split(r"([:,])", str(text))
    out = []
    for item in items:
        if item in (":", ",") or not item.strip() or not re.search(r"[^\d.eE+\-\s]", item):
            out.append(item)  # separators, blanks and bare numbers: as they are
            continue
        try:
            out.append(repr(float(parse_quantity(item, _RANGE_UNITS[name], name))))
        except argparse.ArgumentTypeError as exc:
            raise ProblemError(str(exc)) from None
    return "".join(out)


def _float_list(text, name) -> tuple | None:
    from ..bench.grid import parse_range

    return None if text is None else parse_range(in_model_units(text, name), name)


def _stiffness_list(text) -> tuple[float, ...] | None:
    """``--wall-stiffness``: a comma list of Winkler k (N/mm per mm) or inf; checked."""
    if text is None:
        return None
    from ..problems.scenes import wall_stiffness

    try:
        values = tuple(float(v) for v in str(text).split(",") if v.strip())
    except ValueError:
        raise ProblemError(f"wall-stiffness must be a comma list of numbers > 0 or inf "
                           f"(N/mm per mm of wall), got {text!r}") from None
    if not values:
        raise ProblemError("wall-stiffness must list at least one stiffness")
    return tuple(wall_stiffness(v) for v in values)


def sweep_scenes(args) -> list:
    """The scenes of ``--grid``, validated before anything runs."""
    from ..bench import grid as grids
    from ..bench.grid import Grid, hard_scenes, parse_range

    stiffness = _stiffness_list(getattr(args, "wall_stiffness", None))
    if args.grid == "hard":
        given = [f"--{n}" for n in ("theta", "height", "EI", "weight", "length")
                 if getattr(args, n) is not None] + (["--channel"] if args.channel else [])
        if stiffness is not None:
            given.append("--wall-stiffness")
        if given or args.links is not None:
            raise ProblemError("--grid hard is a fixed list of scenes; it takes no "
                               f"{', '.join(given) or '--links'}")
        return hard_scenes()
    if args.grid == "anchoring":
        if stiffness is not None:
            raise ProblemError("--grid anchoring has rigid walls; it takes no --wall-stiffness")
        pressure, count = getattr(args, "pressure", None), getattr(args, "sections_count", None)
        if args.theta is not None and pressure is not None:
            raise ProblemError("give --theta or --pressure, not both (the calibration sets theta)")
        kw = {"theta": None if args.theta is None else
              parse_range(in_model_units(args.theta, "theta"), "theta"),
              "pressure": (grids.TISSUE_PRESSURES if args.theta is None and pressure is None
                           else None if pressure is None else parse_range(pressure, "pressure")),
              "sections": (grids.ANCHORING_SECTIONS if count is None
                           else parse_range(count, "sections-count", integer=True)),
              "height": parse_range(in_model_units(args.height or grids.ANCHORING_HEIGHT,
                                                    "height"), "height"),
              "links": (None,) if args.links is None else parse_range(args.links, "links",
                                                                       integer=True)}
        for name in ("EI", "weight", "length"):
            values = _float_list(getattr(args, name), name)
            if values is not None:
                kw[name] = values
        return grids.anchoring_scenes(**kw)  # validates every scene before anything runs
    for name in ("pressure", "sections_count"):
        if getattr(args, name, None) is not None:
            raise ProblemError(f"--{name.replace('_', '-')} is for --grid anchoring")
    if args.grid == "tissue":
        from ..bench.grid import TISSUE_HEIGHTS, TISSUE_STIFFNESS, tissue_grid

        given = [f"--{n}" for n in ("theta", "EI", "weight", "length")
                 if getattr(args, n) is not None]
        if given:
            raise ProblemError("--grid tissue sets theta from the paper's pressures; it "
                               f"takes no {', '.join(given)}")
        heights = (parse_range(in_model_units(args.height, "height"), "height")
                   if args.height is not None else TISSUE_HEIGHTS)
        links = parse_range(args.links or str(DEFAULT_LINKS), "links", integer=True)
        tissue = [tissue_grid(stiffness or TISSUE_STIFFNESS, heights, links=int(n))
                  for n in links]
        return [sc for g in tissue for sc in g.scenes()]
    grid_kw = {"theta": parse_range(in_model_units(args.theta or "10:180:10", "theta"),
                                    "theta"),
               "height": parse_range(in_model_units(args.height or "2:7:1", "height"),
                                     "height"),
               "links": parse_range(args.links or str(DEFAULT_LINKS), "links", integer=True),
               "channel": args.channel}
    if stiffness is not None:
        grid_kw["wall_stiffness"] = stiffness
    for name in ("EI", "weight", "length"):
        values = _float_list(getattr(args, name), name)
        if values is not None:
            grid_kw[name] = values
    return Grid(**grid_kw).scenes()  # validates every scene before anything runs


