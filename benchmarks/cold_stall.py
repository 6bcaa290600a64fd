"""Issue 35, target 3: the cold solves that stall, and the margin of the rule that stops them.

Every scene of the corpus that the solve kernel takes (flat walls, rigid or elastic; not
a wall profile) is solved cold by :func:`lcpbench.model.compiled_kernel.solve_chain` at
tol 1e-3 and 1e-9, and its step records (step length t, max|Δα| per outer step) are
read: how each solve ended (converged, or the bail code), how many outer steps it took,
the shortest step of those that converged (the rule's margin: it must never fire on
them), and where the rule (:data:`lcpbench.thresholds.STALL_STEP`, ``STALL_RUN``) fires
or would fire on the others. Run on a tree without the rule, the records are those of
the whole stall and "fires at" says where the rule would have stopped it.

The corpus: ``mixed_batch.mixed(seed)`` for seeds 7, 8, 9, 11, 12, 13 (its elastic,
sections and channel scenes), the paper grid, 300 random rows of 2-4 sections (signed θ
up to 200°, one wall or a channel, N 40-140), 200 elastic and 200 channel scenes
(θ 60-300°), the hard cases of ``hard_cases.py``. ``--wide``: 9000 other scenes instead,
3000 rows, 2000 each elastic and channel (other seeds), 2000 on one flat wall (θ 20-300°,
h 0.3-8 mm, N 8-400, weightless to 8x the paper's weight).

    python benchmarks/cold_stall.py [--wide]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import collections

import numpy as np
from hard_cases import CASES
from mixed_batch import mixed

from lcpbench import ActuatorScene, SectionedScene, thresholds
from lcpbench.model import kernel_call

#: the rule's constants (the values the change measured, where the tree has none yet)
STALL_STEP = getattr(thresholds, "STALL_STEP", 2.0 ** -10)
STALL_RUN = getattr(thresholds, "STALL_RUN", 2)


def paper_grid() -> list:
    return [ActuatorScene(theta=float(t), height=float(h), links=140)
            for t in np.linspace(90, 180, 10) for h in np.linspace(2, 5, 10)]


def random_rows(count: int = 300, seed: int = 35) -> list:
    """Rows of 2-4 sections, each θ in ±200°, boundaries on nodes, N 40-140."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        m, n = int(rng.integers(2, 5)), int(rng.integers(40, 141))
        cuts = np.sort(rng.choice(np.arange(8, n - 7), m - 1, replace=False))
        nk = np.diff(np.concatenate([[0], cuts, [n]]))
        secs = [(float(rng.uniform(-200, 200)), float(k * 30.0 / n)) for k in nk]
        out.append(SectionedScene(sections=secs, height=float(rng.uniform(1, 5)), links=n,
                                  channel=bool(i % 2)))
    return out


def elastic(count: int = 200, seed: int = 36) -> list:
    rng = np.random.default_rng(seed)
    return [ActuatorScene(theta=float(rng.uniform(60, 300)), height=float(rng.uniform(1, 5)),
                          links=int(rng.integers(40, 141)),
                          wall_stiffness=float(10 ** rng.uniform(-3, 9))) for _ in range(count)]


def channel(count: int = 200, seed: int = 37) -> list:
    rng = np.random.default_rng(seed)
    return [ActuatorScene(theta=float(rng.uniform(60, 300)), height=float(rng.uniform(0.6, 5)),
                          links=int(rng.integers(40, 141)), channel=True)
            for _ in range(count)]


def hard() -> list:
    return [ActuatorScene(theta=th, height=h, links=n, weight=w, channel=ch)
            for th, h, n, w, ch, _ in CASES]


def corpus() -> dict:
    out = {f"mixed {s}": mixed(s) for s in (7, 8, 9, 11, 12, 13)}
    out.update({"paper grid": paper_grid(), "rows of sections": random_rows(),
                "elastic walls": elastic(), "channel": channel(), "hard cases": hard()})
    return out


