"""``lcpbench fit``: EI (and the θ(P) line) from measured forces or photographed shapes
(issue 38, item 3).

    lcpbench fit --data F.csv [--fit-theta] [scene options] [--json] [--plot F.png]
    lcpbench fit --shapes S.csv [scene options] [--json]

F.csv has a header ``pressure_kpa,force_n`` (optionally ``height_mm``) and a row per
measurement (:func:`lcpbench.studies.fit.fit`). S.csv has a header
``shape,pressure_kpa,height_mm`` and a row per photograph: the JSON ``lcpbench vision
measure --json`` wrote, its pressure, and the wall height (empty: a free actuator)
(:mod:`lcpbench.vision.shapes_fit`).
"""

from __future__ import annotations

import numpy as np

from ..errors import ProblemError
from ._common import add_json_option, error_line, has_matplotlib, print_json
from ._scene_args import add_scene_options, add_wall_options, calibration_from, scene_from


def register(subparsers) -> None:
    f = subparsers.add_parser(
        "fit", help="fit EI (and the theta(P) line) to measured force-pressure data",
        description="Fit the bending stiffness EI (N mm^2), and with --fit-theta the "
                    "calibration line theta = slope * P + intercept, to measured total "
                    "forces by Gauss-Newton on lcpbench's sensitivities; print the values, "
                    "95 %% intervals and the residuals. The scene options give the rest "
                    "(N, length, weight, walls; --EI the starting value; --actuator or --fit "
                    "the calibration).")
    what = f.add_mutually_exclusive_group(required=True)
    what.add_argument("--data", metavar="F.csv",
                      help="CSV with columns pressure_kpa,force_n[,height_mm]")
    what.add_argument("--shapes", metavar="S.csv",
                      help="CSV with columns shape,pressure_kpa,height_mm: per photograph "
                           "the JSON of 'lcpbench vision measure --json', its pressure and "
                           "the wall's centre-line height (empty: free); free shapes fit "
                           "the theta(P) line, pressed ones EI")
    f.add_argument("--fit-theta", action="store_true",
                   help="fit the calibration line's slope and intercept too")
    f.add_argument("--tol", type=float, default=1e-10, metavar="RAD",
                   help="convergence threshold of each forward solve (default 1e-10)")
    add_scene_options(f)
    add_wall_options(f)
    add_json_option(f, "the fit as JSON")
    f.add_argument("--plot", metavar="FILE.png",
                   help="the data, the fitted curve and its 95 %% band (needs matplotlib)")
    f.set_defaults(func=cmd_fit)


def cmd_fit(args) -> int:
    """0 fitted, 2 bad input (one line)."""
    from ..studies.fit import fit, read_data

    if args.plot is not None and not has_matplotlib():
        error_line("--plot needs matplotlib: pip install 'lcpbench[plot]'")
        return 2
    if args.pressure is not None:
        raise ProblemError("fit takes the pressures from its data: drop --pressure")
    if args.shapes is not None:
        return _fit_shapes(args)
    P, y, h = read_data(args.data)
    cal = calibration_from(args)
    args.fit = None  # (the scene's theta comes from the data, not from --pressure)
    scene = scene_from(args)
    got = fit(scene, P, y, cal, height=h, fit_theta=args.fit_theta, tol=args.tol)
    if args.plot is not None:
        _plot(args.plot, scene, P, y, h, got, cal, args.tol)
    if args.json:
        print_json(got.as_json())
        return 0
    print(f"EI             {got.EI:.6g} N mm^2 (95 % interval {got.EI_low:.6g} .. "
          f"{got.EI_high:.6g})")
    if got.slope_interval is not None:
        print(f"theta(P)       {got.slope:.6g} deg/kPa * P + {got.intercept:.6g} deg")
    if not got.EI_high - got.EI_low <= 0.5 * got.EI:
        print("warning        the data determine EI poorly (95 % interval wider than +-25 %): "
              "measure at more pressures or heights" + (", or fix the calibration (drop "
                                                        "--fit-theta)" if args.fit_theta else ""))
    rms = float(np.sqrt(np.mean(got.residuals**2)))
    print(f"residuals      rms {1e3 * rms:.4g} mN over {P.size} points; largest "
          f"{1e3 * float(np.max(np.abs(got.residuals))):.4g} mN")
    print(f"solves         {got.solves} ({got.iterations} Gauss-Newton iterations)")
    if args.plot is not None:
        print(f"plot           {args.plot}")
    return 0


