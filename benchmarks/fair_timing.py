"""Fair timing (issue 19, item 6): each back-end's full solve in the numpy driver and in
the compiled driver, interleaved in one run.

The numpy driver (``engine="numpy"``: :func:`lcpbench.model.driver.run_driver` with the
step solver, the judge of :mod:`lcpbench.model.judge`) spends milliseconds per solve of
lcpbench's own Python around the back-end's calls; the compiled driver
(``engine="auto"``, :mod:`lcpbench.model.compiled_driver`, what ``lcpbench.solve`` and
the sweep run) compiles those parts. Per back-end, at N = 140, θ = 150°, h = 3 mm, tol
1e-3 rad, default settings: the median wall time of ``lcpbench.solve`` with each engine,
the back-end's own reported time (its solve and setup, summed over the outer
iterations, the same in both), and what is left: lcpbench's part (assembly, the
back-end's form, the judge, the line search, the certificate, the result; for QP
back-ends also the adapter's conversions, which both engines share). Both engines
must take the same path (outer iterations) and give the same force.

    python benchmarks/fair_timing.py [--repeat 15] [--out results/fair-timing.md]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
import statistics
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from perf import interleaved, wall  # the interleaved protocol of results/perf.md

from lcpbench import ActuatorScene
from lcpbench.api import solve_internal
from lcpbench.bench.machine import timing_note, timing_start
from lcpbench.solvers import available_backends, get_backend

SCENE = dict(theta=150.0, height=3.0, links=140)
TOL = 1e-3
#: an LCP back-end (lcpbench's Lemke, in Python) and QP back-ends of each kind
BACKENDS = ["lemke", "quantecon-lemke", "osqp", "clarabel", "qpsolvers-daqp",
            "proxsuite-sparse", "qpsolvers-piqp"]
#: "high": the profile at which these back-ends' answers pass lcpbench's judge here
SETTINGS = "high"
WARMUP = 2
ENGINES = {"numpy driver": "numpy", "compiled driver": "auto"}


def own_time(res) -> float:
    """The back-end's reported solve time, summed over the steps (its setup is not:
    a step's ``setup_time`` holds lcpbench's building of the form as well)."""
    return sum(s.solve_time for s in res.steps)


def timed_calls(backend: str) -> list[float]:
    """Wrap the adapter's entry point (``solve_qp`` / ``solve_lcp``, looked up on its
    module at each step) to add the wall time spent in it to the returned list's item."""
    b = get_backend(backend)
    mod = b.load()
    name = "solve_qp" if b.form == "qp" else "solve_lcp"
    spent = [0.0]
    inner = getattr(mod, name)

    def call(*args, **kw):
        t0 = time.perf_counter()
        try:
            return inner(*args, **kw)
        finally:
            spent[0] += time.perf_counter() - t0

    setattr(mod, name, call)
    return spent


def measure(backend: str, repeat: int, settings: str) -> dict:
    scene = ActuatorScene(**SCENE)
    own: dict[str, list[tuple]] = {name: [] for name in ENGINES}
    spent = timed_calls(backend)

    def contender(name, engine):
        def run():
            spent[0] = 0.0
            seconds, res = wall(lambda: solve_internal(scene, solver=backend, tol=TOL,
                                                       settings=settings, engine=engine))()
            own[name].append((seconds, spent[0], own_time(res)))
            return seconds, res
        return run

    runs = interleaved({n: contender(n, e) for n, e in ENGINES.items()}, repeat,
                       warmup=WARMUP)
    row = {"backend": backend}
    for name, r in runs.items():
        res, timed = r["payload"], own[name][WARMUP:]  # (one call per round: block 1)
        row[name] = {"median_s": statistics.median(r["times"]), "outer": res.outer_iterations,
                     "engine": res.engine, "converged": res.converged,
                     "reason": res.reason, "force": res.total_force,
                     "call_s": statistics.median(c for _, c, _ in timed),
                     "reported_s": statistics.median(o for _, _, o in timed),
                     "lcpbench_s": statistics.median(w - c for w, c, _ in timed),
                     "lcpbench_min_s": min(w - c for w, c, _ in timed)}
    return row


