"""Issue 19, targets 1 and 2: what the interleaved protocol charges a 0.1 ms solve.

In ``benchmarks/perf.py`` every repetition runs the contenders in turn, so the
default solve (N = 140, θ = 150°, h = 3 mm, tol 1e-3) always starts right after
30 ms to 0.8 s of another contender, and takes about twice its back-to-back time.
This script finds out what that penalty depends on. Before each timed solve it runs
one of these, interleaved (each round runs every condition once, in rotating order):

- nothing (back to back: the warm time);
- a busy loop of Python for 0.1, 1, 10, 30 and 100 ms (no memory touched, no
  library code); a sleep of 30 ms;
- a read of 64 MB (every cache level evicted by data);
- the dense paper path of target 1 (what ``perf.py`` runs before the solve);
- the dense path followed by a solve at N = 12 (the same code on a few hundred
  bytes of data: the code warmed, this scene's data not);
- the dense path followed by a read of the arrays the kernels take (the data
  warmed, the code not);
- the dense path followed by a read of the AOT library's code and read-only data
  as data, one byte per 64-byte line (where the AOT kernels are loaded).

It also times the solve kernel and the judge kernel alone, whole solves at N = 12
and N = 140, and the N = 140 solve with its kernels replayed (its Python alone,
``python_overhead.py``'s replay), after a 100 ms busy loop and right after
themselves. Medians and minima in µs, one BLAS thread, the load average recorded.
Writes ``results/cold-penalty.md`` and ``.json``; refuses to overwrite them without
``--force``. The causes named in the Markdown are inferred from these timings: no
hardware counters are read.

    python benchmarks/cold_penalty.py [--repeat 31] [--out results/cold-penalty] [--force]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import ctypes
import json
import statistics
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import refuse_overwrite, timing_note, timing_start
from lcpbench.reference.dense import solve_paper_dense

sys.path.insert(0, str(Path(__file__).resolve().parent))  # python_overhead's replay

SCENE = dict(theta=150.0, height=3.0, links=140)
TOL = 1e-3


def busy(seconds: float) -> None:
    """Python's own loop: no memory beyond a few objects, no library code."""
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        pass


def aot_pages() -> list[np.ndarray]:
    """The AOT library's mapped code and read-only data, as byte arrays (none where
    the kernels run through numba's JIT, or where /proc/self/maps is not there)."""
    views = []
    try:
        with open("/proc/self/maps") as maps:
            lines = maps.read().splitlines()
    except OSError:  # not Linux: the condition is left out
        return views
    for line in lines:
        part = line.split()
        if len(part) >= 6 and "lcpbench_aot" in part[5] and part[1].startswith("r") \
                and "w" not in part[1]:
            lo, hi = (int(x, 16) for x in part[0].split("-"))
            views.append(np.ctypeslib.as_array((ctypes.c_uint8 * (hi - lo)).from_address(lo)))
    return views


def conditions(scene, small, kernel_data, aot) -> dict:
    """Name -> what runs before the timed solve."""
    big = np.ones(8 * 1024 * 1024)  # 64 MB

    def dense():
        solve_paper_dense(scene, tol=TOL)

    out = {"nothing (back to back)": lambda: None}
    for ms in (0.1, 1, 10, 30, 100):
        out[f"busy loop {ms:g} ms"] = lambda s=ms / 1e3: busy(s)
    out.update({
        "sleep 30 ms": lambda: time.sleep(0.03),
        "read 64 MB": lambda: float(big.sum()),
        "dense paper path (target 1's contender)": dense,
        "dense paper path, then a solve at N = 12": lambda: (
            dense(), lcpbench.solve(small, tol=TOL)),
        "dense paper path, then the kernels' arrays read": lambda: (
            dense(), [float(np.sum(a)) for a in kernel_data]),
    })
    if aot:
        out["dense paper path, then the AOT library read (1 byte per line)"] = lambda: (
            dense(), [int(v[::64].sum()) for v in aot])
    return out