def _plot(path, scene, P, y, h, got, cal, tol) -> None:
    import dataclasses

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..api import solve

    grid = np.linspace(P.min(), P.max(), 25)
    height = float(np.median(h)) if h is not None else scene.height
    curves = {}
    for name, EI in (("fit", got.EI), ("low", got.EI_low), ("high", got.EI_high)):
        curves[name] = [solve(dataclasses.replace(scene, EI=EI, height=height,
                                                  theta=float(got.slope * p + got.intercept)),
                              tol=tol).total_force for p in grid]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.fill_between(grid, 1e3 * np.array(curves["low"]), 1e3 * np.array(curves["high"]),
                    color="C0", alpha=0.25, label="95 % interval of EI")
    ax.plot(grid, 1e3 * np.array(curves["fit"]), "C0-", label=f"fit, EI = {got.EI:.4g} N mm²")
    ax.plot(P, 1e3 * y, "ko", ms=4, label="data")
    ax.set_xlabel("pressure (kPa)")
    ax.set_ylabel("total force (mN)")
    ax.legend(loc="upper left", frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _fit_shapes(args) -> int:
    """``fit --shapes``: the line from the free shapes, EI from the pressed ones."""
    from ..vision.shapes_fit import fit_shapes, read_shapes

    if args.fit_theta:
        raise ProblemError("--shapes fits the theta(P) line from the free shapes itself; "
                           "--fit-theta goes with --data")
    if getattr(args, "pressure_limit", None) is not None:
        raise ProblemError("--pressure-limit is not for --shapes (a fit reports no contact "
                           "pressure)")
    shapes = read_shapes(args.shapes)
    cal = calibration_from(args)
    args.fit = None
    scene = scene_from(args)
    got = fit_shapes(scene, shapes, cal, tol=args.tol)
    if args.plot is not None:
        from ..vision.plots import plot_shape_fit

        plot_shape_fit(args.plot, shapes, got)
    if args.json:
        print_json(got.as_json())
        return 0
    src = f"{got.free} free shapes" if got.line_fitted else "the given calibration"
    print(f"theta(P)       {got.slope:.6g} deg/kPa * P + {got.intercept:.6g} deg ({src})")
    if got.slope_ci95 is not None and got.intercept_ci95 is not None:
        print(f"               95 % intervals: slope {got.slope_ci95[0]:.6g} .. "
              f"{got.slope_ci95[1]:.6g}, intercept {got.intercept_ci95[0]:.6g} .. "
              f"{got.intercept_ci95[1]:.6g}")
    if got.EI is None:
        print("EI             no pressed shape (a height_mm): nothing to fit EI to")
        return 0
    print(f"EI             {got.EI:.6g} N mm^2 (95 % interval {got.EI_low:.6g} .. "
          f"{got.EI_high:.6g}) from {got.pressed} pressed shapes")
    if not got.EI_high - got.EI_low <= 0.5 * got.EI:
        print("warning        the shapes determine EI poorly (95 % interval wider than "
              "+-25 %): a pressed shape depends on EI only through w l^3/EI")
    print(f"residuals      rms {1e3 * got.rms_mm:.4g} um over {got.points} points")
    print(f"solves         {got.solves} ({got.iterations} Gauss-Newton iterations)")
    if args.plot is not None:
        print(f"plot           {args.plot}")
    return 0
