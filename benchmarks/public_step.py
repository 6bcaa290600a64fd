"""Issue 35, target 4: the public step call on the N = 140 step against Siconos Lemke.

The step at the paper scene's converged configuration (θ = 150°, h = 3 mm, N = 140;
the step `lcpbench export` writes as an LCP) is solved by the public calls, timed
from Python as a user calls them, interleaved:

- ``lcpbench.model.step_solver.solve_step(step, "active-set")`` (the compiled walk,
  its certificate and lcpbench's residuals);
- ``solve_step(step, "siconos-lemke")`` (the dense LCP formed, Siconos' C Lemke, the
  same residuals);
- ``lcpbench.solvers.runner.solve_lcp(M, q, "siconos-lemke")`` on the exported LCP
  (M, q already formed: the C call and its residuals alone);
- ``solve_lcp(M, q, "active-set")`` on the same LCP (issue 35, item 5: the compiled
  walk, its faces LAPACK's Cholesky of their free block, M being dense).

The answers are checked against each other (forces, and the LCP's z, 1e-9 relative)
before timing.
Writes ``results/public-step.md`` (``--out``; not overwritten without ``--force``).

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/public_step.py --force
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
from perf import interleaved, wall  # (benchmarks/ is the script's directory)

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.step_solver import solve_step, step_lcp
from lcpbench.solvers.registry import available_backends
from lcpbench.solvers.runner import solve_lcp

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=41)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "public-step.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    if "siconos-lemke" not in available_backends():
        print("error: siconos-lemke is not installed (apt-get install python3-siconos)",
              file=sys.stderr)
        return 2
    refuse_overwrite([a.out], a.force)
    cmd = command_line("public_step.py", argv)
    start = timing_start()
    result = lcpbench.solve(ActuatorScene(theta=150, height=3.0, links=140), tol=1e-10)
    step = assemble_step(result.scene.chain(), result.alpha)
    _, M, q, _, _ = step_lcp(step, scaled=True)
    ours, theirs = solve_step(step, "active-set"), solve_step(step, "siconos-lemke")
    rows = np.isfinite(step.upper)
    f1, f2 = ours.forces_net[rows].sum(), theirs.forces_net[rows].sum()
    assert ours.solved and theirs.solved and abs(f1 - f2) <= 1e-9 * abs(f2), (f1, f2)
    z_walk, z_lemke = solve_lcp(M, q, "active-set"), solve_lcp(M, q, "siconos-lemke")
    assert z_walk.solved and z_walk.extra["backend"] == "active-set" and z_lemke.solved
    assert np.max(np.abs(z_walk.z - z_lemke.z)) <= 1e-9 * np.max(np.abs(z_lemke.z))
    calls = {
        "solve_step(step, 'active-set') (compiled)": lambda: solve_step(step, "active-set"),
        "solve_step(step, 'siconos-lemke')": lambda: solve_step(step, "siconos-lemke"),
        "solve_lcp(M, q, 'siconos-lemke') (exported LCP)": lambda: solve_lcp(M, q,
                                                                             "siconos-lemke"),
        "solve_lcp(M, q, 'active-set') (exported LCP, compiled walk)": lambda: solve_lcp(
            M, q, "active-set"),
    }
    times = {name: g["times"] for name, g in interleaved(
        {name: wall(call) for name, call in calls.items()}, a.rounds).items()}
    ours_med = float(np.median(times[next(iter(calls))]))
    lines = ["| call | median (µs) | min (µs) | × the compiled step |", "|---|---:|---:|---:|"]
    for name, t in times.items():
        lines.append(f"| `{name}` | {1e6 * np.median(t):.1f} | {1e6 * min(t):.1f} | "
                     f"{np.median(t) / ours_med:.1f} |")
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# The public step call against Siconos Lemke (issue 35, target 4)", "",
        f"Measured {when}; {timing_note(start)} Command: `{cmd}`. The N = 140 step at the paper scene's converged "
        f"configuration ({step.size} free nodes), {a.rounds} interleaved rounds, wall time "
        f"of each public call from Python. Total force: {f1:.12g} N (active set) and "
        f"{f2:.12g} N (Siconos Lemke). Target: ≥ 20× Siconos Lemke.", "", *lines, ""])
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
