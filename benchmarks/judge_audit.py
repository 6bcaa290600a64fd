"""Converged-but-wrong audit: every back-end on random scenes, judged against the reference.

Issue 14 asks that no back-end ever returns a wrong answer marked converged.
This script draws random actuator scenes over the ranges of that issue's
adversarial test (θ 5–180°, h 0.3–8 mm, N 10–400, EI 1–500 N·mm², w 0–0.02
N/mm, ℓ 10–90 mm), runs every installed back-end at the given profiles through
the sweep harness (one worker process per job, a time limit per run), and
counts per back-end and profile:

- accurate: converged and within the report's success rule, min(1e-3, 100·tol)
  of the reference's total force (:mod:`lcpbench.bench.metrics`);
- wrong: marked converged but outside it ("converged, off the reference");
- not converged.

The reference of each scene is the sweep's own (active set at ``high``, tol
1e-11, its last step re-solved by dense Lemke). Runs go into a scratch store
(``--store``), so the committed results are never touched unless ``--out`` points
at them::

    OMP_NUM_THREADS=1 python benchmarks/judge_audit.py --scenes 100 \
        --store /tmp/audit.db --out results/judge-audit.md
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.bench.metrics import evaluate
from lcpbench.bench.store import Store
from lcpbench.bench.sweep import plan_sweep, sweep
from lcpbench.solvers.registry import available_backends


def random_scenes(count: int, seed: int) -> list[ActuatorScene]:
    """``count`` scenes drawn from the issue's ranges (log-uniform for h, N, EI)."""
    rng = np.random.default_rng(seed)
    scenes = []
    for _ in range(count):
        scenes.append(ActuatorScene(
            theta=round(float(rng.uniform(5.0, 180.0)), 3),
            height=round(float(np.exp(rng.uniform(np.log(0.3), np.log(8.0)))), 4),
            links=int(round(np.exp(rng.uniform(np.log(10), np.log(400))))),
            length=round(float(rng.uniform(10.0, 90.0)), 2),
            EI=round(float(np.exp(rng.uniform(np.log(1.0), np.log(500.0)))), 3),
            weight=round(float(rng.choice([0.0, rng.uniform(0.0, 0.02)])), 5),
        ))
    return scenes


def counts(evaluated, good_refs: set) -> dict[tuple[str, str], dict[str, int]]:
    """Per (back-end, settings): accurate / wrong (converged, off) / not converged, and the
    runs of scenes whose reference did not converge (not judged)."""
    out: dict[tuple[str, str], dict[str, int]] = {}
    for e in evaluated:
        c = out.setdefault((e.backend, e.settings), {"accurate": 0, "wrong": 0,
                                                     "not converged": 0, "no reference": 0})
        if not math.isfinite(e.error) and e.row["scene"] not in good_refs:
            c["no reference"] += 1
        elif e.success:
            c["accurate"] += 1
        elif e.row["converged"]:
            c["wrong"] += 1
        else:
            c["not converged"] += 1
    return out


def markdown(table: dict, args, elapsed: float, machine: str, wrong_examples: list,
             command: str) -> str:
    lines = [f"# Converged-but-wrong audit ({args.scenes} random scenes, seed {args.seed})", "",
             f"Made by `{command}`"
             f" in {elapsed / 60:.1f} min; {machine} \"wrong\" = marked converged but off the reference by more than "
             "the success rule min(1e-3, 100·tol) (docs/bench.md).", "",
             "| back-end | settings | accurate | wrong | not converged | no reference |",
             "|---|---|---:|---:|---:|---:|"]
    total_wrong = 0
    for (b, s), c in sorted(table.items()):
        total_wrong += c["wrong"]
        lines.append(f"| {b} | {s} | {c['accurate']} | {c['wrong']} | {c['not converged']} "
                     f"| {c['no reference']} |")
    lines += ["", f"**Total wrong: {total_wrong}.**", ""]
    if wrong_examples:
        lines += ["Wrong runs (first 20): back-end/settings, scene, error, reason", ""]
        lines += [f"- {w}" for w in wrong_examples[:20]]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", type=int, default=100)
    ap.add_argument("--seed", type=int, default=14)
    ap.add_argument("--profiles", nargs="+", default=["default", "high"])
    ap.add_argument("--solvers", nargs="*", default=None,
                    help="back-ends (default: every installed one)")
    ap.add_argument("--store", default="judge-audit.db", help="scratch store (created)")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--time-limit", type=float, default=30.0, help="s per run")
    ap.add_argument("--out", default=None, help="write the markdown table here")
    ap.add_argument("--force", action="store_true", help="overwrite an existing --out")
    args = ap.parse_args(argv)
    if args.out:
        refuse_overwrite([args.out, Path(args.out).with_suffix(".json")], args.force)
    scenes = random_scenes(args.scenes, args.seed)
    names = args.solvers or available_backends()
    jobs = plan_sweep(scenes, names, args.profiles, baselines=())
    start = timing_start()
    t0 = time.perf_counter()
    with Store(args.store) as store:

        def progress(done, total, job, row):
            if done % 50 == 0 or done == total:
                print(f"  {done}/{total} rows", file=sys.stderr, flush=True)

        sweep(store, jobs, workers=args.jobs, time_limit=args.time_limit, progress=progress)
        keys = {s for s in (j.scene for j in jobs)}
        runs = [r for r in store.runs(arrays=False) if r["scene"] in keys
                and r["backend"] in names and r["settings"] in args.profiles]
        refs = store.refs(arrays=False)
    evaluated = evaluate(runs, refs)
    table = counts(evaluated, {k for k, r in refs.items() if r["converged"]})
    wrong = [f"{e.backend}/{e.settings} {e.row['scene']}: error {e.error:.2e}"
             for e in evaluated if e.row["converged"] and not e.success
             and math.isfinite(e.error)]
    text = markdown(table, args, time.perf_counter() - t0, timing_note(start), wrong,
                    command_line("judge_audit.py", argv))
    print(text)
    if args.out:
        Path(args.out).write_text(text)
        Path(args.out).with_suffix(".json").write_text(json.dumps(
            [{"backend": b, "settings": s, **c} for (b, s), c in sorted(table.items())],
            indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
