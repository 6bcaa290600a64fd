"""Issue 36, target 5: the second-order check's share of a solve at N = 140.

Interleaved in one process, one BLAS thread: the default solve of the paper's scene
(θ = 150°, h = 3 mm, N = 140) against the check itself, called natively (a compiled
loop over the judge kernel's call of ``stability_kernel.unstable_directions``, so no
Python dispatch is counted: inside the judge kernel there is none). Prints the
medians over rounds and their ratio, with the load.

    python benchmarks/stability_cost.py [--rounds 15]
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

import lcpbench  # noqa: E402
from lcpbench.model.judge import stability_args  # noqa: E402
from lcpbench.numba_cache import kernel_module  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=15)
    args = p.parse_args(argv)
    check = kernel_module("lcpbench.model.stability_kernel",
                          "unstable_directions").unstable_directions

    @njit
    def repeat(times, args, thr, pin):
        total = 0
        for _ in range(times):
            total += check(*args, thr, pin)[1]
        return total

    scene = lcpbench.ActuatorScene(theta=150, height=3.0)
    r = lcpbench.solve(scene)
    ch = scene.chain()
    _, kernel_args = stability_args(ch, r.alpha, r.forces, np.zeros(r.forces.size))
    call = (kernel_args, r.judgement.contact_threshold, True)
    repeat(10, *call)
    solves, checks = [], []
    load = os.getloadavg()[0]
    for _ in range(args.rounds):
        t = time.perf_counter()
        for _ in range(200):
            lcpbench.solve(scene)
        solves.append((time.perf_counter() - t) / 200)
        t = time.perf_counter()
        repeat(2000, *call)
        checks.append((time.perf_counter() - t) / 2000)
    s, c = float(np.median(solves)), float(np.median(checks))
    print(f"N = 140 default solve {s * 1e6:.1f} us, second-order check {c * 1e6:.2f} us "
          f"({100 * c / s:.1f} % of the solve); {args.rounds} interleaved rounds, "
          f"load {load:.2f} -> {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
