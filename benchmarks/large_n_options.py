"""Large N: what the acceptance fix and the twisted factor cost, as interleaved ratios.

For each N (θ = 150°, h = 3 mm, tol 1e-3), in one process with one BLAS thread,
alternating: the driver with and without its extra steps past max|Δα| < tol
(:data:`lcpbench.model.large_driver.EXTRA_STEPS`), and the face solves on the
twisted factor against the one-ended restart (:class:`TridiagonalFactor`).
Prints a markdown table (medians of ``--reps``) with the load average.

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/large_n_options.py
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="10000,30000,100000")
    ap.add_argument("--reps", type=int, default=3)
    a = ap.parse_args(argv)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    import lcpbench
    from lcpbench.linalg.saddle import TridiagonalFactor
    from lcpbench.linalg.twisted import TwistedFactor
    from lcpbench.model import large_driver, large_n
    from lcpbench.problems.scenes import ActuatorScene

    class OneEnded(TridiagonalFactor):
        def __init__(self, coef, k):
            super().__init__(coef, k, restart=True)

    variants = {"twisted, extra steps (default)": (TwistedFactor, 4),
                "twisted, no extra steps": (TwistedFactor, 0),
                "one-ended, extra steps": (OneEnded, 4),
                "one-ended, no extra steps": (OneEnded, 0)}
    lcpbench.solve(ActuatorScene(150, 3.0, links=5000), tol=1e-3)  # load the kernels
    load = os.getloadavg()
    print(f"Load average before {load[0]:.2f}.\n")
    print("| N | variant | driver (s), median | outer | face solves | converged | "
          "node bound (F₀) |\n|---|---|---|---|---|---|---|")
    for n in map(int, a.sizes.split(",")):
        scene = ActuatorScene(150, 3.0, links=n)
        times: dict[str, list[float]] = {k: [] for k in variants}
        last = {}
        for _ in range(a.reps):
            for name, (cls, extra) in variants.items():
                large_n.TwistedFactor, large_driver.EXTRA_STEPS = cls, extra
                t0 = time.perf_counter()
                r = lcpbench.solve(scene, tol=1e-3)
                times[name].append(time.perf_counter() - t0)
                last[name] = r
        large_n.TwistedFactor, large_driver.EXTRA_STEPS = TwistedFactor, 4
        base = statistics.median(times["twisted, extra steps (default)"])
        for name, r in last.items():
            t = statistics.median(times[name])
            print(f"| {n} | {name} | {t:.3f} ({t / base:.2f}×) | {r.outer_iterations} | "
                  f"{sum(s.iterations for s in r.steps)} | {r.converged} | "
                  f"{r.judgement.node_error_bound:.1e} |", flush=True)
    print(f"\nLoad average after {os.getloadavg()[0]:.2f}.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