def timed_solves(scene, before: dict, repeat: int) -> dict:
    """Each condition, then one timed solve, interleaved by perf.py's
    :func:`interleaved` (rotating order, one warm-up round, the collector off)."""
    from perf import interleaved

    def after(condition):
        def run():
            condition()
            t0 = time.perf_counter()
            lcpbench.solve(scene, tol=TOL)
            return time.perf_counter() - t0, None
        return run

    runs = interleaved({name: after(c) for name, c in before.items()}, repeat, warmup=1)
    return {name: r["times"] for name, r in runs.items()}


def _replayed_solve(scene):
    """``lcpbench.solve`` of the scene with the two kernels replayed
    (``python_overhead._Replay``: their recorded outputs handed back at once), so that
    only its Python runs (and the four assignments that put the replays in and the
    kernels back after each call). A replayed run must give the recorded force."""
    from python_overhead import _kernels, _Replay

    solve_k, judge_k, _ = _kernels()
    reps = [_Replay(solve_k, "solve_chain"), _Replay(judge_k, "judge_answer")]

    def run():
        try:
            for r in reps:
                r.next = 0 if r.calls else None  # None: the first call records
                setattr(r.module, r.name, r)
            return lcpbench.solve(scene, tol=TOL)
        finally:
            for r in reps:
                setattr(r.module, r.name, r.real)

    recorded = run().total_force

    def checked():
        got = run()
        if got.total_force != recorded:
            raise RuntimeError("the replayed solve left the recorded path")
        return got
    return checked


def kernel_parts(scene, small, repeat: int) -> dict:
    """The solve kernel and the judge kernel alone, and whole solves at N = 12 and 140:
    after a 100 ms busy loop, then right after themselves."""
    from lcpbench.model.judge import _kernel as judge_kernel
    from lcpbench.model.judge import chain_args
    from lcpbench.model.kernel_call import cold_start, kernel_args, kernel_settings, solve_kernel

    chain = scene.chain()
    args = kernel_args(chain)
    jargs = chain_args(chain, args)
    n = chain.free_nodes.size
    k, jk = solve_kernel(), judge_kernel()
    max_iter, request, _ = kernel_settings("default", n)

    def solve_kernel():  # the call of lcpbench.solve (kernel_call.call_kernel, cold start)
        return k.solve_chain(*args, TOL, 200, *cold_start(n), max_iter, request, False)

    got = solve_kernel()
    alpha, rec, count, R = got[1], got[6], got[7], got[9]
    sizes = rec[2, :count].copy()
    zero = np.zeros(R.size)

    def judge():
        return jk.judge_answer(alpha, *jargs, R.copy(), zero, TOL, sizes)

    fns = {"solve kernel (solve_chain)": solve_kernel, "judge kernel (judge_answer)": judge,
           "lcpbench.solve at N = 12": lambda: lcpbench.solve(small, tol=TOL),
           "lcpbench.solve at N = 140": lambda: lcpbench.solve(scene, tol=TOL),
           "lcpbench.solve at N = 140, the kernels replayed (its Python alone)":
               _replayed_solve(scene)}
    times = {f"{name}, {when}": [] for name in fns for when in ("back to back", "after 100 ms")}
    for _ in range(repeat):
        for name, fn in fns.items():
            for when in ("after 100 ms", "back to back"):  # the second call: warm again
                if when == "after 100 ms":
                    busy(0.1)
                t0 = time.perf_counter()
                fn()
                times[f"{name}, {when}"].append(time.perf_counter() - t0)
    return times, [a for a in (*args, *jargs) if isinstance(a, np.ndarray)]


def summary(times: dict) -> dict:
    return {name: {"median_us": statistics.median(t) * 1e6, "min_us": min(t) * 1e6}
            for name, t in times.items()}


