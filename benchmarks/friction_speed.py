"""Issue 39, target 5: the speed of a frictional solve and of a pull-out at N = 140.

Scenes: the paper's (θ 150°, h 3 mm, N = 140) on one flat wall, the same in the
channel (θ 180°, h 2 mm, μ 0.3 above and 0.1 below), and against a stenosis (the wall
profile of ``benchmarks/scene_kinds.py``: 0.8 mm deep at x = 14 mm, 3 mm wide, from
3 mm); sliders at both ends, μ = 0.3. Contenders,
timed around the call and interleaved in rotating order (``perf.interleaved``), one
BLAS thread:

* the frictionless solve, ``lcpbench.solve`` of the scene with μ = 0 and pinned ends;
* a frictional solve: ``lcpbench.solve_path(scene with pull 0.05 N, [{}])``, one state,
  which includes its start (the frictionless placement, itself a solve);
* a pull-out: ``lcpbench.pull_out(scene)``;
* the frictional solve and the pull-out without the primal polish
  (``friction_lemke.polish_step`` made the identity for the call): the polish's cost, as
  the ratio of each to its run without it;
* the pull-out with the polish on every outer step's answer (``StepLemke.defers_polish``
  made False for the call; the default polishes only the answer that would end a state).

Targets: a frictional solve within 10× the frictionless one (the ratio per round,
median over rounds), a pull-out in <= 20 frictional solves and under 20 ms. Also
reported: the outer steps of each and the Lemke calls per contact step (restarts with
other covering vectors where one stops short of SOLVED). Writes
``results/friction/speed.md`` (``--out``; not overwritten unless ``--force``).

    python benchmarks/friction_speed.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from perf import interleaved

import lcpbench
import lcpbench.model.friction_lemke as driver
from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start

sys.path.insert(0, str(Path(__file__).resolve().parent))
from scene_kinds import stenosis

ROOT = Path(__file__).resolve().parents[1]
SCENES = {
    "flat wall": ActuatorScene(theta=150, height=3.0, links=140, friction=0.3,
                               left_end="slider", right_end="slider"),
    "channel": ActuatorScene(theta=180, height=2.0, links=140, channel=True,
                             friction=(0.3, 0.1), left_end="slider", right_end="slider"),
    "stenosis": ActuatorScene(theta=150, wall_profile=stenosis(), links=140, friction=0.3,
                              left_end="slider", right_end="slider"),
}
PULL = 0.05


def timed(fn, cpu: list):
    """A contender timed around the call on two clocks: returns (wall seconds, result)
    and appends the process's CPU seconds to ``cpu``. On a loaded machine the wall clock
    counts the time the process waits for a core; its CPU time does not."""
    def run():
        c0, t0 = time.process_time(), time.perf_counter()
        res = fn()
        seconds = time.perf_counter() - t0
        cpu.append(time.process_time() - c0)
        return seconds, res
    return run


def lemke_calls(fn) -> tuple[int, int]:
    """(contact steps, Lemke calls) of one call of ``fn`` (counted, not timed)."""
    count = {"steps": 0, "calls": 0}
    lemke, step = driver.lemke, driver.StepLemke.__call__

    def counted_lemke(*args, **kw):
        count["calls"] += 1
        return lemke(*args, **kw)

    def counted_step(self, M, q=None, polish=True):
        count["steps"] += 1
        return step(self, M, q, polish)

    driver.lemke, driver.StepLemke.__call__ = counted_lemke, counted_step
    try:
        fn()
    finally:
        driver.lemke, driver.StepLemke.__call__ = lemke, step
    return count["steps"], count["calls"]


def unpolished(fn):
    """``fn`` run with the frictional step's primal polish off (its cost, measured)."""
    def run():
        polish = driver.polish_step
        driver.polish_step = lambda fs, sol, *flips: sol
        try:
            return fn()
        finally:
            driver.polish_step = polish
    return run


