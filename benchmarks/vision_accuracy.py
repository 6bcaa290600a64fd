"""Accuracy of the static-image pipeline on rendered photographs (the paper's Fig. 19).

Two render sets, drawn by two independent renderers, θ from 10° to 175° (9 of
the 24 angles below 35°), every nuisance on, each image measured with automatic
segmentation and the lens calibration it was drawn with (``lcpbench vision
measure IMG --calib CAL``); the middle section's θ and ℓ are compared with the
truth: % error = |truth − detected| / truth × 100, as Fig. 19.

- **own**: the pipeline's renderer (``lcpbench.vision.render``, ``lcpbench vision
  render``), two photographs per θ of a 3-section actuator (ℓ = 30 mm, Ø 3 mm):
  a rotation drawn in ±10°, radial lens distortion, blur σ = 1 px, sensor noise
  σ = 4 grey levels, JPEG 85, uneven lighting, 10-25 px/mm; then the issue 41
  hard case (θ = 34.0°, ℓ = 25.15 mm, a green tube) at six resolutions.
- **agg**: the second renderer (tests/vision/agg_photos.py: matplotlib's Agg,
  closed-form arcs, no drawing code shared), two photographs per θ with ℓ in
  20-35 mm, tube hues across the colour wheel, bearings with a light hub, paper
  texture, a shadow band, the marker above, below, left or right, rotation in
  ±10°, radial and tangential distortion, Pillow blur and JPEG, shot noise,
  10-25 px/mm; then the hard case drawn by it four times.

For each image: the joint fit (the measurement) and the paper's per-section
circle fits (eqs. 38-39) beside it, the joint fit's standard errors (how often
|error| < 1 and 2 s.e.) and its warnings.

It also draws the documentation's figures: an overlay of one measurement, the
comparison of a constrained photograph with the model, a θ-against-pressure
calibration and the error per θ.

Run (about 10 minutes on 2 cores)::

    PYTHONPATH=src python benchmarks/vision_accuracy.py [--out results/vision] [--quick]
        [--force] [--jobs 2]

Writes accuracy.md, accuracy.json, accuracy.png, overlay.png, compare.png and
calibration.png in --out (refuses to overwrite them without --force).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from lcpbench.bench.machine import refuse_overwrite
from lcpbench.vision.calibrate import fit_theta_pressure
from lcpbench.vision.compare import compare, model_centerline
from lcpbench.vision.errors import VisionError
from lcpbench.vision.measure import measure
from lcpbench.vision.plots import plot_calibration, plot_comparison, plot_measurement
from lcpbench.vision.render import (
    Nuisances,
    render_constrained,
    render_unconstrained,
    tube_colour,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "vision"))
from agg_photos import Scene, draw  # noqa: E402  (the second, independent renderer)

SEEDS = (0, 1)
#: θ from 10° to 175°, 9 of the 24 below 35° (issue 41: at least a third)
THETAS = [10, 13, 16, 19, 22, 25, 28, 31, 34] + list(range(40, 171, 10)) + [175]
QUICK = [10, 22, 34, 90, 175]


def resolution(theta: int, seed: int) -> float:
    """10-25 px/mm, stepping with θ and the repeat (every resolution is visited)."""
    return 10.0 + (theta // 10 * 5 + theta % 10 + seed * 7) % 16


def evaluate(img, truth, theta, length, **tags):
    """Measure one photograph (automatic segmentation, its calibration) and compare
    both methods' middle section with the truth."""
    t0 = time.perf_counter()
    try:
        m = measure(img, calibration=truth.get("calibration"))
    except VisionError as exc:       # target 1: every image measured
        print(f"{tags.get('set', '')} theta {theta:5.1f}: not measured: {exc}",
              file=sys.stderr, flush=True)
        return {**tags, "theta_deg": theta, "arc_length_mm": length, "failed": str(exc)}
    dt = time.perf_counter() - t0
    mid, cf = m.sections[m.middle], m.circle_fits[m.middle]
    ppm = truth["px_per_mm"]
    pins = np.asarray(truth["pins_px"], float)
    level = math.degrees(math.atan2(*(pins[1] - pins[0])[::-1]))
    got = np.array([m.bearings.left, m.bearings.right])
    row = {
        **tags, "theta_deg": theta, "arc_length_mm": length, "px_per_mm": round(ppm, 2),
        "detected_theta_deg": mid.theta_deg, "detected_arc_length_mm": mid.arc_length_mm,
        "theta_se_deg": mid.theta_se_deg, "arc_length_se_mm": mid.arc_length_se_mm,
        "theta_error_pct": 100 * abs(mid.theta_deg - theta) / theta,
        "arc_length_error_pct": 100 * abs(mid.arc_length_mm - length) / length,
        "theta_z": (mid.theta_deg - theta) / mid.theta_se_deg,
        "arc_length_z": (mid.arc_length_mm - length) / mid.arc_length_se_mm,
        "circle_theta_error_pct": 100 * abs(cf.theta_deg - theta) / theta,
        "circle_arc_length_error_pct": 100 * abs(cf.arc_length_mm - length) / length,
        "rms_px": m.confidence.rms_px, "length_spread_pct": 100 * m.confidence.length_spread,
        "warnings": m.warnings,
        "px_per_mm_error_pct": 100 * abs(m.px_per_mm - ppm) / ppm,
        "level_error_deg": abs(m.level_deg - level),
        "pin_error_px": float(np.hypot(*(got - pins).T).max()),
        "measure_s": dt,
    }
    print(f"{tags.get('set', '')} theta {theta:5.1f} {ppm:4.1f} px/mm: joint fit "
          f"{row['theta_error_pct']:.3f} / {row['arc_length_error_pct']:.3f} %, circle fits "
          f"{row['circle_theta_error_pct']:.3f} / {row['circle_arc_length_error_pct']:.3f} %, "
          f"{len(m.warnings)} warnings", file=sys.stderr, flush=True)
    return row


