"""Large N (issue 19, item 3 / target 5): time, peak RSS and force against N.

Each N is solved in a fresh subprocess (one BLAS thread) at the paper's scene
(θ = 150°, h = 3 mm), so the peak RSS (``resource.getrusage``) is that solve's
own. The kernels are compiled/loaded once per process before the clock starts
(a tiny solve). Writes ``results/large-n.md`` and ``results/large-n.png``;
``--out`` to write elsewhere.

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/large_n.py
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

CHILD = r"""
import json, resource, sys, time
import lcpbench
from lcpbench.problems.scenes import ActuatorScene
N, tol = int(sys.argv[1]), float(sys.argv[2])
lcpbench.solve(ActuatorScene(150, 3.0, links=5000), tol=1e-3)  # load the kernels
lcpbench.solve(ActuatorScene(150, 3.0, links=140), tol=1e-3)
t0 = time.perf_counter()
r = lcpbench.solve(ActuatorScene(150, 3.0, links=N), tol=tol)
total = time.perf_counter() - t0
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # MiB (Linux: KiB)
print(json.dumps({"N": N, "tol": tol, "driver_s": r.time_s, "total_s": total, "rss_mib": rss,
                  "force": r.total_force, "converged": r.converged, "reason": r.reason[:300],
                  "engine": r.extra.get("engine", ""), "outer": r.iterations}))
"""


def run_one(n: int, tol: float, timeout: float) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-c", CHILD, str(n), str(tol)], env=env,
                           capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"N": n, "tol": tol, "error": f"timeout after {timeout:.0f} s"}
    if p.returncode != 0:
        return {"N": n, "tol": tol, "error": p.stderr.strip().splitlines()[-1][:200]}
    out = json.loads(p.stdout.strip().splitlines()[-1])
    out["wall_s"] = time.perf_counter() - t0
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1000,3000,10000,30000,100000")
    ap.add_argument("--tol", type=float, default=1e-3)
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--out", default="results/large-n")
    a = ap.parse_args(argv)
    load = os.getloadavg()
    rows = [run_one(int(n), a.tol, a.timeout) for n in a.sizes.split(",")]
    for r in rows:
        print(json.dumps(r), flush=True)
    with open(a.out + ".json", "w") as fh:
        json.dump({"load": load, "rows": rows}, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
