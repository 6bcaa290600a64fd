"""``lcpbench solve --friction MU --left-end E --right-end E --pull N [--plot F]`` (issue 39).

The options make the scene frictional (docs/friction.md); such a scene is solved as a
path of one state (:func:`lcpbench.solve_path`) and printed here: the summary, or with
``--json`` the result's fields (``tangential_forces`` in N, ``stick``, ``slip`` in mm,
per node; ``units`` names them); ``--plot`` draws the normal and tangential forces along the chain with stick
and slip marked (:func:`lcpbench.bench.friction_plot.plot_friction_forces`).
"""

from __future__ import annotations

from argparse import ArgumentTypeError

from ..errors import ProblemError
from ..problems.friction import END_CONDITIONS
from ._common import error_line, print_json

_OPTIONS = ("friction", "left_end", "right_end", "pull")
#: the units of the fields of ``--json`` (as ``anchor --json`` gives its own)
UNITS = {"forces": "N", "forces_lower": "N", "tangential_forces": "N", "total_force": "N",
         "pull": "N", "slip": "mm", "x": "mm", "y": "mm", "tol": "rad", "time_s": "s"}


def add_friction_options(parser) -> None:
    """Add ``--friction``, ``--left-end``, ``--right-end`` and ``--pull``."""
    a = parser.add_argument
    a("--friction", type=mu_arg, default=None, metavar="MU",
      help="Coulomb coefficient of the walls: one number, or MU_UPPER,MU_LOWER in a "
           "channel (default 0: frictionless); the scene is then solved along a path")
    a("--left-end", dest="left_end", choices=END_CONDITIONS, default=None,
      help="pinned (default), slider (held in y, free along x) or free")
    a("--right-end", dest="right_end", choices=END_CONDITIONS, default=None,
      help="pinned (default; with a pinned left end it rolls along x, as in the paper), "
           "slider or free")
    a("--pull", type=float, default=None, metavar="N",
      help="axial force on the right end along +x, N (needs --right-end slider or free)")


def mu_arg(text: str):
    """One μ, or a comma-separated one per wall (checked by the scene)."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise ArgumentTypeError(f"a number or MU_UPPER,MU_LOWER, got {text!r}") from None
    return values[0] if len(values) == 1 else tuple(values)


def friction_kw(args) -> dict:
    """The scene's frictional fields given on the command line ({} when none is)."""
    return {k: getattr(args, k) for k in _OPTIONS if getattr(args, k, None) is not None}


def with_friction(scene, args):
    """A row of sections with the frictional options of the command line, where its
    kind of scene takes them; else the scene as it is (the frictional route then
    refuses it in the model's own words: ``solve_path``, ``pull_out``)."""
    kw = friction_kw(args)
    fields = getattr(type(scene), "__dataclass_fields__", {})
    if kw and all(k in fields for k in kw):
        from dataclasses import replace

        return replace(scene, **kw)
    return scene


def wants_friction(args, scene) -> bool:
    """Whether the scene goes the frictional route: it is frictional, or frictional
    options were given for a kind of scene that does not hold them (refused there)."""
    return bool(getattr(scene, "frictional", False)) or (
        bool(friction_kw(args)) and not hasattr(scene, "frictional"))


def refuse_auto_links(args, always: bool = False) -> None:
    """ProblemError for ``--links auto`` on a frictional scene (``always``: the command's
    scenes are all frictional; else when a frictional option is given), before the
    discretisation study would run: it solves the frictionless model."""
    if getattr(args, "links", None) == "auto" and (always or friction_kw(args)):
        raise ProblemError("--links auto is not for a frictional scene (its discretisation "
                           "study solves the frictionless model); give an integer N")


def refuse_options(args, default_solver: str) -> None:
    """ProblemError for the options of ``solve`` that the frictional route does not take."""
    taken = [("--sensitivities", getattr(args, "sensitivities", False)),
             ("--start ramp", getattr(args, "start", "cold") == "ramp"),
             ("--raw", getattr(args, "raw", False)),
             ("--pressure-limit", getattr(args, "pressure_limit", None) is not None)]
    given = [name for name, on in taken if on]
    if given:
        raise ProblemError(f"{', '.join(given)}: not for a frictional scene (--friction, "
                           f"--left-end, --right-end, --pull; solved along a path)")


def solve_frictional(args, scene, default_solver: str) -> int:
    """Solve a frictional scene as a path of one state and print it: 0 converged, 1 not."""
    from ..api import solve_path

    refuse_options(args, default_solver)
    solver = getattr(args, "solver", default_solver)
    (res,) = solve_path(scene, [{}], tol=args.tol,
                        solver=None if solver == default_solver else solver)
    plot_error = None
    if getattr(args, "plot", None) is not None:  # (matplotlib checked by the command)
        from ..bench.friction_plot import plot_friction_forces

        try:
            plot_friction_forces(res, args.plot)
        except (OSError, ValueError) as exc:
            plot_error = f"--plot {args.plot}: {exc}"
    if args.json:
        print_json({**res.to_dict(), "units": UNITS})
    else:
        print(summary(res) + (f"\nplot                {args.plot}"
                              if args.plot is not None and plot_error is None else ""))
    if plot_error is not None:
        error_line(plot_error)
        return 2
    return 0 if res.converged else 1


def summary(res) -> str:
    """A few lines: forces, friction, stick and slip, the verdict."""
    contact = (res.forces + (res.forces_lower if res.forces_lower is not None else 0.0)) > 0
    sliding = contact & ~res.stick
    lines = [
        f"total normal force  {1e3 * res.total_force:.6g} mN over {int(contact.sum())} nodes",
        f"tangential forces   {1e3 * float(res.tangential_forces.sum()):.6g} mN in total "
        f"(pull {1e3 * res.pull:.6g} mN)",
        f"stick / slide       {int(res.stick.sum())} / {int(sliding.sum())} nodes in contact",
        f"largest slip        {float(abs(res.slip).max(initial=0.0)):.3g} mm",
        f"converged           {res.converged} ({res.reason}; {res.outer_iterations} steps)",
        f"step solved by      {res.solver}",
    ]
    return "\n".join(lines)