def measure_one(theta, length, ppm, seed, hue=None, **tags):
    """Render one photograph with the pipeline's renderer and evaluate it."""
    nz = Nuisances.all_on(seed)
    kw = {} if hue is None else {"tube_bgr": tube_colour(hue)}
    img, truth = render_unconstrained(float(theta), length=length, px_per_mm=ppm,
                                      nuisances=nz, **kw)
    return evaluate(img, truth, theta, length, set="own", seed=seed,
                    rotation_deg=round(truth["rotation_deg"], 3), **tags)


def measure_agg(scene: Scene, **tags):
    """Draw one photograph with the second renderer and evaluate it."""
    img, truth = draw(scene)
    mid = truth["middle"]
    return evaluate(img, truth, truth["theta_deg"][mid], truth["arc_length_mm"][mid],
                    set="agg", seed=scene.seed, rotation_deg=round(scene.rotation_deg, 3),
                    hue_deg=round(scene.hue_deg), marker=scene.marker_side, **tags)


def _own(theta, seed):
    return measure_one(theta, 30.0, resolution(theta, seed), 1000 * seed + theta)


def _agg(theta, seed):
    return measure_agg(Scene.varied(theta, 5000 + 1000 * seed + theta))


def _own_hard(i, ppm):
    """The issue 41 image: θ = 34.0°, ℓ = 25.15 mm, a green tube (hue 120°)."""
    return measure_one(34.0, 25.15, ppm, 4100 + i, hue=120.0, case="hard case")


def _agg_hard(i):
    """The issue 41 actuator drawn by the second renderer (the rest of the scene varied)."""
    return measure_agg(Scene.varied(34.0, 4200 + i, length_mm=25.15, hue_deg=120.0),
                       case="hard case")


def run_all(tasks, jobs):
    """Each (function, args) of ``tasks``, in order; in ``jobs`` processes."""
    if jobs <= 1:
        return [f(*a) for f, a in tasks]
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(jobs) as ex:
        futs = [ex.submit(f, *a) for f, a in tasks]
        return [fu.result() for fu in futs]


