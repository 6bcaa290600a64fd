"""Issue 19, items 1 and 5: the compiled solve core against the dense paper path.

Measured in one run, with one BLAS thread, the load average recorded at the
start and the end:

1. Full solve at N = 140, θ = 150°, h = 3 mm, tol 1e-3 (interleaved medians):
   ``lcpbench.solve(scene)`` (the compiled kernel), the paper-faithful dense path with
   Lemke (``solve_paper_dense``), and the kernel alone (``run_compiled``, no
   result, certificate or audit around it).
2. One cold contact step at the converged configuration: the kernel's step
   (assembly, dual walk, refinement, step certificate, judge residual; timed
   around the call), the active-set back-end's own call (``solve_banded_qp``: the same
   compiled walk with Python around it; solver-reported, without assembly),
   and Siconos's Lemke (C) on the step's LCP where installed (solver-reported).
3. Start-up, each in fresh processes (median of ``--starts``): ``import
   lcpbench`` (and whether it loaded numba), and the first solve of a process
   with numba's cache warm (the cache is warmed by one process first).

    python benchmarks/compiled_core.py [--repeat 31] [--starts 5] [--out results/compiled-core.md]
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from perf import interleaved, machine, med, wall  # noqa: E402

import lcpbench  # noqa: E402
from lcpbench.model.compiled_driver import assemble_step  # noqa: E402
from lcpbench.model.kernel_call import run_compiled, solve_kernel  # noqa: E402
from lcpbench.model.step_solver import step_lcp  # noqa: E402
from lcpbench.reference.dense import solve_paper_dense  # noqa: E402
from lcpbench.solvers import available_backends, solve_lcp  # noqa: E402

SCENE = dict(theta=150.0, height=3.0, links=140)
TOL = 1e-3


def full_solve(scene, repeat: int) -> dict:
    chain = scene.chain()
    runs = interleaved({
        "compiled (lcpbench.solve)": wall(lambda: lcpbench.solve(scene, tol=TOL)),
        "dense paper path (Lemke)": wall(lambda: solve_paper_dense(scene, tol=TOL)),
        "kernel alone (run_compiled)": wall(lambda: run_compiled(chain, tol=TOL)),
    }, repeat)
    rows = {}
    for name, run in runs.items():
        res = run["payload"]
        if name.startswith("dense"):
            _, R, outer, ok = res
            force = float(np.sum(R))
        elif name.startswith("kernel"):
            out = res[0]
            outer, ok, force = len(out.steps), out.converged, float(out.forces_upper.sum())
        else:
            outer, ok, force = res.outer_iterations, res.converged, res.total_force
        rows[name] = {"median_s": med(run["times"]), "min_s": min(run["times"]),
                      "outer": int(outer), "converged": bool(ok), "force_N": force}
    c = rows["compiled (lcpbench.solve)"]["median_s"]
    return {"rows": rows, "repeat": repeat,
            "vs_dense": rows["dense paper path (Lemke)"]["median_s"] / c}


def cold_step(scene, repeat: int) -> dict:
    res = lcpbench.solve(scene, tol=1e-10)
    chain = scene.chain()
    step = assemble_step(chain, res.alpha)
    k = solve_kernel()
    n = chain.free_nodes.size
    args = (np.ascontiguousarray(res.alpha), chain.link_length,
            np.ascontiguousarray(chain.joint_links[:, 0]),
            np.ascontiguousarray(chain.joint_links[:, 1]), chain.joint_stiffness,
            chain.rest_joint, int(chain.free_nodes[0]) + 1, n, chain.nodal_load, chain.lower,
            chain.upper, float(chain.length), float(chain.force_scale), np.zeros(0),
            np.zeros(0), np.zeros(n),
            np.zeros(n, bool), np.zeros(n, bool), 0, 20 * n + 50, 1e-6)
    form, M, q, _, _ = step_lcp(step, scaled=True)

    def backend_step():  # the back-end's own call (solve_step's default is the kernel's)
        from lcpbench.solvers.banded import solve_banded_qp

        sol = solve_banded_qp(step)
        return sol.solve_time, sol

    contenders = {"compiled step (assembly + walk + certificate + judge)":
                  wall(lambda: k.contact_step(*args)),
                  "active-set back-end call (solver-reported, no assembly)": backend_step}
    if "siconos-lemke" in available_backends():
        def siconos():
            sol = solve_lcp(M, q, "siconos-lemke", "high")
            return sol.solve_time, sol
        contenders["siconos-lemke (C, solver-reported)"] = siconos
    runs = interleaved(contenders, repeat, warmup=2)
    rows = {name: {"median_s": med(r["times"]), "min_s": min(r["times"])}
            for name, r in runs.items()}
    code = runs["compiled step (assembly + walk + certificate + judge)"]["payload"][0]
    return {"rows": rows, "kernel_code": int(code), "repeat": repeat}


def _fresh(code: str) -> list[str]:
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True, env=dict(os.environ)).stdout.split()


def start_up(starts: int) -> dict:
    imp = ("import time, sys; t = time.perf_counter(); import lcpbench; "
           "print(time.perf_counter() - t, 'numba' in sys.modules)")
    first = ("import time; t0 = time.perf_counter(); import lcpbench; "
             "s = lcpbench.ActuatorScene(theta=150, height=3.0); t = time.perf_counter(); "
             "r = lcpbench.solve(s); t1 = time.perf_counter(); lcpbench.solve(s); "
             "t2 = time.perf_counter(); print(t1 - t, t2 - t1, t1 - t0, r.engine)")
    _fresh(first)  # warms numba's on-disk cache
    imports, numba_loaded, firsts, seconds, totals, engines = [], [], [], [], [], set()
    for _ in range(starts):
        a, b = _fresh(imp)
        imports.append(float(a))
        numba_loaded.append(b == "True")
        f, s, tot, eng = _fresh(first)
        firsts.append(float(f))
        seconds.append(float(s))
        totals.append(float(tot))
        engines.add(eng)
    return {"import_s": statistics.median(imports), "import_loads_numba": any(numba_loaded),
            "first_solve_s": statistics.median(firsts),
            "second_solve_s": statistics.median(seconds),
            "import_plus_first_s": statistics.median(totals), "engines": sorted(engines),
            "starts": starts}


def markdown(res: dict, cmd: str) -> str:
    m, f, c, s = res["machine"], res["full"], res["cold"], res["start"]
    ms = lambda x: f"{x * 1e3:.3f}"  # noqa: E731
    lines = [
        "# The compiled solve core (issue 19, items 1 and 5)", "",
        f"Made by `{cmd}` on {m['date']}: {m['cpu']}, {m['nproc']} cores, one BLAS thread; "
        f"load average {m['load_average_start'][0]:.2f} at the start, "
        f"{res['load_average_end'][0]:.2f} at the end (a shared machine: times are "
        "medians of interleaved repetitions, the ratios are what compares).", "",
        f"## Full solve, N = 140, θ = 150°, h = 3 mm, tol {TOL:g} ({f['repeat']} repetitions)",
        "", "| path | median (ms) | min (ms) | outer | converged | F (N) |",
        "|---|---|---|---|---|---|"]
    for name, r in f["rows"].items():
        lines.append(f"| {name} | {ms(r['median_s'])} | {ms(r['min_s'])} | {r['outer']} | "
                     f"{r['converged']} | {r['force_N']:.10g} |")
    lines += ["", f"- compiled against the dense paper path (Lemke): **{f['vs_dense']:.0f}×** "
              "(target ≥ 150×)", "",
              f"## One cold contact step at the converged configuration ({c['repeat']} "
              "repetitions)", "", "| contender | median (µs) | min (µs) |", "|---|---|---|"]
    for name, r in c["rows"].items():
        lines.append(f"| {name} | {r['median_s'] * 1e6:.1f} | {r['min_s'] * 1e6:.1f} |")
    lines += ["", f"## Start-up (fresh processes, median of {s['starts']})", "",
              f"- `import lcpbench`: {ms(s['import_s'])} ms; loads numba: "
              f"{s['import_loads_numba']} (target ≤ 300 ms)",
              f"- first solve of a process, numba cache warm: {ms(s['first_solve_s'])} ms "
              f"(import + first solve {ms(s['import_plus_first_s'])} ms; target ≤ 500 ms)",
              f"- second solve of that process: {ms(s['second_solve_s'])} ms",
              f"- engine that ran: {', '.join(s['engines'])}", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=31)
    ap.add_argument("--starts", type=int, default=5)
    ap.add_argument("--out", default="results/compiled-core.md")
    args = ap.parse_args(argv)
    scene = lcpbench.ActuatorScene(**SCENE)
    res = {"machine": machine()}
    res["start"] = start_up(args.starts)
    res["full"] = full_solve(scene, args.repeat)
    res["cold"] = cold_step(scene, args.repeat)
    res["load_average_end"] = list(os.getloadavg())
    cmd = "python benchmarks/compiled_core.py " + " ".join(argv if argv is not None
                                                           else sys.argv[1:])
    text = markdown(res, cmd.strip())
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)
    out.with_suffix(".json").write_text(json.dumps(res, indent=1, default=str))
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
