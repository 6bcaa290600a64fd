"""Time one full nonlinear contact solve: the paper's dense path against the banded path.

Dense path: eqs. (3)–(31) assembled densely, A inverted, Lemke, the undamped Fig. 3
iteration (lcpbench.reference.dense.solve_paper_dense). Banded path: lcpbench.solve
(energy-based pentadiagonal step, active-set QP, globalised driver). Same scene,
same tolerance, same run; prints times and their ratio (the machine is shared:
read the ratio, not the seconds).

    python benchmarks/full_solve.py [--links 140] [--theta 150] [--height 3] [--repeat 20]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
import platform
import statistics
import time

import lcpbench
from lcpbench.bench.machine import timing_note, timing_start
from lcpbench.reference.dense import solve_paper_dense


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), statistics.median(times), out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", type=int, default=140)
    ap.add_argument("--theta", type=float, default=150.0)
    ap.add_argument("--height", type=float, default=3.0)
    ap.add_argument("--tol", type=float, default=1e-3)
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args()
    start = timing_start()
    scene = lcpbench.ActuatorScene(theta=args.theta, height=args.height, links=args.links)
    d_best, d_med, (_, R, d_it, d_ok) = best_of(
        lambda: solve_paper_dense(scene, tol=args.tol), args.repeat)
    b_best, b_med, res = best_of(lambda: lcpbench.solve(scene, tol=args.tol), args.repeat)
    print(f"machine: {timing_note(start)} python {platform.python_version()}")
    print(f"scene: theta={args.theta} h={args.height} N={args.links} tol={args.tol}")
    print(f"dense  (paper eqs. 3-31 + Lemke, undamped): best {d_best*1e3:8.2f} ms  median "
          f"{d_med*1e3:8.2f} ms  outer {d_it}  converged {d_ok}  force {R.sum():.6f} N")
    print(f"banded (energy step + active set, globalised): best {b_best*1e3:8.2f} ms  median "
          f"{b_med*1e3:8.2f} ms  outer {res.outer_iterations}  converged {res.converged}  "
          f"force {res.total_force:.6f} N")
    print(f"speed-up dense/banded (best): {d_best / b_best:.1f}x")


if __name__ == "__main__":
    main()