def _reading(solves: dict, parts: dict) -> str:
    """What the table says, in numbers: the penalty after each busy loop, a sleep, a read
    and the dense path, and the share of the dense path's that each warm-up takes away."""
    med = {name: s["median_us"] for name, s in solves.items()}
    base = med["nothing (back to back)"]

    def share(cold: str, warmed: str) -> str:
        penalty = med[cold] - base
        if penalty <= 0:
            return "n/a (no penalty to take away)"
        return f"{100 * (med[cold] - med[warmed]) / penalty:.0f} %"

    dense = "dense paper path (target 1's contender)"
    after = {ms: med[f"busy loop {ms:g} ms"] - base for ms in (1, 10, 30, 100)}
    small = share(dense, "dense paper path, then a solve at N = 12")
    arrays = share(dense, "dense paper path, then the kernels' arrays read")
    text = ("Reading: the penalty (median over back to back) is "
            + ", ".join(f"{round(v):d} µs after a {ms:g} ms busy loop" for ms, v in after.items())
            + f", {med['sleep 30 ms'] - base:.0f} µs after a 30 ms sleep, "
            f"{med['read 64 MB'] - base:.0f} µs after reading 64 MB and "
            f"{med[dense] - base:.0f} µs after the dense path. Of the dense path's, a solve "
            f"at N = 12 just before takes away {small}, reading the kernels' arrays {arrays}")
    aot = "dense paper path, then the AOT library read (1 byte per line)"
    if aot in med:
        text += f", reading the AOT library's bytes {share(dense, aot)}"
    size = {n: parts[f"lcpbench.solve at N = {n}, after 100 ms"]["median_us"]
            - parts[f"lcpbench.solve at N = {n}, back to back"]["median_us"] for n in (12, 140)}
    return text + (f". After 100 ms, the solve at N = 12 pays {size[12]:.0f} µs more than back "
                   f"to back and the solve at N = 140 {size[140]:.0f} µs (below). See "
                   "docs/performance.md for what this says about targets 1 and 2.")


def markdown(res: dict) -> str:
    solves, parts = res["solves"], res["parts"]
    base = solves["nothing (back to back)"]["median_us"]
    lines = [
        "# The cold-start penalty of one solve (issue 19, targets 1 and 2)", "",
        f"Measured {res['when']} on {res['machine']} Command: `{res['command']}`.", "",
        f"`lcpbench.solve` of the paper scene (N = 140, θ = 150°, h = 3 mm, tol 1e-3), "
        f"timed right after each condition; {res['repeat']} interleaved rounds "
        f"(every condition once per round, in rotating order). AOT kernels loaded: "
        f"{res['aot']}.", "",
        "| before the solve | median (µs) | min (µs) | median / back to back |",
        "|---|---|---|---|"]
    for name, s in solves.items():
        lines.append(f"| {name} | {s['median_us']:.1f} | {s['min_us']:.1f} | "
                     f"{s['median_us'] / base:.2f} |")
    lines += ["", "The kernels alone, and whole solves at N = 12 and N = 140 (each call "
              "after a 100 ms busy loop, then right after itself):", "",
              "| call | median (µs) | min (µs) |", "|---|---|---|"]
    for name, s in parts.items():
        lines.append(f"| {name} | {s['median_us']:.1f} | {s['min_us']:.1f} |")
    lines += ["", _reading(solves, parts), ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=31)
    ap.add_argument("--out", default="results/cold-penalty")
    ap.add_argument("--force", action="store_true", help="overwrite committed results")
    args = ap.parse_args(argv)
    if args.repeat < 3:
        ap.error("--repeat must be >= 3")
    out = Path(args.out)
    refuse_overwrite([out.with_suffix(".md"), out.with_suffix(".json")], args.force)
    start = timing_start()
    scene = ActuatorScene(**SCENE)
    small = ActuatorScene(theta=150.0, height=3.0, links=12)
    for _ in range(5):
        lcpbench.solve(scene, tol=TOL)
        lcpbench.solve(small, tol=TOL)
    part_times, kernel_data = kernel_parts(scene, small, args.repeat)
    aot = aot_pages()
    times = timed_solves(scene, conditions(scene, small, kernel_data, aot), args.repeat)
    res = {"when": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
           "command": "python benchmarks/cold_penalty.py " + " ".join(argv or sys.argv[1:]),
           "repeat": args.repeat, "aot": bool(aot), "solves": summary(times),
           "parts": summary(part_times)}
    res["machine"] = timing_note(start)
    res["timing"] = start
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".md").write_text(markdown(res))
    out.with_suffix(".json").write_text(json.dumps(res, indent=1) + "\n")
    print(f"wrote {out.with_suffix('.md')}, {out.with_suffix('.json')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
