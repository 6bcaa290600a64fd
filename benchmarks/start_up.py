"""Issue 19, target 7: start-up of a fresh process, and the AOT kernels' steady state.

Fresh processes (``python -c``, bytecode caching on, as for an installed package;
one BLAS thread), interleaved, medians of ``--starts``:

- ``import lcpbench``;
- the first ``lcpbench.solve`` (N = 140, θ = 150°, h = 3 mm, tol 1e-3) with the
  cache warm, two ways: the default (the ahead-of-time kernels, no numba) and
  ``LCPBENCH_AOT=0`` (numba's on-disk JIT cache, through the light loader);
- the second solve (steady state).

"Warm" means: numba's on-disk cache of the kernels is filled and the AOT module of
the current kernels is built (``python -m lcpbench.aot``, run here first when it is
missing, its wall time recorded), and one process of each kind has run before the
timed ones (the files are in the OS's page cache). Not included: a cold disk.

Steady state, in this process: ``lcpbench.solve`` at N = 140 with the AOT kernels
against the JIT kernels (``numba_cache.use_aot``), interleaved blocks.

    python benchmarks/start_up.py [--starts 7] [--repeat 31]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

START = ("import time; P, T = time.process_time, time.perf_counter; c0, t0 = P(), T(); "
         "import lcpbench; c1, t1 = P(), T(); "
         "s = lcpbench.ActuatorScene(theta=150, height=3.0); r = lcpbench.solve(s); "
         "c2, t2 = P(), T(); import sys; numba = 'numba' in sys.modules; "
         "lcpbench.solve(s); c3, t3 = P(), T(); "
         "print(t1 - t0, c1 - c0, t2 - t1, c2 - c1, t3 - t2, c3 - c2, numba, "
         "r.engine)")
NAMES = ("import_wall_s", "import_cpu_s", "first_wall_s", "first_cpu_s", "second_wall_s",
         "second_cpu_s")
HAS_AOT = ("from lcpbench import numba_cache as n; "
           "print(n.aot_kernels('lcpbench.model.compiled_kernel') is not None)")


def _fresh(code: str, **env) -> list[str]:
    env = {**{k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}, **env}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True, env=env).stdout.split()


def ensure_aot() -> dict:
    """Build the AOT module where it is missing (``python -m lcpbench.aot``)."""
    if _fresh(HAS_AOT) == ["True"]:
        return {"built_here": False}
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "lcpbench.aot"], capture_output=True,
                         text=True)
    return {"built_here": True, "build_wall_s": time.perf_counter() - t0,
            "build_ok": out.returncode == 0, "build_says": (out.stdout + out.stderr).strip()}


def start_up(starts: int) -> dict:
    """Fresh processes, the AOT default and the JIT cache interleaved; medians."""
    aot = ensure_aot()
    ways = {"aot": {}, "jit": {"LCPBENCH_AOT": "0"}}
    for env in ways.values():  # warm: numba's cache, the page cache
        _fresh(START, **env)
    cols = {w: [[] for _ in NAMES] for w in ways}
    numba, engines = {w: set() for w in ways}, {w: set() for w in ways}
    for _ in range(starts):
        for w, env in ways.items():
            out = _fresh(START, **env)
            for i in range(len(NAMES)):
                cols[w][i].append(float(out[i]))
            numba[w].add(out[6] == "True")
            engines[w].add(out[7])
    imp = _fresh("import sys, lcpbench; print('numba' in sys.modules, 'scipy' in sys.modules)")
    res = {w: {**{n: statistics.median(c) for n, c in zip(NAMES, cols[w], strict=True)},
               "first_solve_imports_numba": sorted(numba[w]), "engines": sorted(engines[w])}
           for w in ways}
    return {**res["aot"], "jit": res["jit"], "aot_module": aot,
            "import_loads_numba": imp[0] == "True", "import_loads_scipy": imp[1] == "True",
            "engines": res["aot"]["engines"], "starts": starts}


def steady_state(repeat: int, block: int = 20) -> dict:
    """In this process, blocks of ``block`` calls interleaved, medians of the per-call
    time: ``lcpbench.solve`` (N = 140) with the AOT kernels and with the JIT kernels
    (``numba_cache.use_aot``), and one call of the solve kernel alone, AOT (its argument
    check included) against JIT (numba's dispatch included), on the same arguments."""
    import numpy as np

    import lcpbench
    from lcpbench import numba_cache
    from lcpbench.model.kernel_call import kernel_args

    scene = lcpbench.ActuatorScene(theta=150, height=3.0)
    chain = scene.chain()
    n = chain.free_nodes.size
    args = (*kernel_args(chain), 1e-3, 200, np.zeros(0), np.zeros(n), np.zeros(n, bool),
            np.zeros(n, bool), 0, 20 * n + 50, 1e-10, False)
    name = "lcpbench.model.compiled_kernel"
    times: dict = {"aot": [], "jit": [], "kernel aot": [], "kernel jit": []}
    served = {}
    try:
        for _ in range(repeat):
            for way in ("aot", "jit"):
                numba_cache.use_aot(way == "aot")
                lcpbench.solve(scene)  # the switch's look-up, outside the clock
                k = numba_cache.kernel_module(name, "solve_chain")
                served[way] = type(k).__name__
                t0 = time.perf_counter()
                for _ in range(block):
                    lcpbench.solve(scene)
                times[way].append((time.perf_counter() - t0) / block)
                t0 = time.perf_counter()
                for _ in range(block):
                    k.solve_chain(*args)
                times[f"kernel {way}"].append((time.perf_counter() - t0) / block)
    finally:
        numba_cache.use_aot(None)
    med = {w: statistics.median(t) * 1e6 for w, t in times.items()}
    return {"aot_us": med["aot"], "jit_us": med["jit"], "aot_min_us": min(times["aot"]) * 1e6,
            "jit_min_us": min(times["jit"]) * 1e6, "jit_over_aot": med["jit"] / med["aot"],
            "kernel_aot_us": med["kernel aot"], "kernel_jit_us": med["kernel jit"],
            "served": served, "repeat": repeat, "block": block}


def markdown(s: dict, steady: dict | None = None) -> list[str]:
    """The start-up section of perf.md."""
    j, a = s.get("jit"), s.get("aot_module", {})
    built = (f"built here in {a['build_wall_s']:.0f} s ({a['build_says']})"
             if a.get("built_here") else "built before this run")
    L = [f"### Start-up (fresh processes, median of {s['starts']}, interleaved; cache warm)",
         "",
         "Warm: numba's on-disk cache of the kernels filled and the ahead-of-time module "
         f"built (`lcpbench compile`; {built}), one process of each kind run first.", "",
         "| | import lcpbench | first solve | second solve | first solve imports numba | "
         "engine |", "|---|---|---|---|---|---|"]
    rows = [("the default (AOT kernels where built)", s), ("`LCPBENCH_AOT=0` (JIT cache)", j)]
    for label, r in rows:
        if r is None or "first_solve_imports_numba" not in r:  # a run before the AOT kernels
            continue
        L.append(f"| {label} | {r['import_wall_s'] * 1e3:.0f} ms ({r['import_cpu_s'] * 1e3:.0f}"
                 f" CPU) | {r['first_wall_s'] * 1e3:.0f} ms ({r['first_cpu_s'] * 1e3:.0f} CPU) "
                 f"| {r['second_wall_s'] * 1e3:.2f} ms | "
                 f"{', '.join(map(str, r['first_solve_imports_numba']))} | "
                 f"{', '.join(r['engines'])} |")
    L += ["", f"`import lcpbench` loads numba: {s['import_loads_numba']}, scipy: "
          f"{s['import_loads_scipy']}."]
    if steady:
        L += ["", f"Steady state, `lcpbench.solve` N = 140 in one process ({steady['repeat']} "
              f"interleaved blocks of {steady['block']}): AOT kernels "
              f"{steady['aot_us']:.0f} µs, JIT kernels {steady['jit_us']:.0f} µs (JIT / AOT "
              f"{steady['jit_over_aot']:.2f}; minima {steady['aot_min_us']:.0f} / "
              f"{steady['jit_min_us']:.0f} µs); the solve kernel alone (its call included) "
              f"{steady['kernel_aot_us']:.0f} µs AOT, {steady['kernel_jit_us']:.0f} µs JIT" + (
                  "." if steady["served"].get("aot") == "AotKernels" else
                  "; no AOT module was found, so both are the JIT.")]
    return L + [""]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--starts", type=int, default=7)
    ap.add_argument("--repeat", type=int, default=31, help="steady-state blocks per way")
    args = ap.parse_args(argv)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"
    load0 = os.getloadavg()
    s = start_up(args.starts)
    steady = steady_state(args.repeat)
    print("\n".join(markdown(s, steady)))
    print(f"load average {load0[0]:.2f} (start), {os.getloadavg()[0]:.2f} (end)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
