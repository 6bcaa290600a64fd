"""``lcpbench vision ...``: measure, calibrate, compare, render.

Everything of the vision command line lives here; the main CLI calls
:func:`register` with its sub-parsers. Heavy imports (OpenCV, scikit-image) happen
inside the handlers, so building the parser costs nothing and ``lcpbench solve``
works without the extra. Every handler returns the exit status; bad input raises
:class:`~lcpbench.vision.errors.VisionError` (an LcpbenchError), which the main
CLI prints as one line with status 2.
"""

from __future__ import annotations

import json
import os
import sys

from .errors import VisionError

SUBCOMMANDS = ("measure", "calibrate", "compare", "render")


def _hsv(text: str) -> tuple[int, int, int]:
    try:
        v = tuple(int(x) for x in text.split(","))
    except ValueError:
        v = ()
    if len(v) != 3:
        raise VisionError(f"HSV bound must be H,S,V (three integers; OpenCV H 0-179), got "
                          f"{text!r}")
    return v


def _dump(obj, path: str | None) -> None:
    from ..jsonsafe import sanitise

    text = json.dumps(sanitise(obj), allow_nan=False)
    if path is None:
        print(text)
        return
    try:
        with open(path, "w") as fh:
            fh.write(text + "\n")
    except OSError as exc:
        raise VisionError(f"{path}: cannot write ({exc.strerror})") from None


def _add_measure_options(p) -> None:
    p.add_argument("--calib", metavar="FILE.json",
                   help="OpenCV camera calibration (camera_matrix 3x3, dist_coeffs "
                        "[k1,k2,p1,p2,k3]) to undistort with")
    p.add_argument("--marker-mm", type=float, default=25.0, metavar="MM",
                   help="side of the ArUco marker (DICT_4X4_50), mm (default 25)")
    p.add_argument("--sections", type=int, default=3, metavar="K",
                   help="bending sections of the actuator (default 3; the middle one is measured)")
    p.add_argument("--diameter", type=float, default=3.0, metavar="MM",
                   help="outer diameter of the tube, mm (default 3)")
    p.add_argument("--hsv-lower", type=str, default=None, metavar="H,S,V",
                   help="lower HSV bound of the actuator's colour (OpenCV H 0-179); "
                        "default automatic")
    p.add_argument("--hsv-upper", type=str, default=None, metavar="H,S,V",
                   help="upper HSV bound (give both or neither)")
    p.add_argument("--equal-sections", action="store_true",
                   help="the joint fit shares one theta among the sections (arc lengths "
                        "stay per section)")


