"""Every installed back-end on the N = 140 contact step, with and without scaling.

The step is the one at the converged configuration of the paper's default
scene (θ = 150°, h = 3 mm, N = 140) — the LCP that ``lcpbench export`` writes.
The exact solution comes from the active set and is checked against Lemke
(both finite, exact methods). For each back-end, settings profile and
scaling: status, iterations, solve time as the solver reports it, the relative
error of the total force read both ways (R = K g + z from the gaps, and the
solver's multipliers), and the smallest gap and reaction.

    python benchmarks/backends_step.py [--repeat 5] [--out results/backends-step]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
import json
import platform
import statistics
import sys
from datetime import date
from pathlib import Path

import numpy as np

from lcpbench import ActuatorScene, solve
from lcpbench.bench.machine import timing_note, timing_start
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.step_solver import solve_step
from lcpbench.solvers import available_backends


def exact_step(theta=150.0, height=3.0, links=140):
    scene = ActuatorScene(theta=theta, height=height, links=links)
    result = solve(scene, tol=1e-10)
    step = assemble_step(result.scene.chain(), result.alpha)
    ref = solve_step(step, "active-set", "high")
    check = solve_step(step, "lemke", "high")
    assert ref.solved and check.solved
    f_ref, f_chk = ref.forces_net.sum(), check.forces_net.sum()
    assert abs(f_ref - f_chk) <= 1e-9 * abs(f_ref), (f_ref, f_chk)
    return step, ref


def measure(step, ref, backend, settings, scaled, repeat):
    rows = np.isfinite(step.upper)
    f_ref = float(ref.forces_net[rows].sum())
    times, wall = [], []
    for _ in range(repeat):
        sol = solve_step(step, backend, settings, scaled=scaled)
        times.append(sol.solve_time)
        wall.append(sol.wall_time)
    ok = sol.forces_net is not None and np.all(np.isfinite(sol.forces_net))
    f_gap = float(sol.forces_net[rows].sum()) if ok else np.nan
    f_mul = float((sol.forces_upper - sol.forces_lower)[rows].sum())
    return {
        "backend": backend, "settings": settings, "scaled": scaled,
        "status": sol.status.value, "message": sol.message, "iterations": sol.iterations,
        "solve_time_us": 1e6 * statistics.median(times),
        "wall_time_us": 1e6 * statistics.median(wall), "time_source": sol.time_source,
        "force_error_gaps": abs(f_gap - f_ref) / abs(f_ref),
        "force_error_multipliers": abs(f_mul - f_ref) / abs(f_ref),
        "min_gap_mm": sol.residuals.get("min_gap", np.nan) * step.length_scale,
        "min_reaction_N": sol.residuals.get("min_reaction", np.nan) * step.force_scale,
        "natural_residual": sol.residuals.get("natural", np.nan),
    }


def _fmt(x, spec=".1e"):
    if isinstance(x, float) and not np.isfinite(x):
        return "—"
    return format(x, spec)


def markdown(rows, meta) -> str:
    out = [
        "# Every back-end on the N = 140 contact step",
        "",
        f"Scene θ = {meta['theta']}°, h = {meta['height']} mm, N = {meta['links']}: the step at "
        "the converged configuration (what `lcpbench export` writes). Exact solution: the "
        f"active set, checked against Lemke; total force {meta['force_N']:.9g} N over "
        f"{meta['contact_rows']} contact rows.",
        "",
        f"Machine: {meta['machine']}; {meta['date']}; `python benchmarks/backends_step.py "
        f"--repeat {meta['repeat']}`. Times: median of {meta['repeat']}, as the solver "
        "reports them (solver) or measured around the call (wall).",
        "",
        "Force error: |ΣR − ΣR*| / ΣR*, with R read from the gaps (R = K g + z, nodes without "
        "a wall row re-solved exactly) and from the solver's multipliers. min g, min R: "
        "smallest gap (mm) and reaction (N) from the gaps.",
        "",
        "| back-end | settings | scaled | status | iter | solve µs | time | force err (K g + z) "
        "| force err (mult.) | min g (mm) | min R (N) |",
        "|---|---|---|---|---:|---:|---|---:|---:|---:|---:|",
    ]
    for r in rows:
        out.append(
            f"| {r['backend']} | {r['settings']} | {'yes' if r['scaled'] else 'no'} | "
            f"{r['status']} | {r['iterations']} | {r['solve_time_us']:.0f} | "
            f"{r['time_source']} | {_fmt(r['force_error_gaps'])} | "
            f"{_fmt(r['force_error_multipliers'])} | {_fmt(r['min_gap_mm'], '.2e')} | "
            f"{_fmt(r['min_reaction_N'], '.2e')} |")
    notes = [r for r in rows if r["status"] != "solved" and r["message"]]
    if notes:
        out += ["", "Messages of the rows not solved:", ""]
        seen = set()
        for r in notes:
            key = (r["backend"], r["message"])
            if key in seen:
                continue
            seen.add(key)
            out.append(f"- {r['backend']} ({r['settings']}, "
                       f"{'scaled' if r['scaled'] else 'raw'}): {r['message']}")
    return "\n".join(out) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--settings", default="default,high")
    ap.add_argument("--solvers", default=None, help="comma-separated (default: all installed)")
    ap.add_argument("--out", default="results/backends-step")
    args = ap.parse_args(argv)
    start = timing_start()
    step, ref = exact_step()
    names = args.solvers.split(",") if args.solvers else available_backends()
    rows = []
    for name in names:
        for settings in args.settings.split(","):
            for scaled in (True, False):
                print(f"{name:22s} {settings:8s} {'scaled' if scaled else 'raw':6s}",
                      end=" ", flush=True, file=sys.stderr)
                r = measure(step, ref, name, settings, scaled, args.repeat)
                print(f"{r['status']:15s} {r['solve_time_us']:10.0f} us "
                      f"err {r['force_error_gaps']:.1e}", file=sys.stderr)
                rows.append(r)
    rows_ = np.isfinite(step.upper)
    meta = {"theta": 150, "height": 3, "links": 140,
            "force_N": float(ref.forces_net[rows_].sum()),
            "contact_rows": int(rows_.sum()), "repeat": args.repeat,
            "machine": f"{timing_note(start)} python {platform.python_version()}",
            "date": date.today().isoformat()}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".md").write_text(markdown(rows, meta))
    out.with_suffix(".json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1,
                                                   default=float))
    print(f"wrote {out.with_suffix('.md')}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
