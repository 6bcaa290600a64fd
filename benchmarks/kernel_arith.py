"""Issue 19, targets 1-2: the solve kernel's own arithmetic, an older kernel against this one.

The solve kernel (``compiled_kernel.solve_chain``, without the Python around it)
of a git revision (``--ref``, default ``main``: its ``model/compiled_kernel.py``
and ``model/compiled_dual.py``, and what they import: the walk's ``solvers/dual_kernel.py``, ``model/chain_kernel.py``,
``thresholds.py``, the linalg kernels; copied into a package of their own with its
own numba cache) against the working tree's, on
the same chain arguments, interleaved in one process: CPU time per solve, one
BLAS thread, the load average recorded at the start and the end. Reported: the
median of each, their ratio, the face solves per solve (the records' first row)
and the difference of the total force.

    python benchmarks/kernel_arith.py [--ref main] [--repeat 41] [--block 10]
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import hashlib  # noqa: E402
import importlib  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from lcpbench import ActuatorScene  # noqa: E402
from lcpbench.model.kernel_call import kernel_args, solve_kernel, warm_args  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
PKG = "src/lcpbench"
FILES = {"model": ["compiled_kernel.py", "compiled_dual.py", "chain_kernel.py",
                   "profile_kernel.py", "wall_kernel.py"],
         "solvers": ["dual_kernel.py"],
         "linalg": ["ldl_kernel.py", "wide_face_kernel.py", "walk_key.py", "walk_picks.py"],
         "": ["thresholds.py"]}  # where the ref has them (the walk: solvers/ from 2026-12-05)
SCENES = {"paper N=140 θ=150° h=3": dict(theta=150.0, height=3.0, links=140),
          "channel N=140 θ=160° h=2": dict(theta=160.0, height=2.0, links=140, channel=True),
          "N=400 θ=150° h=3": dict(theta=150.0, height=3.0, links=400)}
TOL = 1e-3


def old_kernel(ref: str):
    """The solve kernel of ``ref``, imported as a package of its own (``_kernel_<sha>``)."""
    sha = subprocess.run(["git", "rev-parse", ref], cwd=ROOT, check=True, capture_output=True,
                         text=True).stdout.strip()
    name = f"_kernel_{sha[:12]}"
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "lcpbench-arith"
    pkg = base / name
    if not (pkg / "done").exists():
        for sub, files in FILES.items():
            (pkg / sub).mkdir(parents=True, exist_ok=True)
            (pkg / sub / "__init__.py").write_text("")
            for f in files:
                where = "/".join(x for x in (PKG, sub, f) if x)
                got = subprocess.run(["git", "show", f"{sha}:{where}"], cwd=ROOT,
                                     capture_output=True)
                if got.returncode == 0:
                    (pkg / sub / f).write_bytes(got.stdout)
        (pkg / "__init__.py").write_text("")
        (pkg / "done").write_text(sha)
    sys.path.insert(0, str(base))
    return importlib.import_module(f"{name}.model.compiled_kernel"), sha


def call(k, args, n, tol=TOL):
    s_alpha, w_u, w_up, w_lo, flags = warm_args(None, n)
    return k.solve_chain(*args, tol, 200, s_alpha, w_u, w_up, w_lo, flags, 20 * n + 50, 1e-9,
                         False)


def measure(kernels: dict, scene: dict, repeat: int, block: int) -> dict:
    chain = ActuatorScene(**scene).chain()
    args, n = kernel_args(chain), chain.free_nodes.size
    times: dict = {name: [] for name in kernels}
    out = {}
    for name, k in kernels.items():
        res = call(k, args, n)
        rec, count = res[6], res[7]
        out[name] = {"code": int(res[0]), "outer": int(count),
                     "faces": [int(x) for x in rec[0, :count]],
                     "force": float(res[9].sum())}
    names = list(kernels)
    for r in range(repeat + 1):
        for name in (names if r % 2 == 0 else names[::-1]):
            k = kernels[name]
            t0 = time.process_time_ns()
            for _ in range(block):
                call(k, args, n)
            if r:
                times[name].append((time.process_time_ns() - t0) / block / 1e3)
    for name in names:
        out[name]["median_us"] = statistics.median(times[name])
        out[name]["min_us"] = min(times[name])
    ratios = [a / b for a, b in zip(times[names[0]], times[names[1]], strict=True)]
    return {"rows": out, "ratio": statistics.median(ratios)}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ref", default="main")
    p.add_argument("--repeat", type=int, default=41)
    p.add_argument("--block", type=int, default=10)
    args = p.parse_args(argv)
    old, sha = old_kernel(args.ref)
    kernels = {f"{args.ref} ({sha[:7]})": old, "this tree": solve_kernel()}
    print(f"load average at start: {os.getloadavg()}; CPU time per solve (µs), "
          f"{args.repeat} interleaved blocks of {args.block}, tol {TOL:g}")
    for label, scene in SCENES.items():
        res = measure(kernels, scene, args.repeat, args.block)
        print(f"\n{label}: ratio old / new (median of the blocks' ratios) {res['ratio']:.3f}")
        forces = [r["force"] for r in res["rows"].values()]
        for name, r in res["rows"].items():
            print(f"  {name:<20} median {r['median_us']:8.1f}  min {r['min_us']:8.1f}  "
                  f"code {r['code']}  outer {r['outer']}  faces {r['faces']} "
                  f"(total {sum(r['faces'])})  F = {r['force']:.12g} N")
        print(f"  |ΔF| / F = {abs(forces[0] - forces[1]) / abs(forces[0]):.1e}")
    print(f"\nload average at end: {os.getloadavg()}")
    digest = hashlib.sha256(Path(solve_kernel().__file__).read_bytes()).hexdigest()[:8]
    print(f"this tree's compiled_kernel.py sha256 {digest}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