def register(subparsers) -> None:
    """Add ``vision`` and its sub-commands to the main CLI's sub-parsers."""
    v = subparsers.add_parser(
        "vision", help="photographs to the model: measure, calibrate, compare, render",
        description="The paper's static-image pipeline (Sec. IV-D): measure bend angles on "
                    "photographs, fit theta against pressure, compare the model's "
                    "constrained shape with a photograph; needs pip install "
                    "'lcpbench[vision]'.")
    cmds = v.add_subparsers(dest="vision_command", metavar="SUBCOMMAND",
                            parser_class=type(v))
    v.set_defaults(func=_missing)

    m = cmds.add_parser("measure", help="bend angle and arc length of each section",
                        description="Measure one photograph: scale, level, centerline, "
                                    "inflection points, circle fits, theta (eq. 38), "
                                    "arc length (eq. 39).")
    m.add_argument("image", metavar="IMAGE")
    _add_measure_options(m)
    m.add_argument("--json", action="store_true", help="print the measurement as JSON")
    m.add_argument("--plot", metavar="OUT.png", help="overlay of the detected features")
    m.set_defaults(func=cmd_measure)

    c = cmds.add_parser("calibrate", help="fit theta = slope * P + intercept (eqs. 40-42)",
                        description="Measure the middle section's bend angle on each image "
                                    "and fit it against pressure, with its uncertainty.")
    c.add_argument("images", nargs="*", metavar="IMAGE")
    c.add_argument("--pressures", metavar="P1,P2,..", help="one pressure per image")
    c.add_argument("--csv", metavar="FILE.csv", help="rows file,pressure instead")
    c.add_argument("--unit", default="kPa", help="pressure unit for the plot (default kPa)")
    _add_measure_options(c)
    c.add_argument("--out", metavar="FIT.json", help="write the calibration here")
    c.add_argument("--plot", metavar="OUT.png", help="theta against pressure (Fig. 20)")
    c.set_defaults(func=cmd_calibrate)

    k = cmds.add_parser("compare", help="model against photograph by ICP (Fig. 23)",
                        description="Solve the constrained model (N = 200) for the "
                                    "photograph's wall faces and theta, register it to the "
                                    "photographed middle section by ICP, report point-pair "
                                    "distances and the predicted contact force.")
    k.add_argument("image", metavar="IMAGE")
    _add_wall_options(k, required=True)
    k.add_argument("--theta", type=float, metavar="DEG", help="unconstrained bend angle")
    k.add_argument("--pressure", type=float, metavar="P",
                   help="pressure instead of --theta (with --fit or --actuator)")
    k.add_argument("--fit", metavar="SLOPE,INTERCEPT", help="your calibration (vision calibrate)")
    k.add_argument("--actuator", default="1", help="the paper's calibration 1, 2 or 3")
    k.add_argument("--offset", choices=("wall", "curve"), default="wall",
                   help="tube radius: move the walls in by r (default, exact for flat walls) "
                        "or offset the model's curve by r (the paper's way)")
    k.add_argument("--one-wall", action="store_true", help="no wall at -h")
    k.add_argument("--links", type=int, default=200, help="links N (paper: 200)")
    _add_measure_options(k)
    k.add_argument("--json", action="store_true")
    k.add_argument("--plot", metavar="OUT.png", help="overlay and point-pair distances")
    k.set_defaults(func=cmd_compare)

    r = cmds.add_parser("render", help="a photograph-like test image with its ground truth",
                        description="Draw the fixture from a known theta (unconstrained), "
                                    "or the model's constrained shape with --wall-face "
                                    "(or --height).")
    r.add_argument("--theta", type=float, required=True, metavar="DEG")
    _add_wall_options(r, required=False)
    r.add_argument("--length", type=float, default=30.0, metavar="MM")
    r.add_argument("--sections", type=int, default=3)
    r.add_argument("--diameter", type=float, default=3.0, metavar="MM")
    r.add_argument("--marker-mm", type=float, default=25.0, metavar="MM")
    r.add_argument("--tube-hue", type=float, metavar="DEG",
                   help="hue of the tube, 0-360 (default: orange, about 22)")
    r.add_argument("--px-per-mm", type=float, default=15.0)
    r.add_argument("--nuisances", choices=("none", "all"), default="all",
                   help="all: rotation in +-10 deg, lens distortion, blur, noise, JPEG, "
                        "uneven light (default)")
    r.add_argument("--rotation", type=float, help="override the rotation, deg")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--out", required=True, metavar="IMG.png|.jpg")
    r.add_argument("--truth", metavar="TRUTH.json", help="ground truth (default OUT.json)")
    r.add_argument("--calib-out", metavar="CAL.json",
                   help="write the lens calibration used (default OUT.calib.json)")
    r.set_defaults(func=cmd_render)


def _missing(args) -> int:
    raise VisionError(f"missing SUBCOMMAND ({', '.join(SUBCOMMANDS)}); "
                      "see 'lcpbench vision --help'")


def _measure(args, image):
    try:
        from .measure import measure
    except ImportError as exc:
        raise VisionError(f"the vision extra is missing ({exc.name}): "
                          "pip install 'lcpbench[vision]'") from None
    if (args.hsv_lower is None) != (args.hsv_upper is None):
        raise VisionError("give both --hsv-lower and --hsv-upper, or neither")
    lo = _hsv(args.hsv_lower) if args.hsv_lower else None
    hi = _hsv(args.hsv_upper) if args.hsv_upper else None
    return measure(image, calibration=args.calib, marker_mm=args.marker_mm,
                   sections=args.sections, diameter_mm=args.diameter, hsv_lower=lo,
                   hsv_upper=hi, equal_sections=args.equal_sections)


