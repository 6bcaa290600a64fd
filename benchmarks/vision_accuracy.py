"""Accuracy of the static-image pipeline on rendered photographs (the paper's Fig. 19).

For θ = 10°, 20°, ..., 180° it renders three photographs of a 3-section actuator
(ℓ = 30 mm, outer diameter 3 mm) with every nuisance on: a rotation drawn in
±10°, radial lens distortion, blur σ = 1 px, sensor noise σ = 4 grey levels, JPEG
quality 85, uneven lighting, and a resolution that steps through 10-25 px/mm. Each
is measured with the lens calibration it was drawn with (``lcpbench vision measure
IMG --calib CAL``), and the middle section's θ and ℓ are compared with the truth:
% error = |truth − detected| / truth × 100, as Fig. 19. 54 images, as the paper's
54 printed shapes. Then the issue 41 hard case (θ = 34.0°, ℓ = 25.15 mm, a green
tube) at six resolutions. For each image: the joint fit (the measurement) and the
paper's per-section circle fits (eqs. 38-39) beside it, the joint fit's standard
errors (how often |error| < 1 and 2 s.e.) and its warnings.

It also draws the documentation's figures: an overlay of one measurement, the
comparison of a constrained photograph with the model, a θ-against-pressure
calibration and the error per θ.

Run (about 3-5 minutes on 2 cores)::

    PYTHONPATH=src python benchmarks/vision_accuracy.py [--out results/vision] [--quick]

Writes accuracy.md, accuracy.json, accuracy.png, overlay.png, compare.png and
calibration.png in --out.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

import numpy as np

from lcpbench.vision.calibrate import fit_theta_pressure
from lcpbench.vision.compare import compare, model_centerline
from lcpbench.vision.measure import measure
from lcpbench.vision.plots import plot_calibration, plot_comparison, plot_measurement
from lcpbench.vision.render import (
    Nuisances,
    render_constrained,
    render_unconstrained,
    tube_colour,
)

SEEDS = (0, 1, 2)


def resolution(theta: int, seed: int) -> float:
    """10-25 px/mm, stepping with θ and the repeat (every resolution is visited)."""
    return 10.0 + (theta // 10 * 5 + seed * 7) % 16


def measure_one(theta, length, ppm, seed, hue=None, **tags):
    """Render one photograph, measure it, and compare both methods with the truth."""
    nz = Nuisances.all_on(seed)
    kw = {} if hue is None else {"tube_bgr": tube_colour(hue)}
    img, truth = render_unconstrained(float(theta), length=length, px_per_mm=ppm,
                                      nuisances=nz, **kw)
    t0 = time.perf_counter()
    m = measure(img, calibration=truth["calibration"])
    dt = time.perf_counter() - t0
    mid, cf = m.sections[m.middle], m.circle_fits[m.middle]
    row = {
        **tags, "theta_deg": theta, "arc_length_mm": length, "seed": seed, "px_per_mm": ppm,
        "rotation_deg": round(truth["rotation_deg"], 3),
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
        "level_error_deg": abs(m.level_deg - truth["rotation_deg"]),
        "measure_s": dt,
    }
    print(f"theta {theta:5.1f} seed {seed} {ppm:4.0f} px/mm: joint fit "
          f"{row['theta_error_pct']:.3f} / {row['arc_length_error_pct']:.3f} %, circle fits "
          f"{row['circle_theta_error_pct']:.3f} / {row['circle_arc_length_error_pct']:.3f} %, "
          f"{len(m.warnings)} warnings", file=sys.stderr, flush=True)
    return row


def sweep(thetas, seeds):
    return [measure_one(theta, 30.0, resolution(theta, seed), 1000 * seed + theta)
            for theta in thetas for seed in seeds]


def hard_case(n):
    """The issue 41 image: θ = 34.0°, ℓ = 25.15 mm, a green tube (hue 120°)."""
    return [measure_one(34.0, 25.15, ppm, 4100 + i, hue=120.0, set="hard case")
            for i, ppm in enumerate((10.0, 12.0, 14.0, 17.0, 20.0, 25.0)[:n])]


def _stats(rows, prefix=""):
    et = np.array([r[f"{prefix}theta_error_pct"] for r in rows])
    el = np.array([r[f"{prefix}arc_length_error_pct"] for r in rows])
    return {"theta_mean_pct": float(et.mean()), "theta_max_pct": float(et.max()),
            "length_mean_pct": float(el.mean()), "length_max_pct": float(el.max())}


def _coverage(rows):
    z = np.abs([[r["theta_z"], r["arc_length_z"]] for r in rows])
    off = [max(r["theta_error_pct"], r["arc_length_error_pct"]) > 1 for r in rows]
    return {"within_1se": (z < 1).mean(axis=0).tolist(),
            "within_2se": (z < 2).mean(axis=0).tolist(),
            "warned": int(sum(bool(r["warnings"]) for r in rows)),
            "off_by_1pct_without_warning": int(sum(o and not r["warnings"]
                                                   for o, r in zip(off, rows)))}


def summarise(rows):
    by = {}
    for r in rows:
        by.setdefault(r["theta_deg"], []).append(r)
    per = [{"theta_deg": theta, "n": len(rs), "px_per_mm": [r["px_per_mm"] for r in rs],
            **_stats(rs), **{f"circle_{k}": v for k, v in _stats(rs, "circle_").items()}}
           for theta, rs in sorted(by.items())]
    joint = _stats(rows)
    overall = {"images": len(rows), **joint,
               "circle_fits": _stats(rows, "circle_"), **_coverage(rows),
               "targets": {"mean_le_0.2_pct": bool(joint["theta_mean_pct"] <= 0.2
                                                   and joint["length_mean_pct"] <= 0.2),
                           "max_le_0.8_pct": bool(joint["theta_max_pct"] <= 0.8
                                                  and joint["length_max_pct"] <= 0.8)}}
    return per, overall


def write_md(path, per, overall, hard, cmp, cal, argv):
    o, c = overall, overall["circle_fits"]
    lines = [
        "# Vision pipeline: accuracy on rendered photographs",
        "",
        "Middle section of a 3-section actuator (ℓ = 30 mm, Ø 3 mm), three rendered "
        "photographs per θ with every nuisance on (rotation in ±10°, radial lens "
        "distortion corrected with its calibration, blur σ = 1 px, noise σ = 4, JPEG 85, "
        "uneven lighting; 10-25 px/mm). % error = |truth − detected| / truth × 100 "
        "(the paper's Fig. 19 measure; the paper: 1.72 % for θ and 1.88 % for ℓ, mean). "
        "**Joint fit**: the measurement, one least-squares chain of three arcs between the "
        "pins; **circles**: the paper's method (a circle per section between inflection "
        "points, eqs. 38-39), for comparison. Only the pipeline's own renderer "
        "(`lcpbench vision render`) drew these images.",
        "",
        f"Produced by `{argv}` on {platform.platform()}, Python {platform.python_version()}.",
        "",
        f"**All {o['images']} images, joint fit: θ error mean {o['theta_mean_pct']:.3f} %, "
        f"max {o['theta_max_pct']:.3f} %; arc length error mean {o['length_mean_pct']:.3f} %, "
        f"max {o['length_max_pct']:.3f} %** (issue 41 targets: mean ≤ 0.2 %, max ≤ 0.8 %). "
        f"Circles: θ mean {c['theta_mean_pct']:.3f} %, max {c['theta_max_pct']:.3f} %; "
        f"ℓ mean {c['length_mean_pct']:.3f} %, max {c['length_max_pct']:.3f} %.",
        "",
        f"Standard errors: the truth within 1 s.e. in {100 * o['within_1se'][0]:.0f} % (θ) "
        f"and {100 * o['within_1se'][1]:.0f} % (ℓ) of the images, within 2 s.e. in "
        f"{100 * o['within_2se'][0]:.0f} % and {100 * o['within_2se'][1]:.0f} % (for a normal "
        f"error: 68 %, 95 %). Warnings: {o['warned']} images; more than 1 % off without a "
        f"warning: {o['off_by_1pct_without_warning']}.",
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
    if hard:
        lines += ["", "## The issue 41 hard case: θ = 34.0°, ℓ = 25.15 mm, a green tube", "",
                  "On main 308f03e a held-out render of this actuator (drawn by another "
                  "renderer, with hubs, texture and a shadow band) measured 32.13° and "
                  "23.81 mm, 5.5 % and 5.3 % off, without a warning. That render is not in "
                  "the repository; here the actuator is drawn by the pipeline's own "
                  "renderer (`--tube-hue 120`), every nuisance on:", "",
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
    lines += ["", "Figures: accuracy.png (error per θ), overlay.png, compare.png, "
              "calibration.png.", ""]
    with open(path, "w") as fh:
        fh.write("\n".join(lines))


def plot_accuracy(per, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    th = np.array([p["theta_deg"] for p in per])
    fig, ax = plt.subplots(figsize=(7, 4))
    for key, lab, off, col in (("theta", "bend angle θ", -1.2, "tab:blue"),
                               ("length", "arc length ℓ", 1.2, "tab:orange")):
        mean = np.array([p[f"{key}_mean_pct"] for p in per])
        mx = np.array([p[f"{key}_max_pct"] for p in per])
        ax.errorbar(th + off, mean, yerr=[np.zeros_like(mean), mx - mean], fmt="o", ms=4,
                    capsize=2, color=col, label=f"{lab}: mean of 3 images, bar to the max")
    ax.axhline(0.2, color="k", ls="--", lw=1, label="target for the mean (0.2 %)")
    ax.set_xlabel("true bend angle θ (deg)")
    ax.set_ylabel("% error, |truth − detected| / truth")
    ax.set_title("Middle-section error of the joint fit on rendered photographs (cf. Fig. 19)")
    ax.set_xticks(th)
    ax.tick_params(axis="x", labelsize=7)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/vision")
    ap.add_argument("--quick", action="store_true", help="θ = 30, 90, 150 and one seed")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    thetas = [30, 90, 150] if args.quick else list(range(10, 181, 10))
    rows = sweep(thetas, SEEDS[:1] if args.quick else SEEDS)
    per, overall = summarise(rows)
    hard = hard_case(2 if args.quick else 6)
    overall["hard_case"] = {**_stats(hard), **_coverage(hard)}

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
        json.dump({"command": argv, "overall": overall, "per_theta": per, "images": rows,
                   "hard_case": hard,
                   "compare": cmp, "calibration": fit.to_dict()}, fh, indent=1)
    write_md(os.path.join(args.out, "accuracy.md"), per, overall, hard, cmp, fit.to_dict(), argv)
    print(json.dumps(overall))
    return 0 if all(overall["targets"].values()) else 1


if __name__ == "__main__":
    raise SystemExit(main())
