"""Hard cases for the nonlinear driver: globalised against the paper's undamped iteration.

Writes results/hard-cases.md (theta, h, N -> converged?, outer iterations, total force,
certificate) and prints it.

    python benchmarks/hard_cases.py [--tol 1e-8] [--out results/hard-cases.md]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
from pathlib import Path

import lcpbench
from lcpbench.bench.machine import timing_note, timing_start

CASES = [
    # theta, height, links, weight, channel, label
    (150, 3.0, 140, 2.45e-4, False, "paper default"),
    (40, 3.0, 140, 2.45e-4, False, "no contact (self-weight sag)"),
    (120, 5.0, 140, 0.0, False, "near-grazing, weightless"),
    (170, 3.0, 140, 2.45e-4, False, "theta 170"),
    (180, 2.0, 140, 2.45e-4, False, "theta 180"),
    (180, 1.0, 140, 2.45e-4, False, "theta 180, h 1"),
    (180, 0.6, 140, 2.45e-4, False, "theta 180, h = 0.02 l"),
    (150, 0.6, 140, 2.45e-4, False, "h = 0.02 l"),
    (180, 0.6, 10, 2.45e-4, False, "N 10"),
    (180, 0.6, 2000, 2.45e-4, False, "N 2000"),
    (150, 3.0, 2000, 2.45e-4, False, "N 2000, paper scene"),
    (150, 3.0, 140, 0.05, False, "heavy chain (sags off)"),
    (150, 3.0, 140, 0.02, False, "heavy chain (still touching)"),
    (180, 1.0, 140, 2.45e-4, True, "channel"),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--out", default="results/hard-cases.md")
    args = ap.parse_args()
    start = timing_start()
    head = ("| case | θ (deg) | h (mm) | N | w (N/mm) | method | converged | outer | "
            "total force (N) | min gap (mm) | rel. torque residual | time (ms) |")
    lines = [f"# Hard cases for the driver (tol = {args.tol:g} rad)", "",
             "Made by `python benchmarks/hard_cases.py`. Certificate values come from the exact "
             "nonlinear geometry; times are one run on a shared 2-core machine.", "", head,
             "|" + "---|" * (head.count("|") - 1)]
    for th, h, n, w, ch, label in CASES:
        scene = lcpbench.ActuatorScene(theta=th, height=h, links=n, weight=w, channel=ch)
        for method in ("globalised", "undamped"):
            r = lcpbench.solve(scene, tol=args.tol, method=method)
            c = r.certificate
            conv = "yes" if r.converged else f"no: {r.reason.split(':')[0]}"
            lines.append(
                f"| {label} | {th:g} | {h:g} | {n} | {w:g} | {method} | {conv} | "
                f"{r.outer_iterations} | {r.total_force:.6g} | {c.min_gap:.2e} | "
                f"{c.relative_torque_residual:.1e} | {r.time_s * 1e3:.1f} |")
    lines[3:3] = ["", f"Machine: {timing_note(start)}"]
    text = "\n".join(lines) + "\n"
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
