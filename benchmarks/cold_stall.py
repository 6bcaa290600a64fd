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
(θ 60-300°), the hard cases of ``hard_cases.py``.

    python benchmarks/cold_stall.py
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import collections

import numpy as np
from hard_cases import CASES
from mixed_batch import mixed

from lcpbench import ActuatorScene, SectionedScene, thresholds
from lcpbench.model import kernel_call

#: the rule's constants (the values the change measured, where the tree has none yet)
STALL_STEP = getattr(thresholds, "STALL_STEP", 2.0 ** -8)
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
    solves = []
    scenes = 0
    for group, members in corpus().items():
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
        name = ("converged" if code == 0 else kernel_call.BAIL_REASONS.get(code, f"code {code}"))
        print(f"| {name} | {len(recs)} | {min(steps)}-{max(steps)} | {sum(steps)} | {at} |")
    shortest = collections.Counter(float(r[1].min()) for r in conv if r.shape[1])
    worst = min(shortest)
    print("\nShortest step of the converged solves: "
          + ", ".join(f"{t:g} ({c})" for t, c in sorted(shortest.items())))
    print(f"Margin: the worst converged solve's shortest step is {worst / STALL_STEP:g} x "
          f"STALL_STEP ({np.log2(worst / STALL_STEP):g} halvings)")
    stalls = [r for _, r in other if r.shape[1]]
    print("Stalls: last step length "
          f"{min(r[1, -1] for r in stalls):.1e}-{max(r[1, -1] for r in stalls):.1e}, "
          f"last max|Δα| {min(r[2, -1] for r in stalls):.2f}-"
          f"{max(r[2, -1] for r in stalls):.2f} rad")


if __name__ == "__main__":
    main()
