"""Issue 35, target 3: ``solve_many`` on 100 mixed scenes at tol 1e-3.

The scenes (seeded, N = 140, θ uniform in 90°–180°, h in 2–5 mm): 25 with elastic walls
(k log-uniform in 0.1–1e4 N/mm²), 25 against a wall profile (the stenosis of
``scene_kinds.py`` or a PCHIP bump, h 3 mm), 25 rows of two sections (θ, −θ), 25 in a
channel. Beside them, for scale, 100 scenes of the paper's grid (one flat wall), and
each kind's 25 scenes as a batch of their own. Each round solves every batch once, in
rotating order (``perf.interleaved``), fresh scene objects every round (nothing a scene
derives once is reused), built before the clock starts: the clock times ``solve_many``
alone, chains included (a scene builds its chain on first read), as
``perf_targets.throughput`` times the paper grid; the constructors' time is a row of its
own. Reports scenes/s (median over rounds) and how many were certified. Writes ``results/mixed-batch.md``
(``--out``; not overwritten unless ``--force``).

    python benchmarks/mixed_batch.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import collections
import sys
import time
from pathlib import Path

import numpy as np
from perf import interleaved, wall
from scene_kinds import stenosis

import lcpbench
from lcpbench import ActuatorScene, SectionedScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.problems.walls import WallProfile

ROOT = Path(__file__).resolve().parents[1]
KINDS = ("elastic walls", "wall profile", "two sections", "channel")


def mixed(seed: int) -> list:
    rng = np.random.default_rng(seed)
    walls = (stenosis(), WallProfile.from_table([0, 10, 14, 18, 30], [3.0, 3.0, 2.4, 3.0, 3.0]))
    out = []
    for i in range(100):
        th, h = float(rng.uniform(90, 180)), float(rng.uniform(2, 5))
        kind = KINDS[i % 4]
        if kind == "elastic walls":
            out.append(ActuatorScene(theta=th, height=h, links=140,
                                     wall_stiffness=float(10 ** rng.uniform(-1, 4))))
        elif kind == "wall profile":
            out.append(ActuatorScene(theta=th, height=3.0, links=140,
                                     wall_profile=walls[(i // 4) % 2]))
        elif kind == "two sections":
            out.append(SectionedScene(sections=[(th, 15.0), (-th, 15.0)], height=h, links=140))
        else:
            out.append(ActuatorScene(theta=th, height=h, links=140, channel=True))
    return out


def of_kind(seed: int, kind: str) -> list:
    """The scenes of one kind of :func:`mixed` (fresh objects)."""
    return [s for i, s in enumerate(mixed(seed)) if KINDS[i % 4] == kind]


def paper_grid() -> list:
    return [ActuatorScene(theta=float(t), height=float(h), links=140)
            for t in np.linspace(90, 180, 10) for h in np.linspace(2, 5, 10)]


#: the phases timed inside solve_many (inclusive: a phase's time holds the phases under
#: it): (label, depth, module, attribute, class or None), each wrapped where it is looked
#: up (with ahead-of-time kernels, lcpbench.aot, the kernel's own row reads 0)
PHASES = (
    ("line kernel: plan checks, arrays, one call per group", 0, "lcpbench.studies.batch",
     "run_line", None),
    ("the kernel (predict, solve, judge each scene)", 1, "lcpbench.model.batch_kernel",
     "solve_line", None),
    ("a line against one profiled wall: one kernel call per attempt", 0,
     "lcpbench.studies.batch_compiled", "profile_line", None),
    ("per-scene loop (wall profiles the profile line does not take)", 0,
     "lcpbench.studies.batch_compiled", "_solve_one", None),
    ("the driver (profile kernel; solve kernel)", 1, "lcpbench.studies.batch_compiled",
     "drive", None),
    ("the driver (profile kernel; solve kernel)", 1, "lcpbench.studies.batch_compiled",
     "run_compiled", None),
    ("result and judge (finish)", 1, "lcpbench.studies.batch_compiled", "finish", None),
    ("a row the line kernel stopped on: the kernel's fall-back, judged", 0,
     "lcpbench.studies.batch", "_after_stop", None),
    ("solve() of a row the line kernel stopped on in its wall-free search", 0,
     "lcpbench.studies.batch", "solve_internal", None),
    ("a refused answer's escalations (as solve()'s)", 0, "lcpbench.studies.batch",
     "_retried", None),
    ("SQP from a neighbouring row (escalation 'from_neighbour')", 1, "lcpbench.escalations",
     "run_heavy", None),
    ("loading path (escalation 'ramped')", 1, "lcpbench.escalations", "follow_load", None),
    ("SQP in the link angles", 2, "lcpbench.model.ramp", "run_heavy", None),
    ("height steps, a run in one call (path kernel)", 2, "lcpbench.model.ramp", "_walked",
     None),
    ("height steps, one by one (solve kernel)", 2, "lcpbench.model.ramp", "drive", None),
    ("rest shapes at s·θ (one pass a path)", 2, "lcpbench.model.ramp", "_rest_shapes", None),
    ("scene build (the chain, inside the phases above where first read)", 0,
     "lcpbench.problems.scenes", "_build_chain", "ActuatorScene"),
    ("scene build (the chain, inside the phases above where first read)", 0,
     "lcpbench.problems.sections", "_build_chain", "SectionedScene"),
)


def batch(make):
    """A contender: ``solve_many`` of the fresh scenes ``make()`` builds, timed around
    ``solve_many`` alone (the scenes' constructors run before the clock starts, as
    ``perf_targets.throughput`` builds its fresh scenes; their chains are built inside
    the clock, on first read)."""
    def run():
        scenes = make()
        t0 = time.perf_counter()
        res = lcpbench.solve_many(scenes, tol=1e-3)
        return time.perf_counter() - t0, res
    return run


def phases(seed: int, rounds: int) -> list[str]:
    """Table rows: the time of each of :data:`PHASES` per mixed batch (mean over
    ``rounds`` batches, after the timed rounds: the wrappers cost a little)."""
    import importlib

    spent: dict = collections.defaultdict(float)
    calls: dict = collections.defaultdict(int)
    saved = []
    for label, _, mod, attr, cls in PHASES:
        owner = importlib.import_module(mod)
        owner = getattr(owner, cls) if cls else owner
        real = getattr(owner, attr)

        def timed(*a, _real=real, _label=label, **kw):
            t0 = time.perf_counter()
            try:
                return _real(*a, **kw)
            finally:
                spent[_label] += time.perf_counter() - t0
                calls[_label] += 1
        saved.append((owner, attr, real))
        setattr(owner, attr, timed)
    try:
        total = 0.0
        for _ in range(rounds):
            scenes = mixed(seed)  # (built outside the clock, as in the timed rounds)
            t0 = time.perf_counter()
            lcpbench.solve_many(scenes, tol=1e-3)
            total += (time.perf_counter() - t0) / rounds
    finally:
        for owner, attr, real in saved:
            setattr(owner, attr, real)
    rows = [f"| solve_many, 100 mixed scenes (timers on) | {total * 1e3:.1f} | 1 |"]
    for label, depth in dict.fromkeys((lab, d) for lab, d, *_ in PHASES):
        rows.append(f"| {'  ' * depth}{'└ ' if depth else ''}{label} | "
                    f"{spent[label] / rounds * 1e3:.1f} | {calls[label] / rounds:.0f} |")
    return rows


def _env() -> str:
    """``LCPBENCH_AOT=0 `` where the run was told to use no ahead-of-time kernels (the
    kernel's own row of the phases then reads its time), else empty."""
    return "LCPBENCH_AOT=0 " if os.environ.get("LCPBENCH_AOT") == "0" else ""


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--seed", type=int, default=7)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "mixed-batch.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("mixed_batch.py", argv, _env())
    start = timing_start()
    calls = {"100 mixed scenes": batch(lambda: mixed(a.seed)),
             "100 paper-grid scenes": batch(paper_grid)}
    for kind in KINDS:  # each kind's 25 scenes as a batch of their own
        calls[kind] = batch(lambda kind=kind: of_kind(a.seed, kind))
    calls["building the 100 mixed scenes (outside the clock above)"] = wall(
        lambda: mixed(a.seed))
    got = interleaved(calls, a.rounds)
    lines = ["| batch | median (s) | scenes/s | certified |", "|---|---:|---:|---:|"]
    for name, g in ((n, g) for n, g in got.items() if n not in KINDS):
        med = float(np.median(g["times"]))
        if name.startswith("building"):
            lines.append(f"| {name} | {med:.4f} | | |")
            continue
        ok = sum(r.converged for r in g["payload"])
        lines.append(f"| {name} | {med:.3f} | {100 / med:.0f} | {ok} of 100 |")
    res = got["100 mixed scenes"]["payload"]
    by_kind = collections.defaultdict(list)
    for i, r in enumerate(res):
        by_kind[KINDS[i % 4]].append(r)
    kinds = ["| kind | certified | routes (count) | alone: median (s) | scenes/s |",
             "|---|---:|---|---:|---:|"]
    for kind, rs in by_kind.items():
        routes = collections.Counter(f"{r.route} / {r.engine.split(' (')[0]}" for r in rs)
        med = float(np.median(got[kind]["times"]))
        kinds.append(f"| {kind} | {sum(r.converged for r in rs)} of {len(rs)} | "
                     + ", ".join(f"{k} ({v})" for k, v in routes.most_common())
                     + f" | {med:.4f} | {len(rs) / med:.0f} |")
    phase_rows = phases(a.seed, a.rounds)
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# solve_many on mixed scenes (issue 35, target 3)", "",
        f"Measured {when}; {timing_note(start)} Command: `{cmd}`. Target: 100 mixed scenes "
        "(elastic and "
        "profiled walls, sections, channels) at ≥ 5,000 scenes/s, tol 1e-3. The clock times "
        "`solve_many` alone: each round's fresh scenes are constructed before it starts (their "
        "chains are built inside it; a wall profile's check, in its scene's constructor, "
        "keeps the extremes of the heights it sampled for the chain's build, ~0.07 ms a "
        "batch outside the clock).", "",
        *lines, "", "The mixed batch by kind (alone: the kind's 25 scenes as a batch of their "
        "own, timed in the same rounds):", "", *kinds, "",
        "Where the time of the mixed batch goes (per-phase timers wrapped around the "
        f"functions named in `PHASES`, {a.rounds} batches after the timed rounds; "
        "inclusive: an indented phase is part of the one above it):", "",
        "| phase | ms per batch | calls per batch |", "|---|---:|---:|", *phase_rows, ""])
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
