"""Issue 35, target 1: every scene kind at N = 140 against the flat-wall solve.

Times ``lcpbench.solve`` (the default back-end, tol 1e-3 and 1e-9) on one scene of each
kind users asked for (θ = 150°, h = 3 mm, the paper's chain), interleaved: each round
calls every scene once, in turn, after one warm-up call each, so that load spikes hit
them alike. Ratios are of medians over the rounds; the engine that ran is recorded from
each result. Writes ``results/scene-kinds.md`` (``--out``; an existing file is not
overwritten unless ``--force``).

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/scene_kinds.py --force
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
from perf import interleaved, wall  # (benchmarks/ is the script's directory)

import lcpbench
from lcpbench import ActuatorScene, SectionedScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.problems.walls import WallProfile

ROOT = Path(__file__).resolve().parents[1]
PAPER = dict(theta=150.0, height=3.0, links=140)


def stenosis() -> WallProfile:
    """A Gaussian narrowing of 0.8 mm at x = 14 mm, 3 mm wide (tests/model/test_profile.py)."""
    def h(x):
        return 3.0 - 0.8 * np.exp(-((x - 14.0) / 3.0) ** 2)

    def dh(x):
        return 0.8 * 2 * (x - 14.0) / 9.0 * np.exp(-((x - 14.0) / 3.0) ** 2)

    return WallProfile.from_function(h, dh, name="stenosis")


def scenes() -> dict[str, object]:
    """The scene kinds of issue 35's table, the flat wall first. The two sections bend
    opposite ways, as the paper's actuator's do (two 150° sections bending the same way
    make a 300° arc, past the range the cold start reaches: the loading path answers it,
    at 15-35 solves)."""
    return {
        "flat wall": ActuatorScene(**PAPER),
        "channel": ActuatorScene(**PAPER, channel=True),
        "two sections": SectionedScene(sections=[(150.0, 15.0), (-150.0, 15.0)], height=3.0,
                                       links=140),
        "elastic walls, k = 0.1 N/mm²": ActuatorScene(**PAPER, wall_stiffness=0.1),
        "elastic walls, k = 1e4 N/mm²": ActuatorScene(**PAPER, wall_stiffness=1e4),
        "wall profile (a stenosis)": ActuatorScene(**PAPER, wall_profile=stenosis()),
        "heavy chain (10× the paper's weight)": ActuatorScene(**PAPER, weight=10 * 0.000245),
    }


def measure(all_scenes: dict, tol: float, rounds: int) -> dict[str, dict]:
    """Each scene's solve times (perf.interleaved: rotating order, one warm-up round,
    the garbage collector off during a call), its engine, verdict and force."""
    calls = {name: wall(lambda scene=scene: lcpbench.solve(scene, tol=tol))
             for name, scene in all_scenes.items()}
    got = interleaved(calls, rounds)
    return {name: {"times": g["times"], "engine": g["payload"].engine,
                   "converged": g["payload"].converged, "force": g["payload"].total_force}
            for name, g in got.items()}


def table(got: dict[str, dict]) -> list[str]:
    base = float(np.median(got["flat wall"]["times"]))
    lines = ["| scene | median (ms) | min (ms) | × the flat wall | engine | converged | F (N) |",
             "|---|---:|---:|---:|---|---|---:|"]
    for name, g in got.items():
        med = float(np.median(g["times"]))
        lines.append(f"| {name} | {1e3 * med:.3f} | {1e3 * min(g['times']):.3f} | "
                     f"{med / base:.2f} | {g['engine']} | {g['converged']} | "
                     f"{g['force']:.10g} |")
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=31)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "scene-kinds.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("scene_kinds.py", argv)
    start = timing_start()
    all_scenes = scenes()
    parts = []
    for tol in (1e-3, 1e-9):
        parts += [f"## tol {tol:g} rad", "", *table(measure(all_scenes, tol, a.rounds)), ""]
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# Every scene kind against the flat wall (issue 35, target 1)", "",
        f"Measured {when}; {timing_note(start)} Command: `{cmd}`. `lcpbench.solve` with the default back-end, θ = 150°, "
        f"h = 3 mm, N = 140; {a.rounds} interleaved rounds after one warm-up round, in rotating order. "
        "Target: every kind within 2× of the flat wall. Times of different runs are not "
        "comparable, ratios are. Each scene object is solved again every round, so what a "
        "scene derives once and keeps (its chain, the kernels' arrays, a function profile's "
        "table of cubic pieces: 3 ms for the stenosis) is not in the times.", "", *parts])
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
