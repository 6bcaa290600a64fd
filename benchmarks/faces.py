"""Issue 19 (targets 1, 2, 6): the solve kernel's faces, this tree against another's.

Times, interleaved in one process with one BLAS thread, this tree's kernels
against those of another source tree (default ``/work/main/src``, imported under
the name ``lcpbench_base``; its numba cache in a directory of its own):

- the solve kernel alone (``model/compiled_kernel.solve_chain``) at N = 140,
  θ = 150°, h = 3 mm, tol 1e-3;
- the whole ``lcpbench.solve`` of that scene, with either solve kernel (all the
  rest, the judge included, is this tree's);
- ``lcpbench.solve_many`` over the paper's 108 scenes at tol 1e-3, with either
  line kernel (``model/batch_kernel.solve_line``, which calls the solve kernel);

and counts the face solves per outer step of both, on that scene and summed over
the paper grid (cold solves, tol 1e-3 and 1e-9). Both trees run their JIT kernels
(``LCPBENCH_AOT=0``): the ahead-of-time module is built for one tree only.

    python benchmarks/faces.py [--base /work/main/src] [--repeat 15] [--out FILE]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"
os.environ["LCPBENCH_AOT"] = "0"

import argparse
import importlib
import statistics
import sys
import tempfile
import time
import types
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene, numba_cache
from lcpbench.bench.grid import PAPER_GRID
from lcpbench.model import compiled
from lcpbench.model import kernel_call as calls
from lcpbench.model.kernel_call import kernel_args

BASE = "lcpbench_base"
SCENE = dict(theta=150.0, height=3.0, links=140)


def load_base(src: str) -> dict:
    """The solve and line kernels of the tree at ``src``, under the package name
    ``lcpbench_base`` (empty package modules: only the kernels' own files run)."""
    from numba.core import config

    root = Path(src) / "lcpbench"
    for name, path in ((BASE, root), (f"{BASE}.model", root / "model"),
                       (f"{BASE}.linalg", root / "linalg")):
        pkg = types.ModuleType(name)
        pkg.__path__ = [str(path)]
        sys.modules[name] = pkg
    saved = config.CACHE_DIR
    config.CACHE_DIR = os.path.join(tempfile.gettempdir(), "lcpbench-faces-base-cache")
    try:
        return {"solve": importlib.import_module(f"{BASE}.model.compiled_kernel"),
                "line": importlib.import_module(f"{BASE}.model.batch_kernel")}
    finally:
        config.CACHE_DIR = saved


def this_tree() -> dict:
    return {"solve": numba_cache.kernel_module("lcpbench.model.compiled_kernel", "solve_chain"),
            "line": numba_cache.kernel_module("lcpbench.model.batch_kernel", "solve_line")}


def use(kernels: dict) -> None:
    """Route ``lcpbench.solve`` and ``solve_many`` through ``kernels``."""
    calls._KERNEL[:] = [kernels["solve"]]
    numba_cache._LOADED["lcpbench.model.batch_kernel"] = kernels["line"]


def kernel_call(module, chain, tol: float):
    args = kernel_args(chain)
    n = chain.free_nodes.size
    cold = (np.zeros(0), np.zeros(n), np.zeros(n, bool), np.zeros(n, bool), 0)
    return lambda: module.solve_chain(*args, tol, 200, *cold, 20 * n + 50, 1e-3, False)


def faces(module, chain, tol: float) -> tuple[list[int], int]:
    got = kernel_call(module, chain, tol)()
    assert got[0] == 0, f"kernel code {got[0]}"
    per_step = [int(x) for x in got[6][0, :got[7]]]
    return per_step, int(got[7])


def interleaved(contenders: dict, repeat: int, inner: int) -> dict:
    """Median seconds per call of each contender, ``inner`` calls per sample, the
    contenders in rotating order in every repetition (one warm-up round)."""
    names = list(contenders)
    times: dict = {k: [] for k in names}
    for r in range(repeat + 1):
        k = r % len(names)
        for name in names[k:] + names[:k]:
            fn = contenders[name]
            t0 = time.perf_counter()
            for _ in range(inner):
                fn()
            if r:
                times[name].append((time.perf_counter() - t0) / inner)
    return {k: (statistics.median(v), min(v)) for k, v in times.items()}


def measure(base_src: str, repeat: int) -> dict:
    kernels = {"base": load_base(base_src), "this": this_tree()}
    scene = ActuatorScene(**SCENE)
    chain = scene.chain()
    scenes = [ActuatorScene(theta=t, height=h) for h in PAPER_GRID.height for t in PAPER_GRID.theta]
    for s in scenes:
        s.chain()
    out: dict = {"load_start": os.getloadavg(),
                 "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}
    # path: faces per step on the scene, and over the grid (the contact scenes)
    for who, ks in kernels.items():
        out[f"steps_{who}"] = faces(ks["solve"], chain, 1e-3)[0]
        for tol in (1e-3, 1e-9):
            total = outer = 0
            for s in scenes:
                c = s.chain()
                if not compiled.direct(c):
                    continue
                per, o = faces(ks["solve"], c, tol)
                total, outer = total + sum(per), outer + o
            out[f"grid_{who}_{tol:g}"] = (total, outer)
    # answers: both kernels' forces agree (the tests compare them more strictly)
    F = {}
    for who, ks in kernels.items():
        use(ks)
        F[who] = lcpbench.solve(scene, tol=1e-3).total_force
        many = lcpbench.solve_many(scenes, tol=1e-3)
        out[f"many_outer_{who}"] = sum(r.outer_iterations for r in many)
        out[f"many_conv_{who}"] = all(r.converged for r in many)
    out["forces"] = F
    # timings
    k = {who: kernel_call(ks["solve"], chain, 1e-3) for who, ks in kernels.items()}
    out["kernel"] = interleaved({"base": k["base"], "this": k["this"]}, repeat, 20)

    def whole(who):
        def run():
            use(kernels[who])
            return lcpbench.solve(scene, tol=1e-3)
        return run

    def many(who):
        def run():
            use(kernels[who])
            return lcpbench.solve_many(scenes, tol=1e-3)
        return run

    out["solve"] = interleaved({"base": whole("base"), "this": whole("this")}, repeat, 20)
    out["many"] = interleaved({"base": many("base"), "this": many("this")}, repeat, 1)
    use(kernels["this"])
    out["load_end"] = os.getloadavg()
    return out


def markdown(res: dict, base_src: str) -> str:
    L = [f"Measured {res['date']}, one BLAS thread, JIT kernels of both trees; load average "
         f"{res['load_start'][0]:.2f} at the start, {res['load_end'][0]:.2f} at the end. "
         f"Base: `{base_src}`. Medians of interleaved samples (min beside).", "",
         "| what | base | this | base / this |", "|---|---|---|---|"]
    for key, label, unit, scale in (("kernel", "solve kernel alone (solve_chain), N = 140", "µs", 1e6),
                                    ("solve", "`lcpbench.solve`, N = 140", "µs", 1e6),
                                    ("many", "`solve_many`, 108 paper scenes", "ms", 1e3)):
        b, t = res[key]["base"], res[key]["this"]
        L.append(f"| {label} | {b[0] * scale:.1f} {unit} (min {b[1] * scale:.1f}) | "
                 f"{t[0] * scale:.1f} {unit} (min {t[1] * scale:.1f}) | {b[0] / t[0]:.2f}× |")
    mb, mt = res["many"]["base"][0], res["many"]["this"][0]
    L.append(f"| `solve_many` scenes per second | {108 / mb:.0f} | {108 / mt:.0f} | |")
    L += ["", "| face solves | base | this |", "|---|---|---|",
          f"| per outer step, N = 140, tol 1e-3 | {res['steps_base']} | {res['steps_this']} |"]
    for tol in ("0.001", "1e-09"):
        b, t = res[f"grid_base_{tol}"], res[f"grid_this_{tol}"]
        L.append(f"| paper grid (kernel-direct scenes), tol {tol}: faces / outer | "
                 f"{b[0]} / {b[1]} | {t[0]} / {t[1]} |")
    L.append(f"| `solve_many` 108 scenes: outer iterations (all converged) | "
             f"{res['many_outer_base']} ({res['many_conv_base']}) | "
             f"{res['many_outer_this']} ({res['many_conv_this']}) |")
    F = res["forces"]
    L += ["", f"Total force, N = 140: base {F['base']:.10f} N, this {F['this']:.10f} N."]
    return "\n".join(L) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="/work/main/src")
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    text = markdown(measure(a.base, a.repeat), a.base)
    print(text)
    if a.out:
        Path(a.out).write_text(text)


if __name__ == "__main__":
    main()