def wide() -> dict:
    rng = np.random.default_rng(104)
    flat = [ActuatorScene(theta=float(rng.uniform(20, 300)), height=float(rng.uniform(0.3, 8)),
                          links=int(rng.integers(8, 401)),
                          weight=float(rng.choice([0, 2.45e-4, 2e-3]))) for _ in range(2000)]
    return {"rows of sections": random_rows(3000, seed=101),
            "elastic walls": elastic(2000, seed=102), "channel": channel(2000, seed=103),
            "flat wall": flat}


#: solve_chain's outcomes other than the bail codes
OUTCOMES = {0: "converged", 1: "out of outer steps (200)", 2: "line search failed",
            3: "no fit between the walls"}


def fires_at(t: np.ndarray) -> int | None:
    """The outer step (1-based) after which the rule stops a cold solve with step
    lengths ``t``, or None."""
    run = 0
    for i, x in enumerate(t):
        run = run + 1 if x <= STALL_STEP else 0
        if run >= STALL_RUN:
            return i + 1
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wide", action="store_true", help="the 9000 other scenes")
    solves = []
    scenes = 0
    for group, members in (wide() if ap.parse_args().wide else corpus()).items():
        for scene in members:
            chain = scene.chain()
            if chain.profiled_walls or not kernel_call.consecutive(chain):
                continue
            scenes += 1
            for tol in (1e-3, 1e-9):
                got, _, _ = kernel_call.call_kernel(chain, tol=tol, max_outer=200, start=None,
                                                    settings="default", args=None,
                                                    newton=False)
                solves.append((group, int(got[0]), np.array(got[6][:, :got[7]])))
    conv = [rec for _, code, rec in solves if code == 0]
    other = [(code, rec) for _, code, rec in solves if code != 0]
    print(f"# Cold solves of the solve kernel: {scenes} scenes, tol 1e-3 and 1e-9, "
          f"{len(solves)} solves; rule: t <= {STALL_STEP:g} for {STALL_RUN} outer steps "
          "running\n")
    print("| ended | solves | outer steps (min-max) | outer steps in all | "
          "rule fires at step (min / median / max) |")
    print("|---|---:|---|---:|---|")
    by_code: dict = collections.defaultdict(list)
    for code, rec in other:
        by_code[code].append(rec)
    by_code[0] = conv
    for code in sorted(by_code):
        recs = by_code[code]
        steps = [r.shape[1] for r in recs]
        fire = [f for f in (fires_at(r[1]) for r in recs) if f is not None]
        at = (f"{min(fire)} / {np.median(fire):g} / {max(fire)} ({len(fire)} of {len(recs)})"
              if fire else "never")
        name = OUTCOMES.get(code) or kernel_call.BAIL_REASONS.get(code, f"code {code}")
        print(f"| {name} | {len(recs)} | {min(steps)}-{max(steps)} | {sum(steps)} | {at} |")
    shortest = collections.Counter(float(r[1].min()) for r in conv if r.shape[1])
    worst = min(shortest)
    print("\nShortest step of the converged solves: "
          + ", ".join(f"{t:g} ({c})" for t, c in sorted(shortest.items())))
    # what the rule reads: the longer of STALL_RUN steps running, at its shortest
    runs = collections.Counter(
        float(min(r[1, i:i + STALL_RUN].max() for i in range(r.shape[1] - STALL_RUN + 1)))
        for r in conv if r.shape[1] >= STALL_RUN)
    closest = min(runs)
    print(f"The longest of {STALL_RUN} steps running, at its shortest, in the converged "
          "solves: " + ", ".join(f"{t:g} ({c})" for t, c in sorted(runs.items())[:4]))
    print(f"Margin: the worst converged solve's shortest step is {worst / STALL_STEP:g} x "
          f"STALL_STEP ({np.log2(worst / STALL_STEP):g} halvings); its {STALL_RUN} steps "
          f"running {closest / STALL_STEP:g} x ({np.log2(closest / STALL_STEP):g} halvings)")
    stalls = [r for _, r in other if r.shape[1]]
    print("Stalls: last step length "
          f"{min(r[1, -1] for r in stalls):.1e}-{max(r[1, -1] for r in stalls):.1e}, "
          f"last max|Δα| {min(r[2, -1] for r in stalls):.2f}-"
          f"{max(r[2, -1] for r in stalls):.2f} rad")


if __name__ == "__main__":
    main()
