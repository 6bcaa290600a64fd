"""``lcpbench cycle``: a load–unload cycle against walls with friction (issue 39).

::

    lcpbench cycle --friction 0.1,0.3 [--height MM] [--channel] [--pressure A:B:STEP]
                   [--actuator 1|2|3] [--links N] [--tol RAD] [--json] [--plot F.png]

The actuator is inflated through the pressures and deflated again at one wall height,
as one loading path for each μ (:func:`lcpbench.studies.load_cycle.load_cycle`, each
state from the last, θ from the actuator's calibration), on the model's support (a pin
and a roller). It prints ΣN over every wall (mN) per pressure on the way up and down,
beside the frictionless model's; ``--plot`` draws them (the hysteresis,
:func:`lcpbench.bench.friction_plot.plot_load_cycle`). Exit status 0 when every state
converged, 1 when some did not (named), 2 on bad input.
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from ._common import add_json_option, error_line, format_rows, has_matplotlib, print_json
from ._units import quantity_type

#: the paper's pressures: 0 to 25 psi in steps of 2.5 psi (kPa)
PAPER_PSI_STEPS = (0.0, 25.0, 2.5)
#: the study's N (docs/friction.md, "The study"; the figure of results/friction/)
DEFAULT_CYCLE_LINKS = 40
DEFAULT_CYCLE_HEIGHT = 5.5


def register(subparsers) -> None:
    """Add ``cycle`` to the command line."""
    a = subparsers.add_parser(
        "cycle", help="a load-unload cycle of pressure against contact force, with friction",
        description="Inflate the actuator through the input pressures and deflate it again "
                    "at one wall height, as a loading path for each friction coefficient "
                    "(docs/friction.md, Figures): the total normal force on the way up and "
                    "down beside the frictionless model's (the hysteresis).")
    a.add_argument("--friction", required=True, metavar="LIST",
                   help="Coulomb coefficients mu of the walls, one cycle each: a number, a "
                        "comma list or A:B:STEP (>= 0)")
    a.add_argument("--height", type=quantity_type("length", "height"),
                   default=DEFAULT_CYCLE_HEIGHT, metavar="MM",
                   help=f"wall height above the pins, mm (default {DEFAULT_CYCLE_HEIGHT:g})")
    a.add_argument("--channel", action="store_true",
                   help="a second wall at -height (the paper's fixture)")
    a.add_argument("--pressure", default=None, metavar="A:B:STEP|LIST",
                   help="increasing input pressures, kPa (default the paper's 0-25 psi in "
                        "2.5-psi steps, 0-172.37 kPa); the cycle goes up through them and "
                        "back down")
    a.add_argument("--actuator", default="1", metavar="1|2|3",
                   help="the paper's calibration theta(P) (default 1, eq. 40)")
    a.add_argument("--links", type=int, default=DEFAULT_CYCLE_LINKS, metavar="N",
                   help=f"number of links (default {DEFAULT_CYCLE_LINKS})")
    a.add_argument("--tol", type=float, default=1e-8, metavar="RAD",
                   help="convergence threshold of each state, rad (default 1e-8)")
    add_json_option(a)
    a.add_argument("--plot", metavar="FILE.png",
                   help="draw the contact force against the pressure, loading and unloading "
                        "(needs matplotlib)")
    a.set_defaults(func=cmd_cycle)


def pressures_from(text) -> np.ndarray:
    """The cycle's increasing pressures (kPa) from ``--pressure`` (None: the paper's)."""
    from ..bench.grid import parse_range
    from ..problems.calibrations import KPA_PER_PSI

    if text is None:
        lo, hi, step = PAPER_PSI_STEPS
        return np.arange(lo, hi + step / 2, step) * KPA_PER_PSI
    values = np.asarray(parse_range(text, "pressure"), float)
    typed = [v for v in str(text).split(",") if v.strip()]
    if ":" not in str(text) and (len(typed) != values.size  # (parse_range drops repeats)
                                 or np.any(np.diff([float(v) for v in typed]) <= 0)):
        raise ProblemError(f"--pressure must be increasing, each value once (kPa), got "
                           f"{text!r}")
    return values


def cmd_cycle(args) -> int:
    """``lcpbench cycle``: 0 every state converged, 1 not, 2 bad input or plot error."""
    from ..bench.grid import parse_range
    from ..problems.scenes import ActuatorScene
    from ..studies.load_cycle import load_cycle

    if args.plot is not None and not has_matplotlib():
        error_line("--plot needs matplotlib: pip install 'lcpbench[plot]'")
        return 2
    mus = parse_range(args.friction, "friction")
    pressures = pressures_from(args.pressure)
    if not np.isfinite(args.tol) or args.tol <= 0:
        raise ProblemError(f"tol must be a positive number (rad), got {args.tol!r}")
    cycles = [load_cycle(ActuatorScene(theta=90.0, height=float(args.height), links=args.links,
                                       channel=args.channel, friction=mu),
                         pressures, actuator=args.actuator, tol=args.tol)
              for mu in mus]  # (each scene checks its μ, h and N: one line if bad)
    plot_error = None
    if args.plot is not None:
        from ..bench.friction_plot import plot_load_cycle

        try:
            plot_load_cycle(cycles, args.plot)
        except (OSError, ValueError) as exc:
            plot_error = f"--plot {args.plot}: {exc}"
    if args.json:
        print_json(cycle_json(cycles, mus, args))
    else:
        print(summary(cycles, mus, args, None if plot_error else args.plot))
    if plot_error is not None:
        error_line(plot_error)
        return 2
    return 0 if all(bool(c.converged.all()) for c in cycles) else 1


def cycle_json(cycles, mus, args) -> dict:
    """The JSON answer: one entry per μ, per state of its path (N, kPa, degrees)."""
    first = cycles[0]
    return {
        "height": float(args.height), "channel": args.channel, "links": args.links,
        "actuator": args.actuator, "pressure": first.pressure, "theta": first.theta,
        "loading": first.loading, "frictionless_force": first.frictionless,
        "cycles": [{"friction": float(mu), "force": c.force, "converged": c.converged,
                    "reasons": [r.reason for r in c.path]}
                   for mu, c in zip(mus, cycles, strict=True)],
        "units": {"height": "mm", "pressure": "kPa", "theta": "deg",
                  "frictionless_force": "N", "cycles.force": "N"},
    }


def summary(cycles, mus, args, plot) -> str:
    """A table of ΣN (mN) per pressure, up and down per μ, then the verdict."""
    first = cycles[0]
    up = first.branch(True)[0]
    head = ["P (kPa)", "theta", "mu = 0"] + [f"mu = {m:g} up / down" for m in mus]
    rows = []
    for p in up:
        at = np.flatnonzero(np.isclose(first.pressure, p))
        ref = first.frictionless[at[0]]
        cells = [f"{p:.2f}", f"{first.theta[at[0]]:.2f}", f"{1e3 * ref:.2f}"]
        for c in cycles:
            (pu, fu), (pd, fd) = c.branch(True), c.branch(False)
            cells.append(f"{1e3 * fu[np.isclose(pu, p)][0]:.2f} / "
                         f"{1e3 * fd[np.isclose(pd, p)][0]:.2f}")
        rows.append(cells)
    widths = [max(len(h), *(len(r[k]) for r in rows)) for k, h in enumerate(head)]
    lines = ["  ".join(h.rjust(w) for h, w in zip(head, widths, strict=True))]
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    bad = [f"mu {m:g} at {c.pressure[k]:.4g} kPa ({'up' if c.loading[k] else 'down'}): "
           f"{c.path[k].reason}" for m, c in zip(mus, cycles, strict=True)
           for k in np.flatnonzero(~c.converged)]
    info = [("scene", f"h={args.height:g} mm" + (", channel" if args.channel else "")
             + f", N={args.links}, actuator {args.actuator}, a pin and a roller; "
               "total normal force over every wall, mN"),
            ("converged", "every state" if not bad else
             f"no: {len(bad)} states did not ({'; '.join(bad[:3])}"
             + (", ..." if len(bad) > 3 else "") + ")")]
    if plot is not None:
        info.append(("plot", plot))
    return format_rows(info) + "\n" + "\n".join(lines)
