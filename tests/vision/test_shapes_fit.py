"""The fit from photographs (vision/shapes_fit.py, issue 38 item 3), by round trips:
shapes drawn from the model at known parameters (and photographs drawn by the
renderer), written as `lcpbench vision measure --json` writes them, then fitted.

The data: free shapes give the middle section's θ = slope · P + intercept (+ noise);
pressed shapes are the model's centre line (its N + 1 nodes, pin to pin) at
θ(P), h = 4 mm in a channel, EI = 40 N mm², w = 5× the paper's (the shape sees EI
only through wℓ³/EI), each coordinate + N(0, σ) noise, σ = 2 µm (0.03 px at
15 px/mm, the centre line's accuracy on renders, docs/vision.md).
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.errors import ProblemError
from lcpbench.problems.calibrations import linear_calibration
from lcpbench.vision.shapes_fit import Shape, fit_shapes, read_shapes, section_points

SLOPE, INTERCEPT, EI, W = 0.8, 10.0, 40.0, 5 * 2.45e-4
START = ActuatorScene(theta=150, height=4.0, links=140, EI=32.01, weight=W, channel=True)
GUESS = linear_calibration(0.81, 9.78)  # (unused where free shapes give the line)


def measured(res_or_points, theta):
    """A `vision measure --json` dict of one section: its centre line, ends, θ."""
    c = np.asarray(res_or_points, float)
    return {"centerline_mm": c.tolist(), "pin_span_mm": float(c[-1, 0]),
            "sections": [{"theta_deg": theta, "start_mm": c[0].tolist(),
                          "end_mm": c[-1].tolist()}],
            "middle": {"theta_deg": theta, "index": 0}, "circle_fits": None}


def pressed_shape(P, rng, sigma, *, weight=W, height=4.0):
    theta = SLOPE * P + INTERCEPT
    res = lcpbench.solve(ActuatorScene(theta=theta, height=height, links=140, EI=EI,
                                       weight=weight, channel=True), tol=1e-11)
    assert res.converged
    c = np.column_stack([res.x, res.y])
    if sigma:
        c = c + rng.normal(0.0, sigma, c.shape)
    return measured(c, theta)


def shapes(rng, sigma, theta_sigma, free=(60, 80, 100, 120, 140, 160), pressed=(150, 170)):
    out = [Shape(P, None, SLOPE * P + INTERCEPT + (rng.normal(0, theta_sigma) if theta_sigma
                                                   else 0.0), np.zeros((8, 2))) for P in free]
    for P in pressed:
        pts, th = section_points(pressed_shape(P, rng, sigma))
        out.append(Shape(P, 4.0, th, pts))
    return out


def test_exact_shapes_give_back_the_line_and_EI():
    got = fit_shapes(START, shapes(None, 0.0, 0.0, free=(60, 100, 140)), GUESS, tol=1e-11)
    assert got.line_fitted and (got.free, got.pressed) == (3, 2)
    assert got.slope == pytest.approx(SLOPE, rel=1e-12)
    assert got.intercept == pytest.approx(INTERCEPT, rel=1e-12)
    assert got.EI == pytest.approx(EI, rel=1e-6)
    assert got.rms_mm < 1e-7


def test_noisy_shapes_give_EI_within_its_interval():
    """20 data sets (seeds 100-119, not chosen): 6 free shapes (θ noise 0.05°) and 2
    pressed ones (σ = 2 µm). The 95 % interval covers the true EI in at least 17 (a
    well-calibrated interval: 19 on average; at most 16 has probability 1.6 %), every
    estimate is within 3.5 s.e., and the s.e. is at most 10 % (4-7 % here)."""
    covered = 0
    for seed in range(100, 120):
        got = fit_shapes(START, shapes(np.random.default_rng(seed), 0.002, 0.05), GUESS)
        covered += got.EI_low <= EI <= got.EI_high
        assert abs(got.EI - EI) <= 3.5 * got.EI_se, seed
        assert got.EI_se <= 0.1 * EI, seed
    assert covered >= 17


def test_a_weightless_chain_does_not_determine_EI():
    """Without weight the pressed shape does not depend on EI at all: the interval is
    unbounded, never a false precision."""
    rng = np.random.default_rng(3)
    pts, th = section_points(pressed_shape(150, rng, 0.002, weight=0.0))
    scene = ActuatorScene(theta=150, height=4.0, links=140, weight=0.0, channel=True)
    got = fit_shapes(scene, [Shape(150, 4.0, th, pts)], linear_calibration(SLOPE, INTERCEPT))
    assert not got.line_fitted and got.EI_high == np.inf and got.EI_low == 0.0


def _write(tmp_path, rows):
    lines = ["shape,pressure_kpa,height_mm"]
    for k, (meas, P, h) in enumerate(rows):
        (tmp_path / f"s{k}.json").write_text(json.dumps(meas))
        lines.append(f"s{k}.json,{P},{'' if h is None else h}")
    path = tmp_path / "shapes.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_the_cli_reads_vision_measure_json_and_fits(tmp_path):
    rng = np.random.default_rng(7)
    rows = [(measured(np.zeros((9, 2)) + [[i, 0.0] for i in range(9)],
                      SLOPE * P + INTERCEPT), P, None) for P in (60, 100, 140)]
    rows += [(pressed_shape(P, rng, 0.0), P, 4.0) for P in (150, 170)]
    path = _write(tmp_path, rows)
    assert len(read_shapes(path)) == 5
    plot = tmp_path / "fit.png"
    run = subprocess.run([sys.executable, "-m", "lcpbench.cli", "fit", "--shapes", str(path),
                          "--height", "4", "--channel", "--weight", str(W), "--json",
                          "--plot", str(plot)], capture_output=True, text=True, check=True)
    assert plot.stat().st_size > 10_000
    got = json.loads(run.stdout)
    assert got["slope"] == pytest.approx(SLOPE, rel=1e-9)
    assert got["EI"] == pytest.approx(EI, rel=1e-5)
    assert got["EI_low"] < got["EI"] < got["EI_high"]
    bad = tmp_path / "bad.csv"
    bad.write_text("file,pressure\ns0.json,60\n")
    run = subprocess.run([sys.executable, "-m", "lcpbench.cli", "fit", "--shapes", str(bad)],
                         capture_output=True, text=True)
    assert run.returncode == 2 and run.stderr.count("\n") == 1 and "header" in run.stderr
    with pytest.raises(ProblemError, match="vision measure"):
        section_points({"centerline_mm": [[0, 0]] * 10}, "x.json")


def test_rendered_photographs_give_back_the_line_and_EI():
    """Photographs drawn by the renderer (no nuisances, 15 px/mm) and measured by the
    pipeline: three free actuators at θ(P), and two pressed into a 4 mm channel (walls'
    faces at 5.5 mm) with EI = 40 N mm² and w = 20× the paper's (wℓ³/EI = 3.3: the
    shape sees EI). The line within 1e-4 (slope) and 0.02° (intercept): the pipeline
    measures θ to ~0.001° here; EI within 3 %: the measured centre line carries ~1 µm of
    systematic error, 1.6 % of EI here (its interval, from the scatter alone, is
    narrower than that)."""
    import dataclasses

    from lcpbench.vision.measure import measure
    from lcpbench.vision.render import render_constrained, render_unconstrained

    out = []
    for P in (60, 100, 140):
        img, truth = render_unconstrained(SLOPE * P + INTERCEPT, px_per_mm=15.0)
        meas = json.loads(json.dumps(measure(img, calibration=truth.get("calibration"))
                                     .to_dict()))
        pts, th = section_points(meas)
        out.append(Shape(P, None, th, pts))
    heavy = dataclasses.replace(START, links=200, weight=20 * 2.45e-4)
    for P in (150, 170):
        res = lcpbench.solve(dataclasses.replace(heavy, EI=EI, theta=SLOPE * P + INTERCEPT),
                             tol=1e-11)
        img, truth = render_constrained(res.x, res.y, wall_height=4.0 + 1.5, px_per_mm=15.0)
        meas = json.loads(json.dumps(measure(img, calibration=truth.get("calibration"))
                                     .to_dict()))
        pts, th = section_points(meas)
        out.append(Shape(P, 4.0, th, pts))
    got = fit_shapes(heavy, out, GUESS)
    assert got.slope == pytest.approx(SLOPE, rel=1e-4)
    assert got.intercept == pytest.approx(INTERCEPT, abs=0.02)
    assert got.EI == pytest.approx(EI, rel=0.03)