def _stats(rows, prefix=""):
    ok = [r for r in rows if "failed" not in r]
    et = np.array([r[f"{prefix}theta_error_pct"] for r in ok])
    el = np.array([r[f"{prefix}arc_length_error_pct"] for r in ok])
    return {"theta_mean_pct": float(et.mean()), "theta_max_pct": float(et.max()),
            "length_mean_pct": float(el.mean()), "length_max_pct": float(el.max())}


def _coverage(rows):
    ok = [r for r in rows if "failed" not in r]
    z = np.abs([[r["theta_z"], r["arc_length_z"]] for r in ok])
    off = [max(r["theta_error_pct"], r["arc_length_error_pct"]) > 1 for r in ok]
    return {"within_1se": (z < 1).mean(axis=0).tolist(),
            "within_2se": (z < 2).mean(axis=0).tolist(),
            "warned": int(sum(bool(r["warnings"]) for r in ok)),
            "off_by_1pct_without_warning": int(sum(o and not r["warnings"]
                                                   for o, r in zip(off, ok)))}


def per_theta(rows):
    by = {}
    for r in rows:
        if "failed" not in r:
            by.setdefault(r["theta_deg"], []).append(r)
    return [{"theta_deg": theta, "n": len(rs), "px_per_mm": [r["px_per_mm"] for r in rs],
             **_stats(rs), **{f"circle_{k}": v for k, v in _stats(rs, "circle_").items()}}
            for theta, rs in sorted(by.items())]


def summarise(rows):
    """One render set's summary and the issue 41 targets on it."""
    joint = _stats(rows)
    cov = _coverage(rows)
    failed = sum("failed" in r for r in rows)
    below = sum(r["theta_deg"] < 35 for r in rows)
    return {"images": len(rows), "measured": len(rows) - failed, "below_35_deg": below,
            **joint, "circle_fits": _stats(rows, "circle_"), **cov,
            "targets": {"every_image_measured": failed == 0,
                        "mean_le_0.2_pct": bool(joint["theta_mean_pct"] <= 0.2
                                                and joint["length_mean_pct"] <= 0.2),
                        "max_le_0.8_pct": bool(joint["theta_max_pct"] <= 0.8
                                               and joint["length_max_pct"] <= 0.8),
                        "none_off_by_1pct_unwarned": cov["off_by_1pct_without_warning"] == 0}}


def _yes(b):
    return "met" if b else "**not met**"


