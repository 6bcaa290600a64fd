"""Issue 6, targets 1-4: every speed ratio, measured in one run on one machine.

1. Full nonlinear solve at N = 140 (θ = 150°, h = 3 mm, tol 1e-3): the fastest
   back-end against the paper-faithful dense path (eqs. 3-31, A⁻¹, Lemke,
   undamped iteration: ``lcpbench.reference.dense.solve_paper_dense``).
2. The same solve against the paper's root-finding baseline (Appendix A,
   3N + 2 equations): analytic Jacobian with Powell's hybrid method, and the
   finite-difference Jacobian (as MATLAB's fsolve) with Levenberg-Marquardt
   (hybr does not converge with it at N = 140; that attempt is timed too).
3. One contact step at N = 140 (the converged configuration's, the LCP
   ``lcpbench export`` writes): the active set from cold (no contact set
   given) against Siconos's Lemke (C) on that LCP, both exact; solver-reported
   times (Siconos: inside its worker, around the C call only; the round trip
   through the bridge is reported beside it). Also the primal active set (the
   cold start before issue 6) and lcpbench's Lemke.
4. Full-solve time against N = 100 ... 3200 for the fast path, the dense paths
   and a few QP back-ends, with fitted log-log slopes; a series stops at the
   first N whose solve would take longer than ``--max-seconds`` (predicted
   from the last two sizes) and says so.

The machine is shared: every ratio is a ratio of medians over interleaved
repetitions (each repetition runs every contender once, in rotating order).
Writes ``results/perf.md``, ``results/perf.json`` and
``results/perf-scaling.png``.

    python benchmarks/perf.py [--quick] [--repeat 21] [--out results/perf]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
import gc
import importlib.metadata
import json
import math
import platform
import statistics
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.compiled_driver import run as run_driver
from lcpbench.model.step_solver import solve_step, step_lcp, step_residuals
from lcpbench.reference.dense import solve_paper_dense
from lcpbench.reference.root_finding import solve_baseline
from lcpbench.solvers import available_backends, get_backend, solve_lcp
from lcpbench.solvers.banded import solve_banded_qp

sys.path.insert(0, str(Path(__file__).resolve().parent))
from perf_report import BLOCK, FORCE_RTOL, full_markdown, markdown19  # noqa: I001

SCENE = dict(theta=150.0, height=3.0, links=140)
TOL = 1e-3
#: Back-ends tried for the fastest full solve (target 1), where installed.
FULL_SOLVE = ["active-set", "qpsolvers-piqp", "qpsolvers-daqp", "clarabel", "osqp",
              "proxsuite-sparse", "qpsolvers-quadprog", "siconos-lemke", "lemke"]
#: Series of the scaling plot (target 4): label -> how to solve a scene.
SCALING_QP = ["qpsolvers-piqp", "proxsuite-sparse", "qpsolvers-daqp", "clarabel"]
SIZES = [100, 200, 400, 800, 1600, 3200]


# -- measuring ----------------------------------------------------------------------
def interleaved(contenders: dict, repeat: int, warmup: int = 1, block: int = 1) -> dict:
    """Run every contender ``block`` times in a row per repetition, in rotating order.

    ``contenders`` maps a name to a callable returning ``(seconds, payload)``.
    Returns name -> {"times": [...], "payload": last payload}; warm-up rounds
    (imports, worker start-up, caches) are not recorded. As in :mod:`timeit`,
    the garbage collector is off during a timed call (it runs between calls;
    forcing a collection just before one would time a cold cache instead).
    """
    names = list(contenders)
    out = {name: {"times": [], "payload": None} for name in names}
    for r in range(warmup + repeat):
        k = r % len(names)
        for name in names[k:] + names[:k]:
            for _ in range(block):
                seconds, payload = no_gc(contenders[name])
                if r >= warmup:
                    out[name]["times"].append(seconds)
                    out[name]["payload"] = payload
    return out


def no_gc(fn):
    """fn() with the garbage collector off (as timeit does)."""
    was = gc.isenabled()
    gc.disable()
    try:
        return fn()
    finally:
        if was:
            gc.enable()


def wall(fn):
    """A contender timed around the call."""
    def run():
        t0 = time.perf_counter()
        res = fn()
        return time.perf_counter() - t0, res
    return run


def med(times) -> float:
    return float(statistics.median(times)) if times else math.nan


def machine() -> dict:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {}
    for dist in ("lcpbench", "numpy", "scipy", "qpsolvers", "piqp", "daqp", "proxsuite",
                 "clarabel", "osqp", "quadprog", "matplotlib"):
        try:
            versions[dist] = importlib.metadata.version(dist)
        except importlib.metadata.PackageNotFoundError:
            pass
    if "siconos-lemke" in available_backends():
        versions["siconos"] = get_backend("siconos-lemke").version()
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = os.cpu_count()
    return {
        "cpu": cpu, "nproc": affinity, "cpu_count": os.cpu_count(),
        "platform": platform.platform(), "python": platform.python_version(),
        "versions": versions, "load_average_start": list(os.getloadavg()),
        "date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
    }


# -- target 1 -----------------------------------------------------------------------
def target1(scene, repeat: int, reference: float) -> dict:
    names = [b for b in FULL_SOLVE if b in available_backends()]
    contenders = {"dense paper path (Lemke)": wall(lambda: solve_paper_dense(scene, tol=TOL))}
    for name in names:
        contenders[name] = wall(lambda name=name: lcpbench.solve(scene, solver=name, tol=TOL))
    runs = interleaved(contenders, repeat)
    rows = []
    for name, run in runs.items():
        res = run["payload"]
        if name.startswith("dense"):
            _, R, outer, ok = res
            force = float(np.sum(R))
        else:
            outer, ok, force = res.outer_iterations, res.converged, res.total_force
        err = abs(force - reference) / reference
        rows.append({"name": name, "median_s": med(run["times"]), "min_s": min(run["times"]),
                     "converged": bool(ok), "outer": int(outer), "force_N": force,
                     "force_error": err, "accurate": bool(ok and err <= FORCE_RTOL)})
    dense = rows[0]
    ok = [r for r in rows[1:] if r["accurate"]]
    fastest = min(ok, key=lambda r: r["median_s"])
    res = runs[fastest["name"]]["payload"]
    breakdown = {"steps_solver_s": float(sum(st.solve_time for st in res.steps)),
                 "steps_assembly_s": float(sum(st.assemble_time for st in res.steps)),
                 "face_solves": [int(st.iterations) for st in res.steps],
                 "engine": str(res.engine)}
    return {"rows": rows, "fastest": fastest["name"], "dense_s": dense["median_s"],
            "fastest_s": fastest["median_s"], "ratio": dense["median_s"] / fastest["median_s"],
            "repeat": repeat, "breakdown": breakdown}


# -- target 2 -----------------------------------------------------------------------
def target2(scene, fastest: str, repeat: int) -> dict:
    contenders = {
        "fast path": wall(lambda: lcpbench.solve(scene, solver=fastest, tol=TOL)),
        "baseline analytic (hybr)": wall(lambda: solve_baseline(scene, jacobian="analytic")),
        "baseline fd (lm)": wall(lambda: solve_baseline(scene, jacobian="fd", method="lm")),
    }
    runs = interleaved(contenders, repeat)
    # the fd Jacobian with hybr, as fsolve's default would try it: once, to show it fails
    t0 = time.perf_counter()
    hybr_fd = solve_baseline(scene, jacobian="fd")
    hybr_fd_s = time.perf_counter() - t0
    fast = med(runs["fast path"]["times"])
    rows = []
    for name, run in list(runs.items())[1:]:
        b = run["payload"]
        rows.append({"name": name, "median_s": med(run["times"]), "ratio": med(run["times"]) / fast,
                     "status": b.status, "converged": b.converged, "valid": b.valid,
                     "nfev": b.iterations, "njev": b.jacobian_evaluations,
                     "force_N": b.total_force, "solver_time_s": b.time_s})
    rows.append({"name": "baseline fd (hybr)", "median_s": hybr_fd_s, "ratio": hybr_fd_s / fast,
                 "status": hybr_fd.status, "converged": hybr_fd.converged,
                 "valid": hybr_fd.valid, "nfev": hybr_fd.iterations,
                 "njev": hybr_fd.jacobian_evaluations, "force_N": hybr_fd.total_force,
                 "solver_time_s": hybr_fd.time_s, "single_run": True})
    return {"fast": fastest, "fast_s": fast, "rows": rows, "repeat": repeat}


# -- target 3 and the cold active set -------------------------------------------------
def converged_step(scene):
    """The step at the converged configuration, and its exact answer (checked by Lemke)."""
    result = lcpbench.solve(scene, solver="active-set", tol=1e-10)
    step = assemble_step(result.scene.chain(), result.alpha)
    ref = solve_step(step, "active-set", "high")
    check = solve_step(step, "lemke", "high")
    assert ref.solved and check.solved
    rows = np.isfinite(step.upper)
    f_ref, f_chk = ref.forces_net[rows].sum(), check.forces_net[rows].sum()
    assert abs(f_ref - f_chk) <= 1e-9 * abs(f_ref), (f_ref, f_chk)
    return step, float(f_ref)


def target3(scene, repeat: int) -> dict:
    step, f_ref = converged_step(scene)
    form, M, q, dz, dw = step_lcp(step, scaled=True)  # what `lcpbench export` writes
    solved = solve_banded_qp(step)

    def step_solver(name, **kw):
        def run():
            sol = solve_step(step, name, "high", **kw)
            return sol.solve_time, sol
        return run

    def primal():
        sol = solve_banded_qp(step, method="primal")
        return sol.solve_time, sol

    round_trips: dict[str, list] = {}

    def lcp(name):
        def run():
            sol = solve_lcp(M, q, name, "high")
            if "wall_time" in sol.extra:  # the bridge's round trip
                round_trips.setdefault(name, []).append(sol.extra["wall_time"])
            return sol.solve_time, sol
        return run

    contenders = {
        "active-set (dual, cold)": step_solver("active-set"),
        "active-set (primal, cold; before)": primal,
        "active-set (warm: exact contact set)": step_solver("active-set", warm=solved),
        "lemke (lcpbench, Python)": lcp("lemke"),
    }
    have_siconos = "siconos-lemke" in available_backends()
    if have_siconos:
        contenders["siconos-lemke (C)"] = lcp("siconos-lemke")
    # strict: each call follows a call of another solver (cold caches); steady: blocks
    # of BLOCK calls in a row (warm caches, as when one solver runs a whole sweep)
    steady = interleaved(contenders, max(2, repeat // BLOCK), warmup=1, block=BLOCK)
    round_trips.clear()
    runs = interleaved(contenders, repeat, warmup=2)
    rows = []
    contact = np.isfinite(step.upper)
    for name, run in runs.items():
        sol = run["payload"]
        if hasattr(sol, "z"):  # an LCP answer: the gaps z, in units of l
            u = step.from_lcp(form, sol.z * dz)
            backend = "siconos-lemke" if name.startswith("siconos") else "lemke"
            bridge = med(round_trips.get(backend, []))
        else:
            u, bridge = sol.u, math.nan
        # every answer judged the same way: R = K g + z from its gaps, lcpbench's residual
        resid, R = step_residuals(step, u)
        force = float(R[contact].sum())
        rows.append({"name": name, "status": sol.status.value, "iterations": int(sol.iterations),
                     "median_s": med(run["times"]), "min_s": min(run["times"]),
                     "steady_median_s": med(steady[name]["times"]),
                     "round_trip_s": bridge, "force_error": abs(force - f_ref) / abs(f_ref),
                     "natural_residual": resid["natural"]})
    by = {r["name"]: r for r in rows}
    out = {"rows": rows, "force_N": f_ref, "contact_rows": int(form.n_gap), "repeat": repeat,
           "size": int(step.size)}
    if have_siconos:
        a, s = by["active-set (dual, cold)"], by["siconos-lemke (C)"]
        out["ratio"] = s["median_s"] / a["median_s"]
        out["ratio_steady"] = s["steady_median_s"] / a["steady_median_s"]
        out["ratio_round_trip"] = s["round_trip_s"] / a["median_s"]
    old = by["active-set (primal, cold; before)"]
    new = by["active-set (dual, cold)"]
    out["cold_before_after"] = {"before_changes": old["iterations"], "before_s": old["median_s"],
                                "after_solves": new["iterations"], "after_s": new["median_s"],
                                "speed_up": old["median_s"] / new["median_s"]}
    return out


def full_solve_before_after(scene, repeat: int) -> dict:
    """The N = 140 full solve with each active-set start: the driver and the steps only."""
    chain = scene.chain()

    def stepper(method):
        def solve(step, warm):
            kw = {} if warm is None else {"start": warm.u, "active_upper": warm.active_upper,
                                          "active_lower": warm.active_lower}
            return solve_banded_qp(step, method=method, **kw)
        return solve

    contenders = {m: wall(lambda m=m: run_driver(chain, stepper(m), tol=TOL))
                  for m in ("dual", "primal")}
    runs = interleaved(contenders, repeat)
    out = {}
    for m, run in runs.items():
        steps = run["payload"].steps
        out[m] = {"median_s": med(run["times"]), "outer": len(steps),
                  "face_solves": [s.iterations for s in steps]}
    out["speed_up"] = out["primal"]["median_s"] / out["dual"]["median_s"]
    return out


# -- target 4 -----------------------------------------------------------------------
def series_solvers() -> dict:
    """label -> callable(scene) returning (converged, force)."""
    def via(name):
        def run(scene):
            res = lcpbench.solve(scene, solver=name, tol=TOL)
            return res.converged, res.total_force
        return run

    def paper(scene):
        _, R, _, ok = solve_paper_dense(scene, tol=TOL)
        return ok, float(np.sum(R))

    out = {"fast path (active-set)": via("active-set"),
           "dense LCP + Lemke (lcpbench)": via("lemke"),
           "dense paper path (eqs. 3-31 + Lemke)": paper}
    if "siconos-lemke" in available_backends():
        out["dense LCP + Siconos Lemke"] = via("siconos-lemke")
    for name in SCALING_QP:
        if name in available_backends():
            out[name] = via(name)
    return out


def target4(sizes, repeat: int, max_seconds: float) -> dict:
    solvers = series_solvers()
    series = {label: {"N": [], "median_s": [], "converged": [], "force_N": [], "cut": None}
              for label in solvers}
    for N in sizes:
        scene = ActuatorScene(theta=SCENE["theta"], height=SCENE["height"], links=N)
        live = {}
        for label, fn in solvers.items():
            s = series[label]
            if s["cut"]:
                continue
            if len(s["N"]) >= 2:  # the local slope, plus a margin: costs steepen with N
                slope = max(math.log(s["median_s"][-1] / s["median_s"][-2])
                            / math.log(s["N"][-1] / s["N"][-2]), 1.0) + 0.5
                guess = s["median_s"][-1] * (N / s["N"][-1]) ** slope
                if guess > max_seconds:
                    s["cut"] = f"N = {N}: predicted {guess:.0f} s > {max_seconds:g} s per solve"
                    continue
            live[label] = fn
        if not live:
            break
        times = {label: [] for label in live}
        payload = {}
        for r in range(repeat + 1):  # round 0 is a warm-up, except for slow solves
            k = r % len(live)
            order = list(live)[k:] + list(live)[:k]
            for label in order:
                if r >= 2 and times[label] and times[label][0] > 2.0:
                    continue  # one or two timings of a solve of seconds are enough
                dt, payload[label] = no_gc(wall(lambda f=live[label], sc=scene: f(sc)))
                if r > 0 or dt > 2.0:
                    times[label].append(dt)
        for label in live:
            s = series[label]
            ok, force = payload[label]
            s["N"].append(N)
            s["median_s"].append(med(times[label]))
            s["converged"].append(bool(ok))
            s["force_N"].append(float(force))
            if med(times[label]) > max_seconds:
                s["cut"] = f"after N = {N}: {med(times[label]):.0f} s > {max_seconds:g} s"
        print(f"  N = {N}: " + ", ".join(f"{k} {series[k]['median_s'][-1]*1e3:.1f} ms"
                                         for k in live), file=sys.stderr, flush=True)
    for s in series.values():
        s["slope"] = fit_slope(s)
    return {"series": series, "sizes": list(sizes), "repeat": repeat, "max_seconds": max_seconds}


def fit_slope(s) -> float | None:
    pts = [(n, t) for n, t, ok in zip(s["N"], s["median_s"], s["converged"]) if ok]
    if len(pts) < 2:
        return None
    x = np.log([p[0] for p in pts])
    y = np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def plot(t4: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    for label, s in t4["series"].items():
        if not s["N"]:
            continue
        N = np.array(s["N"], float)
        t = np.array(s["median_s"])
        ok = np.array(s["converged"])
        slope = s["slope"]
        name = f"{label} (slope {slope:.2f})" if slope is not None else f"{label} (no fit)"
        line, = ax.plot(N[ok], t[ok], "o-", label=name)
        if (~ok).any():
            ax.plot(N[~ok], t[~ok], "o", mfc="none", color=line.get_color())
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("links N")
    ax.set_ylabel("full nonlinear solve (s), median")
    ax.set_title(f"θ = {SCENE['theta']:g}°, h = {SCENE['height']:g} mm, tol {TOL:g}; "
                 "hollow: did not converge", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: few repeats, small N")
    ap.add_argument("--repeat", type=int, default=None, help="repetitions (default 21; quick 3)")
    ap.add_argument("--max-seconds", type=float, default=30.0,
                    help="stop a scaling series beyond this time per solve")
    ap.add_argument("--out", default="results/perf", help="writes OUT.md, OUT.json, "
                    "OUT-scaling.png")
    ap.add_argument("--from-json", action="store_true",
                    help="measure nothing: rewrite OUT.md and the plot from OUT.json")
    ap.add_argument("--issue19-only", action="store_true",
                    help="only issue 19's targets (benchmarks/perf_targets.py)")
    ap.add_argument("--starts", type=int, default=5, help="fresh processes for start-up")
    ap.add_argument("--force", action="store_true", help="overwrite OUT.md, .json and "
                    "-scaling.png")
    args = ap.parse_args(argv)
    out = Path(args.out)
    if args.from_json:
        res = json.loads(out.with_suffix(".json").read_text())
        plot(res["t4"], out.parent / f"{out.name}-scaling.png")
        out.with_suffix(".md").write_text(full_markdown(res, res.get("command", "?")))
        print(f"rewrote {out.with_suffix('.md')} from {out.with_suffix('.json')}",
              file=sys.stderr)
        return 0
    refuse_overwrite([out.with_suffix(".md"), out.with_suffix(".json"),
                      out.parent / f"{out.name}-scaling.png"], args.force)
    repeat = args.repeat or (3 if args.quick else 21)
    sizes = [100, 200, 400] if args.quick else SIZES
    cmd = command_line("perf.py", argv)
    out.parent.mkdir(parents=True, exist_ok=True)

    res = {"machine": machine(), "command": cmd}
    import perf_targets
    from compiled_core import cold_step

    res["issue19"] = perf_targets.measure(interleaved, wall, med, repeat, args.starts, cold_step)
    if args.issue19_only:
        res["machine"]["load_average_end"] = list(os.getloadavg())
        out.with_suffix(".md").write_text(markdown19(res, cmd))
        out.with_suffix(".json").write_text(json.dumps(res, indent=1, default=float))
        print(f"wrote {out.with_suffix('.md')}, {out.with_suffix('.json')}", file=sys.stderr)
        return 0
    scene = ActuatorScene(**SCENE)
    res["reference_force"] = lcpbench.solve(scene, solver="active-set", tol=1e-10).total_force
    print("target 1: full solve, N = 140", file=sys.stderr, flush=True)
    res["t1"] = target1(scene, repeat, res["reference_force"])
    print(f"  dense / {res['t1']['fastest']}: {res['t1']['ratio']:.1f}x", file=sys.stderr)
    print("target 2: root-finding baseline", file=sys.stderr, flush=True)
    res["t2"] = target2(scene, res["t1"]["fastest"], 1 if args.quick else max(3, repeat // 3))
    for r in res["t2"]["rows"]:
        print(f"  {r['name']} / fast path: {r['ratio']:.3g}x ({r['status']})", file=sys.stderr)
    print("target 3: one contact step, N = 140", file=sys.stderr, flush=True)
    res["t3"] = target3(scene, max(repeat, 5) * (2 if not args.quick else 1))
    if "ratio" in res["t3"]:
        print(f"  siconos-lemke / active-set (cold): {res['t3']['ratio']:.1f}x", file=sys.stderr)
    res["full_before_after"] = full_solve_before_after(scene, repeat)
    print("target 4: scaling", file=sys.stderr, flush=True)
    res["t4"] = target4(sizes, 2 if args.quick else 5, args.max_seconds)
    for label, s in res["t4"]["series"].items():
        slope = f"{s['slope']:.2f}" if s["slope"] is not None else "-"
        print(f"  slope {slope:>5}  {label}" + (f"  (cut {s['cut']})" if s["cut"] else ""),
              file=sys.stderr)
    res["machine"]["load_average_end"] = list(os.getloadavg())

    png = out.parent / f"{out.name}-scaling.png"
    plot(res["t4"], png)
    out.with_suffix(".md").write_text(full_markdown(res, cmd))
    out.with_suffix(".json").write_text(json.dumps(res, indent=1, default=float))
    print(f"wrote {out.with_suffix('.md')}, {out.with_suffix('.json')}, {png}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