def every_step_polished(fn):
    """``fn`` run with the primal polish on every outer step's answer (the default before
    it was deferred to the answer that would end a state: StepLemke.defers_polish
    False)."""
    def run():
        driver.StepLemke.defers_polish = False
        try:
            return fn()
        finally:
            driver.StepLemke.defers_polish = True
    return run


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "friction" / "speed.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("friction_speed.py", argv)
    start = timing_start()
    rows, ratios = [], []
    for name, scene in SCENES.items():
        plain = replace(scene, friction=0.0, left_end="pinned", right_end="pinned")
        pulled = replace(scene, pull=PULL)
        sink: dict = {"frictionless": [], "frictional": [], "pull-out": [], "unpolished": [],
                      "pull-out unpolished": [], "pull-out every step": []}
        calls = {"frictionless": timed(lambda plain=plain: lcpbench.solve(plain),
                                       sink["frictionless"]),
                 "frictional": timed(lambda s=pulled: lcpbench.solve_path(s, [{}]),
                                     sink["frictional"]),
                 "pull-out": timed(lambda s=scene: lcpbench.pull_out(s), sink["pull-out"]),
                 "unpolished": timed(unpolished(lambda s=pulled: lcpbench.solve_path(s, [{}])),
                                     sink["unpolished"]),
                 "pull-out unpolished": timed(unpolished(lambda s=scene: lcpbench.pull_out(s)),
                                              sink["pull-out unpolished"]),
                 "pull-out every step": timed(
                     every_step_polished(lambda s=scene: lcpbench.pull_out(s)),
                     sink["pull-out every step"])}
        got = interleaved(calls, a.rounds)
        t = {k: np.array(v["times"]) for k, v in got.items()}
        ratio = float(np.median(t["frictional"] / t["frictionless"]))
        bare = float(np.median(t["unpolished"] / t["frictionless"]))
        cost = float(np.median(t["frictional"] / t["unpolished"]))
        po_cost = float(np.median(t["pull-out"] / t["pull-out unpolished"]))
        deferred = float(np.median(t["pull-out every step"] / t["pull-out"]))
        (state,) = got["frictional"]["payload"]
        po = got["pull-out"]["payload"]
        cpu = {k: np.array(v[1:]) for k, v in sink.items()}  # (the first: the warm-up)
        cpu_ratio = float(np.median(cpu["frictional"] / cpu["frictionless"]))
        s_steps, s_calls = lemke_calls(lambda s=pulled: lcpbench.solve_path(s, [{}]))
        p_steps, p_calls = lemke_calls(lambda s=scene: lcpbench.pull_out(s))
        rows.append(
            f"| {name} | {1e3 * np.median(t['frictionless']):.3f} | "
            f"{1e3 * np.median(t['frictional']):.2f} | {ratio:.1f}× | {cpu_ratio:.1f}× | "
            f"{bare:.1f}× | {cost:.2f}× | "
            f"{state.outer_iterations} / {s_calls / max(s_steps, 1):.1f} | "
            f"{1e3 * np.median(t['pull-out']):.1f} | {1e3 * np.median(cpu['pull-out']):.1f} | "
            f"{1e3 * np.median(t['pull-out unpolished']):.1f} | {po_cost:.2f}× | "
            f"{1e3 * np.median(t['pull-out every step']):.1f} | {deferred:.2f}× | "
            f"{po.solves} | "
            f"{sum(r.outer_iterations for r in po.path)} / {p_calls / max(p_steps, 1):.1f} | "
            f"{1e3 * po.force:.4g} | {state.converged and po.converged} |")
        ratios.append(ratio)
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# Speed of the frictional solve and of pull-out (issue 39, target 5)", "",
        f"Measured {when}; {timing_note(start)} Command: `{cmd}`. N = 140, sliders at both ends, μ 0.3 (the channel: "
        f"0.3 above, 0.1 below; the stenosis: the wall profile of benchmarks/scene_kinds.py, "
        f"its frictionless solve the compiled profile driver), each call at its defaults (`solve` and `solve_path`: tol "
        "1e-3, the paper's; `pull_out`: tol 1e-10, rtol 1e-6). Medians over rounds, interleaved; the "
        "ratio is the median of the per-round ratios, on the wall clock and on the process's "
        "CPU time (which does not count the time a loaded machine keeps the process "
        "waiting). Lemke calls per step: the steps the warm start (block principal "
        "pivoting from the last answer's support, else from the frictionless contacts "
        "sticking or sliding) does not answer go to Lemke, one call "
        "per covering vector tried. Without the polish: the same frictional solve with the "
        "step's primal polish off (friction_lemke.polish_step made the identity), "
        "interleaved with the others. The polish runs on the answer that would end a "
        "state (the reported one), not on the outer steps before it; every step polished: "
        "the pull-out with the polish on every outer step's answer (the default before; "
        "StepLemke.defers_polish made False), interleaved, and its time over the "
        "default's. The frictional solve is one state of "
        f"a path, pull {PULL} N, and includes its start (the frictionless placement).", "",
        "Targets: frictional solve <= 10× the frictionless one; pull-out in <= 20 "
        "frictional solves and < 20 ms.", "",
        "| scene | frictionless (ms) | frictional (ms) | ratio | ratio (CPU) | ratio without "
        "the polish | the polish's cost (frictional / without) | its outer "
        "steps / Lemke calls per step | pull-out (ms) | pull-out (CPU ms) | pull-out without "
        "the polish (ms) | the polish's cost | every step polished (ms) | its time over "
        "the default's | its solves | "
        "outer steps (all states) / Lemke calls per step | pull-out force (mN) | converged |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
        *rows, ""])
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
