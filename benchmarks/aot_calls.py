"""One call of the solve and judge kernels: the AOT module against numba's JIT.

In one process, interleaved blocks of ``--block`` calls, medians and minima of the
per-call time (µs): each kernel ahead of time with :class:`AotKernels`'s argument
check ("checked"), the extension's function alone ("raw"), and the JIT dispatcher,
on the arguments one ``lcpbench.solve`` of the paper's actuator (N = 140) passes.
Needs the AOT module (``lcpbench compile``; ``LCPBENCH_AOT_DIR`` names another one).
Pin BLAS to one thread and record the load (the script prints it).

    python benchmarks/aot_calls.py [--repeat 60] [--block 50]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

KERNELS = {"solve": ("lcpbench.model.compiled_kernel", "solve_chain"),
           "judge": ("lcpbench.model.judge_kernel", "judge_answer")}


def calls() -> dict:
    """{label: a function of no arguments making one kernel call}."""
    import lcpbench
    from lcpbench import numba_cache

    scene = lcpbench.ActuatorScene(theta=150, height=3.0)
    numba_cache.use_aot(True)
    out = {}
    try:
        lcpbench.solve(scene)
        captured = {}
        for label, (name, entry) in KERNELS.items():
            aot = numba_cache.kernel_module(name, entry)
            if not isinstance(aot, numba_cache.AotKernels):
                raise SystemExit(f"no AOT module for {name} (run `lcpbench compile`)")
            plain = getattr(aot, entry)

            def spy(*a, _plain=plain, _label=label):
                captured.setdefault(_label, a)
                return _plain(*a)
            setattr(aot, entry, spy)
            captured[label + " kernels"] = (aot, entry, plain)
        lcpbench.solve(scene)
        for label, (name, entry) in KERNELS.items():
            aot, _, plain = captured[label + " kernels"]
            setattr(aot, entry, plain)
            args = captured[label]
            raw = getattr(aot._module, f"{name.rsplit('.', 1)[-1]}__{entry}")  # build_aot's
            jit = getattr(numba_cache.jit_module(name), entry)
            jit(*args)  # loaded and compiled outside the clock
            out[f"{label} checked"] = lambda f=plain, a=args: f(*a)
            out[f"{label} raw"] = lambda f=raw, a=args: f(*a)
            out[f"{label} jit"] = lambda f=jit, a=args: f(*a)
    finally:
        numba_cache.use_aot(None)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=60)
    ap.add_argument("--block", type=int, default=50)
    args = ap.parse_args(argv)
    load0 = os.getloadavg()[0]
    ways = calls()
    times: dict = {k: [] for k in ways}
    for _ in range(args.repeat):
        for k, f in ways.items():
            t0 = time.perf_counter()
            for _ in range(args.block):
                f()
            times[k].append((time.perf_counter() - t0) / args.block * 1e6)
    print(f"| call ({args.repeat} interleaved blocks of {args.block}) | median µs | min µs |")
    print("|---|---|---|")
    for k, t in times.items():
        print(f"| {k} | {statistics.median(t):.1f} | {min(t):.1f} |")
    print(f"\nload average {load0:.2f} (start), {os.getloadavg()[0]:.2f} (end)")
    return 0


if __name__ == "__main__":
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    raise SystemExit(main())