def markdown(rows: list[dict], note: str, args, when: str) -> str:
    lines = ["# Fair timing: every back-end in the same compiled driver (issue 19, item 6)", "",
             f"Made by `python benchmarks/fair_timing.py --repeat {args.repeat}` on {when}: "
             f"`lcpbench.solve(ActuatorScene(theta=150, height=3, links=140), solver=X, "
             f"tol=1e-3, settings=\"{args.settings}\", engine=E)`, E = `numpy` (the numpy "
             f"driver, the reference) and `auto` (the compiled driver around the back-end), "
             f"interleaved in rotating order, {args.repeat} repetitions after {WARMUP} "
             f"warm-up rounds, medians. Machine: {note}",
             "", "Back-end's calls: the wall time inside its adapter's `solve_qp` / "
             "`solve_lcp` (the adapter's and the library's Python and the library), summed "
             "over the outer iterations; of which it reports: its own solve time "
             "(the solver-reported column of the sweep; compiled driver's runs). lcpbench's part: the wall time minus the "
             "back-end's calls: assembly, the form, the "
             "judge, the line search, the certificate and the result (in brackets: the "
             "smallest over the runs, what an idle core gives). Medians over the runs of "
             "each engine.", "",
             "| back-end | outer (numpy / compiled) | numpy driver (ms) | compiled driver "
             "(ms) | speed-up | back-end's calls, numpy / compiled (ms) | of which it "
             "reports as its solve (ms) | lcpbench's part, numpy (ms) | lcpbench's part, compiled (ms) | "
             "force difference |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        a, b = r["numpy driver"], r["compiled driver"]
        diff = abs(a["force"] - b["force"]) / max(abs(a["force"]), 1e-300)
        conv = "" if a["converged"] and b["converged"] else " (not accepted by the judge)"
        lines.append(
            f"| `{r['backend']}`{conv} | {a['outer']} / {b['outer']} | "
            f"{a['median_s'] * 1e3:.2f} | {b['median_s'] * 1e3:.2f} | "
            f"{a['median_s'] / b['median_s']:.2f}× | {a['call_s'] * 1e3:.2f} / "
            f"{b['call_s'] * 1e3:.2f} | {b['reported_s'] * 1e3:.2f} | "
            f"{a['lcpbench_s'] * 1e3:.2f} ({a['lcpbench_min_s'] * 1e3:.2f}) | "
            f"{b['lcpbench_s'] * 1e3:.2f} ({b['lcpbench_min_s'] * 1e3:.2f}) | {diff:.1e} |")
    lines += ["", "Engines that ran: " + ", ".join(sorted(
        {f"{r[n]['engine']}" for r in rows for n in ENGINES})) + "."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--backends", default=",".join(BACKENDS))
    ap.add_argument("--settings", default=SETTINGS)
    ap.add_argument("--out", default="results/fair-timing.md")
    args = ap.parse_args(argv)
    start = timing_start()
    have = set(available_backends())
    rows = []
    for name in args.backends.split(","):
        if name not in have:
            print(f"{name}: not installed, skipped", file=sys.stderr)
            continue
        rows.append(measure(name, args.repeat, args.settings))
        a, b = rows[-1]["numpy driver"], rows[-1]["compiled driver"]
        print(f"{name:20s} numpy {a['median_s'] * 1e3:8.2f} ms  compiled "
              f"{b['median_s'] * 1e3:8.2f} ms  lcpbench's part {a['lcpbench_s'] * 1e3:6.2f} / "
              f"{b['lcpbench_s'] * 1e3:6.2f} ms",
              file=sys.stderr, flush=True)
    when = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    text = markdown(rows, timing_note(start), args, when)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
