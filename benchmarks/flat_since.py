"""Issue 35, target 6 (issue 19's target 1 kept) read against a fixed revision: the flat
solve now and at an older revision (``--ref``, default 308f03e: main when issue 35 was
filed), with the dense paper path of each beside it, interleaved in one run.

Target 6 asks that "the flat solve ≥ 150× the dense paper path" stay as it was. The
ratio moves with both of its terms, and the dense path's Lemke was compiled after the
issue was filed, so this script times both terms of both revisions on the same machine
in the same minutes. Each revision runs in a process of its own (its ``src`` first on the
path, its own numba cache, ``LCPBENCH_AOT=0``: both use numba's JIT cache, so the same
compiler builds both), driven round by round from here; in each round each revision in
turn (the order alternating) runs

- a 30 ms busy loop of Python, then one timed ``lcpbench.solve`` of the paper scene
  (N = 140, θ = 150°, h = 3 mm, tol 1e-3): the cold state of ``perf.py``'s interleaved
  protocol (results/cold-penalty.md: 2.4× the warm time after 30 ms);
- five ``lcpbench.solve`` in a row (the back-to-back time: their median), then five
  more under cProfile, for the own time of its two kernels (``solve_chain``, the solve;
  ``judge_answer``, the result judge);
- the dense paper path once (eqs. 3-31 and Lemke; ``solve_paper_dense``).

Wall time (``perf_counter``), one BLAS thread, the load average recorded. Reported: the
medians and minima, now / then per row, dense / solve within each revision, and the
forces of both revisions. Writes ``results/flat-since.md`` and ``.json``; refuses to
overwrite them without ``--force``.

    python benchmarks/flat_since.py [--ref 308f03e] [--now REV] [--rounds 41]
                                    [--out results/flat-since] [--force]

``--now`` puts another revision in place of this tree (to find which change moved a
time: two revisions, interleaved).
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import io
import json
import statistics
import subprocess
import sys
import tarfile
from datetime import datetime, timezone
from pathlib import Path

from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start

ROOT = Path(__file__).resolve().parent.parent
ROWS = {"cold": "after a 30 ms busy loop", "warm": "back to back (median of 5 in a row)",
        "kernel": "its solve kernel (solve_chain), back to back",
        "judge": "its judge kernel (judge_answer), back to back", "dense": "dense paper path"}

#: what each revision's process runs: one line in ("round"), one JSON line out
CHILD = r"""
import cProfile, json, pstats, statistics, sys, time
import lcpbench
try:
    from lcpbench.reference.dense import solve_paper_dense
except ImportError:  # before the dense path moved to reference/
    from lcpbench.model.dense import solve_paper_dense
scene = lcpbench.ActuatorScene(theta=150.0, height=3.0, links=140)

def solve():
    t0 = time.perf_counter()
    res = lcpbench.solve(scene, tol=1e-3)
    return time.perf_counter() - t0, res

def dense():
    t0 = time.perf_counter()
    out = solve_paper_dense(scene, tol=1e-3)
    return time.perf_counter() - t0, out

for _ in range(3):
    _, res = solve()
    _, out = dense()
print(json.dumps({"force": float(res.total_force), "converged": bool(res.converged),
                  "dense_force": float(sum(out[1])), "dense_ok": bool(out[3])}), flush=True)
for line in sys.stdin:
    if line.strip() != "round":
        break
    end = time.perf_counter() + 0.030
    while time.perf_counter() < end:
        pass
    cold, _ = solve()
    warm = statistics.median(solve()[0] for _ in range(5))
    prof = cProfile.Profile()  # the two kernels' own time in five more solves
    prof.enable()
    for _ in range(5):
        solve()
    prof.disable()
    part = {"solve_chain": 0.0, "judge_answer": 0.0}
    for (_, _, name), (_, _, own, _, _) in pstats.Stats(prof).stats.items():
        if name in part:
            part[name] += own / 5
    d, _ = dense()
    print(json.dumps({"cold": cold, "warm": warm, "kernel": part["solve_chain"],
                      "judge": part["judge_answer"], "dense": d}), flush=True)
"""


def source_of(ref: str) -> tuple[Path, str]:
    """``src`` of revision ``ref``, extracted once under the user's cache; (path, sha)."""
    sha = subprocess.run(["git", "rev-parse", ref], cwd=ROOT, check=True, capture_output=True,
                         text=True).stdout.strip()
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "lcpbench-since"
    tree = base / sha[:12]
    if not (tree / "done").exists():
        tar = subprocess.run(["git", "archive", sha, "src"], cwd=ROOT, check=True,
                             capture_output=True).stdout
        with tarfile.open(fileobj=io.BytesIO(tar)) as t:
            t.extractall(tree, filter="data")
        (tree / "done").write_text(sha)
    return tree / "src", sha


def start(src: Path) -> tuple[subprocess.Popen, dict]:
    """A process of the revision at ``src``, warmed (three solves and dense paths; it
    compiles its kernels the first time); (process, its forces)."""
    env = dict(os.environ, PYTHONPATH=str(src), LCPBENCH_AOT="0")
    proc = subprocess.Popen([sys.executable, "-c", CHILD], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True, env=env, cwd=src.parent)
    line = proc.stdout.readline()
    if not line:
        raise SystemExit(f"error: the process of {src} ended before it was warm")
    return proc, json.loads(line)