def write_md(path, sets, per, hard, cmp, cal, argv):
    own, agg = sets["own"], sets["agg"]
    lines = [
        "# Vision pipeline: accuracy on rendered photographs",
        "",
        "The middle section of a 3-section actuator (Ø 3 mm), measured with automatic "
        "segmentation on photographs drawn by two independent renderers, every nuisance "
        "on; each image is undistorted with the lens calibration it was drawn with. "
        "% error = |truth − detected| / truth × 100 (the paper's Fig. 19 measure; the paper: "
        "1.72 % for θ and 1.88 % for ℓ, mean, on photographs). **Joint fit**: the "
        "measurement, one least-squares chain of three arcs between the pins; **circles**: "
        "the paper's method (a circle per section between inflection points, eqs. 38-39), "
        "for comparison.",
        "",
        "- **own**: the pipeline's renderer (`lcpbench vision render`), ℓ = 30 mm, two "
        "photographs per θ (rotation in ±10°, radial lens distortion, blur σ = 1 px, noise "
        "σ = 4, JPEG 85, uneven lighting; 10-25 px/mm), and the issue 41 hard case (θ = 34°, "
        "ℓ = 25.15 mm, green) at six resolutions.",
        "- **agg**: a second renderer that shares no drawing code with it "
        "(tests/vision/agg_photos.py: matplotlib's Agg rasteriser, closed-form arcs): two "
        "photographs per θ with ℓ in 20-35 mm, tube hues across the colour wheel, bearings "
        "with a light hub, paper texture, a shadow band, the marker above, below, left or "
        "right, rotation in ±10°, radial and tangential distortion, Pillow blur (σ = 1 px) "
        "and JPEG (80-94), shot noise; 10-25 px/mm; and the hard case drawn four times.",
        "",
        f"Both sets: θ from 10° to 175°, {len(THETAS)} angles, 9 of them below 35°. "
        f"Produced by `{argv}` on {platform.platform()}, Python "
        f"{platform.python_version()}.",
        "",
        "## Targets (issue 41)",
        "",
        "| target | own | agg |",
        "|---|---|---|",
        f"| images (below 35°) | {own['images']} ({own['below_35_deg']}) | "
        f"{agg['images']} ({agg['below_35_deg']}) |",
        f"| 1. every image measured, automatic segmentation | {own['measured']} of "
        f"{own['images']}: {_yes(own['targets']['every_image_measured'])} | "
        f"{agg['measured']} of {agg['images']}: "
        f"{_yes(agg['targets']['every_image_measured'])} |",
    ]
    for key, lab in (("theta", "bend angle θ"), ("length", "arc length ℓ")):
        lines.append(f"| 2. {lab}: mean ≤ 0.2 %, max ≤ 0.8 % (joint fit) | "
                     + " | ".join(f"{o[key + '_mean_pct']:.3f} %, {o[key + '_max_pct']:.3f} %: "
                                  + _yes(o[key + "_mean_pct"] <= 0.2
                                         and o[key + "_max_pct"] <= 0.8)
                                  for o in (own, agg)) + " |")
    for key, lab in (("theta", "θ"), ("length", "ℓ")):
        lines.append(f"| (circles, for comparison: {lab} mean, max) | "
                     + " | ".join(f"{o['circle_fits'][key + '_mean_pct']:.3f} %, "
                                  f"{o['circle_fits'][key + '_max_pct']:.3f} %"
                                  for o in (own, agg)) + " |")
    lines += [
        "| 3. no image more than 1 % off without a warning | "
        + " | ".join(f"{o['off_by_1pct_without_warning']} ({o['warned']} warned): "
                     + _yes(o["targets"]["none_off_by_1pct_unwarned"]) for o in (own, agg))
        + " |",
        "| truth within 1 s.e., 2 s.e. (θ; ℓ) (normal: 68 %, 95 %) | "
        + " | ".join(f"{100 * o['within_1se'][0]:.0f} %, {100 * o['within_2se'][0]:.0f} %; "
                     f"{100 * o['within_1se'][1]:.0f} %, {100 * o['within_2se'][1]:.0f} %"
                     for o in (own, agg)) + " |",
        "",
        "## Own renderer, per θ",
        "",
        "| θ (deg) | px/mm | joint θ mean (%) | joint θ max (%) | joint ℓ mean (%) | "
        "joint ℓ max (%) | circles θ mean (%) | circles θ max (%) | circles ℓ mean (%) | "
        "circles ℓ max (%) |",
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for p in per:
        lines.append(f"| {p['theta_deg']} | {', '.join(f'{v:g}' for v in p['px_per_mm'])} | "
                     f"{p['theta_mean_pct']:.3f} | {p['theta_max_pct']:.3f} | "
                     f"{p['length_mean_pct']:.3f} | {p['length_max_pct']:.3f} | "
                     f"{p['circle_theta_mean_pct']:.3f} | {p['circle_theta_max_pct']:.3f} | "
                     f"{p['circle_length_mean_pct']:.3f} | {p['circle_length_max_pct']:.3f} |")
    lines += ["", "## Second renderer (agg), every image", "",
              "| θ (deg) | ℓ (mm) | px/mm | hue (deg) | marker | rotation (deg) | "
              "joint θ error (%) | joint ℓ error (%) | circles θ, ℓ error (%) | "
              "pin error (px) | warnings |",
              "|---:|---:|---:|---:|---|---:|---:|---:|---|---:|---:|"]
    for r in sets["agg_rows"]:
        name = f"{r['theta_deg']:g}" + (" (hard case)" if r.get("case") else "")
        if "failed" in r:
            lines.append(f"| {name} | {r['arc_length_mm']:.2f} | | | | | not measured: "
                         f"{r['failed']} | | | | |")
            continue
        lines.append(
            f"| {name} | {r['arc_length_mm']:.2f} | {r['px_per_mm']:.1f} | {r['hue_deg']} | "
            f"{r['marker']} | {r['rotation_deg']:.1f} | {r['theta_error_pct']:.3f} | "
            f"{r['arc_length_error_pct']:.3f} | {r['circle_theta_error_pct']:.3f}, "
            f"{r['circle_arc_length_error_pct']:.3f} | {r['pin_error_px']:.3f} | "
            f"{len(r['warnings'])} |")
    if hard:
        lines += ["", "## The issue 41 hard case: θ = 34.0°, ℓ = 25.15 mm, a green tube", "",
                  "On main 308f03e a held-out render of this actuator (drawn by another "
                  "renderer, with hubs, texture and a shadow band) measured 32.13° and "
                  "23.81 mm, 5.5 % and 5.3 % off, without a warning. That render is not in "
                  "the repository; the second renderer's four drawings of it are in the "
                  "table above; here the pipeline's own renderer (`--tube-hue 120`), every "
                  "nuisance on:", "",
                  "| px/mm | joint θ (deg) | ± s.e. | joint ℓ (mm) | ± s.e. | error θ, ℓ (%) "
                  "| circles error θ, ℓ (%) | RMS (px) | length spread (%) | warnings |",
                  "|---:|---:|---:|---:|---:|---|---|---:|---:|---:|"]
        for r in hard:
            lines.append(
                f"| {r['px_per_mm']:g} | {r['detected_theta_deg']:.3f} | "
                f"{r['theta_se_deg']:.3f} | {r['detected_arc_length_mm']:.3f} | "
                f"{r['arc_length_se_mm']:.3f} | {r['theta_error_pct']:.3f}, "
                f"{r['arc_length_error_pct']:.3f} | {r['circle_theta_error_pct']:.3f}, "
                f"{r['circle_arc_length_error_pct']:.3f} | {r['rms_px']:.3f} | "
                f"{r['length_spread_pct']:.2f} | {len(r['warnings'])} |")
    if cmp is not None:
        lines += ["", "## Model against a photograph of its own shape (Fig. 23)", "",
                  f"θ = {cmp['theta_deg']:g}°, wall faces at ±{cmp['wall_face_mm']:g} mm, N = 200: "
                  f"mean point-pair distance after ICP {cmp['mean_distance_mm']:.4f} mm "
                  f"({cmp['mean_percent']:.4f} % of the span), max "
                  f"{cmp['max_distance_mm']:.4f} mm (target: mean < 0.05 mm; the paper "
                  f"on real photographs: 0.31 mm, 1.06 %). Predicted contact force "
                  f"{1e3 * cmp['contact_force_n']:.2f} mN."]
    if cal is not None:
        lines += ["", "## θ against pressure from photographs (Fig. 20)", "",
                  f"Photographs rendered from θ = 0.81 P + 9.78 (eq. 40): fitted θ = "
                  f"{cal['slope']:.4f} P + {cal['intercept']:.3f} (slope ± "
                  f"{cal['slope_se']:.1e}, intercept ± {cal['intercept_se']:.2f}, 1 s.e.), "
                  f"`--fit {cal['fit']}`."]
    lines += ["", "Figures: accuracy.png (error per θ, both renderers), overlay.png, "
              "compare.png, calibration.png.", ""]
    with open(path, "w") as fh:
        fh.write("\n".join(lines))


def plot_accuracy(pers, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(7.5, 6), sharex=True)
    for ax, (name, per) in zip(axes, pers.items()):
        th = np.array([p["theta_deg"] for p in per])
        for key, lab, off, col in (("theta", "bend angle θ", -0.8, "tab:blue"),
                                   ("length", "arc length ℓ", 0.8, "tab:orange")):
            mean = np.array([p[f"{key}_mean_pct"] for p in per])
            mx = np.array([p[f"{key}_max_pct"] for p in per])
            ax.errorbar(th + off, mean, yerr=[np.zeros_like(mean), mx - mean], fmt="o", ms=3,
                        capsize=2, color=col, label=f"{lab}: mean per θ, bar to the max")
        ax.axhline(0.2, color="k", ls="--", lw=1, label="target for the mean (0.2 %)")
        ax.set_ylabel("% error")
        ax.set_title(f"{name} renderer", fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("true bend angle θ (deg)")
    fig.suptitle("Middle-section error of the joint fit on rendered photographs (cf. Fig. 19)",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/vision")
    ap.add_argument("--quick", action="store_true",
                    help=f"θ = {', '.join(map(str, QUICK))}, one image each per renderer")
    ap.add_argument("--force", action="store_true", help="overwrite the results in --out")
    ap.add_argument("--jobs", type=int, default=1, help="images measured in parallel")
    args = ap.parse_args()
    names = ("accuracy.md", "accuracy.json", "accuracy.png", "overlay.png", "compare.png",
             "calibration.png")
    refuse_overwrite([os.path.join(args.out, n) for n in names], args.force)
    os.makedirs(args.out, exist_ok=True)
    thetas = QUICK if args.quick else THETAS
    seeds = SEEDS[:1] if args.quick else SEEDS
    ppms = (10.0, 12.0, 14.0, 17.0, 20.0, 25.0)[:2 if args.quick else 6]
    tasks = ([(_own, (t, s)) for t in thetas for s in seeds]
             + [(_own_hard, (i, p)) for i, p in enumerate(ppms)]
             + [(_agg, (t, s)) for t in thetas for s in seeds]
             + [(_agg_hard, (i,)) for i in range(1 if args.quick else 4)])
    out = run_all(tasks, args.jobs)
    n_own, n_hard = len(thetas) * len(seeds), len(ppms)
    rows, hard = out[:n_own], out[n_own:n_own + n_hard]
    agg_rows = out[n_own + n_hard:]
    sets = {"own": summarise(rows + hard), "agg": summarise(agg_rows)}
    per = {"own": per_theta(rows), "agg": per_theta(agg_rows)}

    # figures: one measurement overlay
    img, truth = render_unconstrained(120.0, px_per_mm=15.0, nuisances=Nuisances.all_on(7))
    plot_measurement(measure(img, calibration=truth["calibration"]),
                     os.path.join(args.out, "overlay.png"), truth)
    # model against a photograph of its own constrained shape
    pts, _ = model_centerline(150.0, 5.0)
    img, truth = render_constrained(pts[:, 0], pts[:, 1], wall_height=5.0, px_per_mm=15.0,
                                    nuisances=Nuisances.all_on(11))
    c = compare(measure(img, calibration=truth["calibration"]), 150.0, 5.0)
    plot_comparison(c, os.path.join(args.out, "compare.png"))
    cmp = {k: v for k, v in c.to_dict().items() if k != "point_pair_distance_mm"}
    # theta against pressure: eq. (40), 10-25 psi, two photographs each
    ps, ts = [], []
    for k, p in enumerate(np.linspace(68.95, 172.37, 6)):
        for rep in range(2):
            img, truth = render_unconstrained(0.81 * p + 9.78, px_per_mm=10.0 + 3 * rep,
                                              nuisances=Nuisances.all_on(100 + 2 * k + rep))
            m = measure(img, calibration=truth["calibration"])
            ps.append(float(p))
            ts.append(m.sections[m.middle].theta_deg)
    fit = fit_theta_pressure(ps, ts)
    plot_calibration(ps, ts, fit, os.path.join(args.out, "calibration.png"))
    plot_accuracy(per, os.path.join(args.out, "accuracy.png"))

    argv = "PYTHONPATH=src python benchmarks/vision_accuracy.py" + (" --quick" if args.quick
                                                                    else "")
    with open(os.path.join(args.out, "accuracy.json"), "w") as fh:
        json.dump({"command": argv, "sets": sets, "per_theta": per,
                   "images": {"own": rows, "agg": agg_rows}, "hard_case": hard,
                   "compare": cmp, "calibration": fit.to_dict()}, fh, indent=1)
    write_md(os.path.join(args.out, "accuracy.md"), {**sets, "agg_rows": agg_rows}, per["own"],
             hard, cmp, fit.to_dict(), argv)
    print(json.dumps(sets))
    return 0 if all(all(o["targets"].values()) for o in sets.values()) else 1


if __name__ == "__main__":
    raise SystemExit(main())
