"""Issue 19 (targets 2 and 5): how many face solves a perfect warm start would save.

Each scene is solved twice by the numpy driver with the active set
(``make_step_solver("active-set")``, the reference of the compiled walk): once as
usual (step k warm-started from step k − 1's answer), then with step k warm-started
from *its own* answer of the first run, an oracle no solver has. The face solves
per outer step of both bound what a predicted contact set could save: the outer
steps stay the same, every step of the second run takes one face. Counts only,
no times (deterministic; run anywhere). Below ``LARGE_N`` links only: from there the
steps are solved in increments by their own driver (:mod:`lcpbench.model.large_n`).

    python benchmarks/warm_oracle.py [--sizes 140,1000,3000]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse

from lcpbench import ActuatorScene
from lcpbench.model.compiled_driver import run as run_driver
from lcpbench.model.large_n import LARGE_N
from lcpbench.model.step_solver import make_step_solver

SCENES = [(150, 3.0), (120, 2.0), (170, 5.0), (90, 1.0)]  # (θ in °, h in mm)


def face_solves(scene: ActuatorScene, oracle: list | None = None, tol: float = 1e-3):
    """(faces per outer step, the step answers); step k warm-started from
    ``oracle[k]`` where given, else from step k − 1's answer (the driver's)."""
    active_set = make_step_solver("active-set")
    answers = []

    def solver(step, warm):
        k = len(answers)
        answers.append(active_set(step, oracle[k] if oracle and k < len(oracle) else warm))
        return answers[-1]

    run_driver(scene.chain(), solver, tol=tol)
    return [a.iterations for a in answers], answers


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="140,1000,3000", help="links N, comma-separated")
    a = ap.parse_args(argv)
    sizes = [int(x) for x in a.sizes.split(",")]
    if max(sizes) >= LARGE_N:
        ap.error(f"--sizes: each N below {LARGE_N} (the banded path), got {max(sizes)}")
    print("| θ (°) | h (mm) | N | faces per outer step | sum | with the oracle warm start | sum |")
    print("|---|---|---|---|---|---|---|")
    for n in sizes:
        for theta, h in SCENES if n <= 140 else SCENES[:1]:
            scene = ActuatorScene(theta=theta, height=h, links=n)
            usual, answers = face_solves(scene)
            oracle, _ = face_solves(scene, answers)
            print(f"| {theta} | {h} | {n} | {usual} | {sum(usual)} | {oracle} | {sum(oracle)} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