def _warn(meas) -> None:
    for w in meas.warnings:
        print(f"lcpbench: warning: {w}", file=sys.stderr)


def cmd_measure(args) -> int:
    meas = _measure(args, args.image)
    if args.plot:
        from .plots import plot_measurement

        plot_measurement(meas, args.plot)
    _warn(meas)
    if args.json:
        _dump(meas.to_dict(), None)
        return 0
    c = meas.confidence
    print(f"scale        {meas.px_per_mm:.4f} px/mm (ArUco id {meas.marker.id})")
    print(f"level        {meas.level_deg:+.3f} deg")
    print(f"joint fit    {len(meas.sections)} arcs between the pins"
          f"{', one shared theta' if args.equal_sections else ''} (+- 1 s.e.)")
    for j, s in enumerate(meas.sections):
        tag = "  <- middle" if j == meas.middle else ""
        print(f"section {j + 1}    theta {s.theta_deg:8.3f} +- {s.theta_se_deg:.3f} deg   arc "
              f"length {s.arc_length_mm:7.3f} +- {s.arc_length_se_mm:.3f} mm   radius "
              f"{s.radius_mm:8.3f} mm{tag}")
    print(f"residual     RMS {c.rms_px:.3f} px ({c.rms_mm:.4f} mm), {c.points} points"
          f"{f', {c.outliers} outliers left out' if c.outliers else ''}; section lengths "
          f"spread {100 * c.length_spread:.2f} %")
    if meas.circle_fits is not None:
        cm = meas.circle_fits[meas.middle]
        print(f"circle fits  middle theta {cm.theta_deg:8.3f} deg   arc length "
              f"{cm.arc_length_mm:7.3f} mm (per-section, eqs. 38-39, for comparison)")
    print("confidence   " + (f"{len(meas.warnings)} warning(s), see above" if meas.warnings
                             else "no warning"))
    if args.plot:
        print(f"plot         {args.plot}")
    return 0