def one_round(proc: subprocess.Popen) -> dict:
    proc.stdin.write("round\n")
    proc.stdin.flush()
    return json.loads(proc.stdout.readline())


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description="the flat solve now against an older revision, "
                                 "interleaved (issue 35, target 6)")
    ap.add_argument("--ref", default="308f03e", help="the older revision (default 308f03e)")
    ap.add_argument("--now", default=None,
                    help="a revision in place of this tree's src (default: this tree)")
    ap.add_argument("--rounds", type=int, default=41, help="interleaved rounds (default 41)")
    ap.add_argument("--out", default=str(ROOT / "results" / "flat-since"),
                    help="output path without extension (default results/flat-since)")
    ap.add_argument("--force", action="store_true", help="overwrite committed results")
    args = ap.parse_args(argv)
    if args.rounds < 1:
        ap.error("--rounds must be at least 1")
    out = Path(args.out)
    refuse_overwrite([out.with_suffix(".md"), out.with_suffix(".json")], args.force)
    then_src, sha = source_of(args.ref)
    if args.now is None:
        now_src = ROOT / "src"
        now_sha = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT,
                                 capture_output=True, text=True).stdout.strip()
    else:
        now_src, now_sha = source_of(args.now)
        now_sha = now_sha[:7]
    trees = {"then": then_src, "now": now_src}
    t = timing_start()
    procs, forces = {}, {}
    for name, src in trees.items():
        print(f"warming {name} ({src}) ...", file=sys.stderr)
        procs[name], forces[name] = start(src)
    times = {name: {row: [] for row in ROWS} for name in trees}
    for r in range(args.rounds):
        order = ("then", "now") if r % 2 == 0 else ("now", "then")
        for name in order:
            got = one_round(procs[name])
            for row in ROWS:
                times[name][row].append(got[row])
        print(f"\rround {r + 1}/{args.rounds}", end="", file=sys.stderr)
    print(file=sys.stderr)
    for proc in procs.values():
        proc.stdin.close()
        proc.wait()
    note = timing_note(t)
    stats = {name: {row: {"median_ms": 1e3 * statistics.median(v), "min_ms": 1e3 * min(v)}
                    for row, v in rows.items()} for name, rows in times.items()}
    report = {"date": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
              "then": sha, "now": now_sha, "rounds": args.rounds, "machine": note,
              "command": command_line("flat_since.py", argv), "forces": forces,
              "stats": stats, "times_s": times}
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(report, indent=1) + "\n")
    out.with_suffix(".md").write_text(markdown(report))
    print(out.with_suffix(".md").read_text())


def markdown(rep: dict) -> str:
    s, f = rep["stats"], rep["forces"]
    then = rep["then"][:7]
    lines = [
        f"# The flat solve now against {then} (issue 35, target 6: issue 19's target 1 kept)",
        "",
        f"Measured {rep['date']} on {rep['machine']} Command: `{rep['command']}`.", "",
        f"`lcpbench.solve` of the paper scene (N = 140, θ = 150°, h = 3 mm, tol 1e-3) and the "
        f"dense paper path, in a process of each revision ({then}: main when issue 35 was "
        f"filed; now: {rep['now']}), {rep['rounds']} interleaved rounds, the order "
        "alternating; `LCPBENCH_AOT=0` in both (numba's JIT cache). Wall time.", "",
        f"| row | {then} median (ms) | min | now median (ms) | min | now / {then} |",
        "|---|---|---|---|---|---|"]
    for row, label in ROWS.items():
        a, b = s["then"][row], s["now"][row]
        lines.append(f"| {label} | {a['median_ms']:.3f} | {a['min_ms']:.3f} | "
                     f"{b['median_ms']:.3f} | {b['min_ms']:.3f} | "
                     f"{b['median_ms'] / a['median_ms']:.2f} |")
    lines += ["", "Target 6's ratio, dense paper path / flat solve, within each revision "
              "(medians):", "",
              "| revision | dense / solve after 30 ms | dense / solve back to back |",
              "|---|---|---|"]
    for name, label in (("then", then), ("now", rep["now"])):
        d = s[name]["dense"]["median_ms"]
        lines.append(f"| {label} | {d / s[name]['cold']['median_ms']:.0f}× | "
                     f"{d / s[name]['warm']['median_ms']:.0f}× |")
    med = {name: {row: s[name][row]["median_ms"] * 1e3 for row in ROWS} for name in s}
    parts = {name: (m["kernel"], m["judge"], m["warm"] - m["kernel"] - m["judge"])
             for name, m in med.items()}
    delta = [b - a for a, b in zip(parts["then"], parts["now"])]
    lines += ["", f"Back to back, now − {then} = {med['now']['warm'] - med['then']['warm']:+.1f} "
              f"µs: the solve kernel {delta[0]:+.1f} µs, the judge kernel {delta[1]:+.1f} µs, "
              f"the rest (the Python around them; the kernels' own times are read under "
              f"cProfile) {delta[2]:+.1f} µs ({parts['then'][2]:.1f} → {parts['now'][2]:.1f} "
              "µs)."]
    rel = abs(f["now"]["force"] - f["then"]["force"]) / abs(f["then"]["force"])
    lines += ["", f"Forces: {then} F = {f['then']['force']:.10f} N (converged "
              f"{f['then']['converged']}), now F = {f['now']['force']:.10f} N (converged "
              f"{f['now']['converged']}): relative difference {rel:.1e}. Dense paper path: "
              f"{f['then']['dense_force']:.10f} N and {f['now']['dense_force']:.10f} N.", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    main()
