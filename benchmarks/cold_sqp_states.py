"""Issue 35, target 3: can the rows of sections that the line kernel stops on skip the
loading path, solved instead from their cold start by the SQP in the link angles?

For rows of sections that share one layout (the mixed batch's rows of two sections
(θ, −θ), and seeded rows of two and three sections with independent signed θ in
100°–180°, h in 1–5 mm, against one wall or in a channel), the rows on which the line
kernel stops cold (:func:`lcpbench.studies.batch_line.run_line` gives a
:class:`~lcpbench.studies.batch_result.Stopped`) are solved
twice: by :func:`lcpbench.solve` (its plan: the cold start refused, the loading path,
escalation "ramped") and by the compiled SQP in the link angles from the same cold
start as the line kernel's (:func:`lcpbench.model.heavy_driver.run_heavy`, no start),
judged by lcpbench's judge (:func:`lcpbench.model.finish.finish`). Reports how many of
each are certified, whether the two certified answers are one state
(:func:`lcpbench.escalations.same_state`: each wall's total force within the judge's
τ·F₀), and the median time of each. Writes ``results/cold-sqp-states.md`` (``--out``;
not overwritten unless ``--force``).

    python benchmarks/cold_sqp_states.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from mixed_batch import KINDS, mixed

import lcpbench
from lcpbench import SectionedScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.escalations import same_state
from lcpbench.model.finish import finish
from lcpbench.model.heavy_driver import run_heavy
from lcpbench.studies.batch_line import run_line
from lcpbench.studies.batch_result import Stopped

ROOT = Path(__file__).resolve().parents[1]
TOL = 1e-3


def rows_of(seed: int, sections: int, channel: bool, count: int = 80) -> list:
    rng = np.random.default_rng(seed)
    return [SectionedScene(sections=[(float(rng.choice([-1, 1]) * rng.uniform(100, 180)),
                                      15.0) for _ in range(sections)],
                           height=float(rng.uniform(1.0, 5.0)), links=20 * sections,
                           channel=channel) for _ in range(count)]


def cold_sqp(scene):
    """The SQP's answer from the cold start, judged; None where it did not converge."""
    chain = scene.chain()
    out = run_heavy(chain, None, TOL, 200, why="the cold start, for comparison")
    if out is None:
        return None
    return finish(scene, chain, out, solver="active-set", method="globalised", tol=TOL,
                  elapsed=0.0, settings="default", engine="compiled", why=None)


def timed(fn, scene):
    t0 = time.perf_counter()
    got = fn(scene)
    return got, time.perf_counter() - t0


def compare(name: str, rows: list) -> str:
    got = run_line(rows, tol=TOL, plane=list(range(len(rows))))
    if got is None:
        return f"| {name} | {len(rows)} | the line kernel does not take them | | | | | |"
    stopped = [s for s, r in zip(rows, got, strict=True) if isinstance(r, Stopped)]
    path_ok = sqp_ok = same = 0
    t_path, t_sqp = [], []
    for scene in stopped:
        ramped, tp = timed(lambda s: lcpbench.solve(s, tol=TOL), scene)
        direct, ts = timed(cold_sqp, scene)
        t_path.append(tp)
        t_sqp.append(ts)
        path_ok += ramped.converged
        ok = direct is not None and direct.converged
        sqp_ok += ok
        same += ok and ramped.converged and same_state(ramped, direct)
    if not stopped:
        return f"| {name} | {len(rows)} | 0 | | | | | |"
    return (f"| {name} | {len(rows)} | {len(stopped)} | {path_ok} | {sqp_ok} | {same} | "
            f"{np.median(t_path) * 1e3:.1f} | {np.median(t_sqp) * 1e3:.1f} |")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seed", type=int, default=11)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "cold-sqp-states.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("cold_sqp_states.py", argv)
    start = timing_start()
    sets = [("mixed batch (seed 7): two sections (θ, −θ), N = 140",
             [s for i, s in enumerate(mixed(7)) if KINDS[i % 4] == "two sections"])]
    for k, channel in ((2, False), (2, True), (3, False), (3, True)):
        sets.append((f"{k} sections, independent signed θ, {'channel' if channel else 'one wall'}"
                     f", N = {20 * k}", rows_of(a.seed + 10 * k + channel, k, channel)))
    cold_sqp(sets[0][1][0])  # (compiled kernels loaded before timing)
    table = [compare(name, rows) for name, rows in sets]
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# Rows the line kernel stops on: the loading path or the cold SQP? (issue 35, "
        "target 3)", "",
        f"Measured {when}; {timing_note(start)} Command: `{cmd}`; tol {TOL:g}.", "",
        "Rows of sections on which the line kernel stops cold, solved by `lcpbench.solve` "
        "(the loading path) and by the compiled SQP in the link angles from the same cold "
        "start, judged by lcpbench's judge; same state: each wall's total force within the "
        "judge's τ·F₀ (`escalations.same_state`).", "",
        "| rows | count | stopped | loading path certified | cold SQP certified | "
        "same state | loading path ms (median) | cold SQP ms (median) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|", *table, "",
        "Same state counts the rows where both answers are certified and agree. Where "
        "both are certified and disagree, the scene has several stable states and the cold "
        "SQP reaches another than the loading path, which `lcpbench.solve` returns (the "
        "state the pressurised actuator reaches). Only the mixed batch's (θ, −θ) rows "
        "agree throughout, so the cold SQP does not replace the loading path; `solve_many` "
        "starts a refused row from a certified neighbouring row's answer instead, where it "
        "has one (results/row-neighbours.md).",
        ""])
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
