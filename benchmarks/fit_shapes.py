"""Issue 38, item 3: the fit from photographs (``lcpbench fit --shapes``) on synthetic shapes.

For each weight (1×, 5× and 20× the paper's 0.245 N/m) ``--trials`` trials: 6 free
shapes at P = 60, 80, …, 160 kPa with the measured θ = 0.8 P + 10° + 0.05° z, and 2
pressed ones at P = 150 and 170 kPa, the model's centre line (N = 140, a 4 mm channel,
EI = 40 N mm², forward solves at tol 1e-11) with each coordinate + σ z, σ = 2 µm (the
centre line's accuracy on renders, docs/vision.md), z ~ N(0, 1) from numpy's
default_rng(seed). Each is fitted by :func:`lcpbench.vision.shapes_fit.fit_shapes` from
EI = 32.01 N mm². Reports the line's and EI's errors, the share of EI within 2 %, and
how often the 95 % intervals cover the truth. The data come from the model (no model or
photograph error: the renderer round trip is in tests/vision/test_shapes_fit.py).
Writes ``results/fit-shapes.md`` (``--out``; not overwritten without ``--force``).

    python benchmarks/fit_shapes.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite
from lcpbench.problems.calibrations import linear_calibration
from lcpbench.vision.shapes_fit import Shape, fit_shapes, section_points

ROOT = Path(__file__).resolve().parents[1]
SLOPE, INTERCEPT, EI_TRUE, H, N, SIGMA, THETA_SD = 0.8, 10.0, 40.0, 4.0, 140, 0.002, 0.05
FREE, PRESSED = (60, 80, 100, 120, 140, 160), (150, 170)


def pressed(P, weight, cache):
    if (P, weight) not in cache:
        theta = SLOPE * P + INTERCEPT
        res = lcpbench.solve(ActuatorScene(theta=theta, height=H, links=N, EI=EI_TRUE,
                                           weight=weight, channel=True), tol=1e-11)
        cache[P, weight] = (np.column_stack([res.x, res.y]), theta)
    return cache[P, weight]


def trial(rng, weight, cache):
    out = [Shape(P, None, SLOPE * P + INTERCEPT + THETA_SD * rng.standard_normal(),
                 np.zeros((8, 2))) for P in FREE]
    for P in PRESSED:
        c, theta = pressed(P, weight, cache)
        c = c + SIGMA * rng.standard_normal(c.shape)
        pts, th = section_points({
            "centerline_mm": c.tolist(), "pin_span_mm": float(c[-1, 0]),
            "sections": [{"theta_deg": theta, "start_mm": c[0].tolist(),
                          "end_mm": c[-1].tolist()}],
            "middle": {"theta_deg": theta, "index": 0}})
        out.append(Shape(P, H, th, pts))
    start = ActuatorScene(theta=150.0, height=H, links=N, weight=weight, channel=True)
    return fit_shapes(start, out, linear_calibration(0.81, 9.78))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--trials", type=int, default=100)
    p.add_argument("--seed", type=int, default=2026)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "fit-shapes.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("fit_shapes.py", argv)
    rng = np.random.default_rng(a.seed)
    rows, cache, t0 = [], {}, time.perf_counter()
    for mult in (1, 5, 20):
        w = mult * 2.45e-4
        err, cov, half, line_cov, slope_err, solves = [], 0, [], 0, [], []
        for _ in range(a.trials):
            got = trial(rng, w, cache)
            err.append(got.EI / EI_TRUE - 1)
            cov += got.EI_low <= EI_TRUE <= got.EI_high
            half.append((got.EI_high - got.EI_low) / (2 * EI_TRUE))
            line_cov += (got.slope_ci95[0] <= SLOPE <= got.slope_ci95[1]
                         and got.intercept_ci95[0] <= INTERCEPT <= got.intercept_ci95[1])
            slope_err.append(abs(got.slope / SLOPE - 1))
            solves.append(got.solves)
        e = np.abs(np.array(err))
        rows.append(f"| {mult}× ({w * wl3(1):.2f}) | {a.trials} | {np.mean(e <= 0.02):.0%} | "
                    f"{np.median(e):.1%} | {cov / a.trials:.0%} | {np.median(half):.1%} | "
                    f"{np.median(slope_err):.1e} | {line_cov / a.trials:.0%} | "
                    f"{int(np.median(solves))} |")
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# The fit from photographs on synthetic shapes (issue 38, item 3)", "",
        f"Computed {when} by `{cmd}` in {time.perf_counter() - t0:.0f} s. Data (per trial): 6 free "
        f"shapes at P = {', '.join(map(str, FREE))} kPa, measured θ = {SLOPE:g} P + "
        f"{INTERCEPT:g}° + {THETA_SD:g}° z; 2 pressed shapes at P = "
        f"{', '.join(map(str, PRESSED))} kPa: the model's centre line (N = {N}, a {H:g} mm "
        f"channel, EI = {EI_TRUE:g} N mm², tol 1e-11), each coordinate + {1e3 * SIGMA:g} µm "
        "z; z ~ N(0, 1). The fit starts from EI = 32.01 N mm² and the line 0.81 P + 9.78°. "
        "The data come from the model (no model or photograph error).", "",
        "| weight (wℓ³/EI) | trials | EI within 2 % | median EI error | 95 % interval "
        "covers EI | median half-width | median slope error | line's intervals cover | "
        "median solves |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|", *rows, "",
        "A pressed shape sees EI only through wℓ³/EI: at the paper's weight two pressed "
        "shapes measured to 2 µm leave EI uncertain by tens of per cent (the interval says "
        "so); forces (`fit --data`, results/fit-ei.md) determine it.", ""])
    a.out.write_text(text)
    print(text)
    return 0


def wl3(mult: float) -> float:
    """wℓ³/EI per unit w at the true EI and ℓ = 30 mm."""
    return mult * 30.0**3 / EI_TRUE


if __name__ == "__main__":
    sys.exit(main())
