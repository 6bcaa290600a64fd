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
                  "engine": r.extra.get("engine", ""), "outer": r.outer_iterations,
                  "force_error_bound": r.judgement.force_error_bound if r.judgement else None,
                  "node_error_bound": r.judgement.node_error_bound if r.judgement else None}))
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
    rows = []
    for n in a.sizes.split(","):
        rows.append(run_one(int(n), a.tol, a.timeout))
        print(json.dumps(rows[-1]), flush=True)
    load_after = os.getloadavg()
    with open(a.out + ".json", "w") as fh:
        json.dump({"load": load, "load_after": load_after, "rows": rows}, fh, indent=1)
    write_report(a.out, rows, a.tol, load, load_after)
    return 0


def _slope(xs, ys):
    import numpy as np

    if len(xs) < 2:
        return float("nan")
    return float(np.polyfit(np.log(xs), np.log(ys), 1)[0])


def write_report(out: str, rows: list[dict], tol: float, load, load_after) -> None:
    from lcpbench.bench.machine import cpu_model

    ok = [r for r in rows if "error" not in r]
    big = [r for r in ok if r["N"] >= 4000]
    lines = [f"# Large N (issue 19, target 5): θ = 150°, h = 3 mm, tol = {tol:g} rad", "",
             "`python benchmarks/large_n.py` (one subprocess per N, one BLAS thread; kernels "
             "loaded before the clock). Load average before "
             f"{load[0]:.2f}, after {load_after[0]:.2f}; {cpu_model()}, {os.cpu_count()} "
             "cores.", "",
             "| N | engine | driver (s) | solve + judge (s) | peak RSS (MiB) | F (N) | outer | "
             "converged | judge |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['N']} | | | | | | | | {r['error']} |")
            continue
        eng = "compiled" if r["engine"] == "compiled" else "increments"
        why = "" if r["converged"] else r["reason"].replace("|", "/")[:160]
        lines.append(f"| {r['N']} | {eng} | {r['driver_s']:.3f} | {r['total_s']:.3f} | "
                     f"{r['rss_mib']:.0f} | {r['force']:.10f} | {r['outer']} | "
                     f"{r['converged']} | {why} |")
    if len(big) >= 2:
        lines += ["", f"Log-log slope of the driver time over the increment path "
                      f"(N = {big[0]['N']}…{big[-1]['N']}): "
                      f"{_slope([r['N'] for r in big], [r['driver_s'] for r in big]):.2f}; "
                      f"of the peak RSS: {_slope([r['N'] for r in big], [r['rss_mib'] for r in big]):.2f}."]
    with open(out + ".md", "w") as fh:
        fh.write("\n".join(lines) + "\n")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.loglog([r["N"] for r in ok], [r["driver_s"] for r in ok], "o-", label="driver (s)")
    ax.loglog([r["N"] for r in ok], [r["total_s"] for r in ok], "s--", label="solve + judge (s)")
    ax.set_xlabel("links N")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out + ".png", dpi=120)


if __name__ == "__main__":
    sys.exit(main())