def cmd_calibrate(args) -> int:
    from .calibrate import fit_theta_pressure, parse_pressures, read_pressure_csv

    if args.csv:
        if args.images or args.pressures:
            raise VisionError("give IMAGES with --pressures, or --csv, not both")
        rows = read_pressure_csv(args.csv)
    else:
        if not args.images or args.pressures is None:
            raise VisionError("give IMAGES... --pressures P1,P2,.. (one per image) or --csv FILE")
        ps = parse_pressures(args.pressures)
        if len(ps) != len(args.images):
            raise VisionError(f"{len(args.images)} images but {len(ps)} pressures")
        rows = list(zip(args.images, ps))
    thetas = []
    for path, p in rows:
        meas = _measure(args, path)
        _warn(meas)
        mid = meas.sections[args.sections // 2]
        thetas.append(mid.theta_deg)
        print(f"{path}: P = {p:g} {args.unit}, theta = {mid.theta_deg:.3f} deg", file=sys.stderr)
    pressures = [p for _, p in rows]
    fit = fit_theta_pressure(pressures, thetas)
    out = fit.to_dict() | {"unit": args.unit, "images": [
        {"file": f, "pressure": p, "theta_deg": t} for (f, p), t in zip(rows, thetas)]}
    if args.out:
        _dump(out, args.out)
    if args.plot:
        from .plots import plot_calibration

        plot_calibration(pressures, thetas, fit, args.plot, args.unit)
    print(f"theta = {fit.slope:.6g} * P + {fit.intercept:.6g} deg   (slope +- {fit.slope_se:.3g}, "
          f"intercept +- {fit.intercept_se:.3g} (1 s.e.), R^2 {fit.r2:.5f}, n = {fit.n})")
    print(f"--fit {fit.fit_arg}")
    print(f"use it: lcpbench solve --pressure P --fit {fit.fit_arg} --height H --channel")
    return 0


def _add_wall_options(parser, *, required: bool) -> None:
    """``--wall-face MM`` or ``--height MM``: where the walls are, one of the two."""
    g = parser.add_mutually_exclusive_group(required=required)
    g.add_argument("--wall-face", type=float, metavar="MM",
                   help="distance from the pin line to each wall's face, mm (the "
                        "photograph's walls)")
    g.add_argument("--height", type=float, metavar="MM",
                   help="the centre-line height h, as in `lcpbench solve --height`: the "
                        "wall face minus the tube radius, mm")


def _wall_face(args) -> float | None:
    """The wall faces' distance from the pin line (mm): --wall-face, or --height + r."""
    if args.wall_face is not None:
        return args.wall_face
    return None if args.height is None else args.height + args.diameter / 2


def cmd_compare(args) -> int:
    from .compare import compare, theta_from_pressure

    if (args.theta is None) == (args.pressure is None):
        raise VisionError("give --theta DEG or --pressure P (with --fit or --actuator)")
    if args.theta is not None and args.fit is not None:
        raise VisionError("--fit needs --pressure")
    theta = args.theta if args.theta is not None else \
        theta_from_pressure(args.pressure, args.fit, args.actuator)
    meas = _measure(args, args.image)
    cmp = compare(meas, theta, _wall_face(args), diameter_mm=args.diameter, offset=args.offset,
                  channel=not args.one_wall, links=args.links)
    if args.plot:
        from .plots import plot_comparison

        plot_comparison(cmp, args.plot)
    d = cmp.to_dict()
    if args.json:
        _dump(d, None)
    else:
        print(f"model        theta {theta:.3f} deg, wall faces at +-{d['wall_face_mm']:g} mm "
              f"(centre-line height h {d['height_mm']:g} mm), N = {args.links}, "
              f"{'converged' if d['model_converged'] else 'NOT converged'}")
        print(f"distance     mean {d['mean_distance_mm']:.4f} mm (sd {d['sd_distance_mm']:.4f}), "
              f"max {d['max_distance_mm']:.4f} mm")
        print(f"percent      mean {d['mean_percent']:.3f} % of the span "
              f"{d['model_span_mm']:.2f} mm (eq. 43), max {d['max_percent']:.3f} %")
        print(f"force        {1e3 * cmp.force_n:.4f} mN (predicted contact force)")
    return 0 if d["model_converged"] else 1


def cmd_render(args) -> int:
    import cv2

    from .render import Nuisances, render_constrained, render_unconstrained

    nz = Nuisances.all_on(args.seed) if args.nuisances == "all" else Nuisances(seed=args.seed)
    if args.rotation is not None:
        nz.rotation_deg = args.rotation
    kw = dict(px_per_mm=args.px_per_mm, diameter=args.diameter, marker_mm=args.marker_mm,
              nuisances=nz)
    if args.tube_hue is not None:
        from .render import tube_colour

        kw["tube_bgr"] = tube_colour(args.tube_hue)
    face = _wall_face(args)
    if face is None:
        img, truth = render_unconstrained(args.theta, length=args.length,
                                          sections=args.sections, **kw)
    else:
        from .compare import model_centerline

        pts, res = model_centerline(args.theta, face, diameter_mm=args.diameter,
                                    length=args.length)
        img, truth = render_constrained(pts[:, 0], pts[:, 1], wall_height=face,
                                        length=args.length, sections=args.sections, **kw)
        truth.update(theta_deg=args.theta, contact_force_n=res.total_force,
                     model="lcpbench.solve, N = 200, walls at the centre-line height "
                           "h = wall face - r (channel)")
    if not cv2.imwrite(args.out, img):
        raise VisionError(f"{args.out}: cannot write an image there (give a .png or .jpg path)")
    base = os.path.splitext(args.out)[0]
    truth_path = args.truth or base + ".json"
    _dump(truth, truth_path)
    msg = f"wrote {args.out} and {truth_path}"
    if "calibration" in truth:
        cal = args.calib_out or base + ".calib.json"
        _dump(truth["calibration"], cal)
        msg += f" and {cal} (measure with --calib {cal})"
    print(msg)
    return 0
