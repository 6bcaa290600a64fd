"""Heavy chains (issue 19, target 8): random scenes with wℓ³/EI from 40 to 10⁴.

Each scene is solved by ``lcpbench.solve`` (default back-end and engine) and
by the independent energy minimisation
(:func:`lcpbench.reference.energy.minimise_energy`, SLSQP + Newton
polish in the link angles). Reported: converged count, outer iterations,
and the total-force difference to the reference (upper and lower wall, the
larger), relative to max(|F_ref|, |F_ref lower|, EI/ℓ²). Half the scenes have one wall at +h (the chain hangs off
it), half are channels (the chain drapes on the lower wall).

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 PYTHONPATH=src \\
        python benchmarks/heavy_chains.py --count 60 --links 140 --label after

Run with PYTHONPATH pointing at another checkout's src for a "before" row.
Appends a section to results/heavy-chains.md (``--out``).
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
import subprocess
import time

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import timing_note, timing_start
from lcpbench.reference.energy import minimise_energy

ELL, EI = 30.0, 32.01


def scenes(count: int, links: int, seed: int):
    rng = np.random.default_rng(seed)
    for k in range(count):
        q = 10 ** rng.uniform(np.log10(40.0), 4.0)
        theta, h = rng.uniform(60, 180), rng.uniform(0.5, 8.0)
        yield q, ActuatorScene(theta=theta, height=h, links=links, weight=q * EI / ELL**3,
                               channel=bool(k % 2))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--count", type=int, default=60)
    ap.add_argument("--links", type=int, default=140)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--label", default="run")
    ap.add_argument("--out", default="results/heavy-chains.md")
    a = ap.parse_args()
    start = timing_start()
    rows, conv, outer, errs, bad_ref = [], 0, [], [], 0
    t_all = time.perf_counter()
    for q, sc in scenes(a.count, a.links, a.seed):
        t0 = time.perf_counter()
        r = lcpbench.solve(sc)
        dt = time.perf_counter() - t0
        ref = minimise_energy(sc)
        lo = float(np.sum(r.forces_lower)) if r.forces_lower is not None else 0.0
        ref_lo = float(np.sum(ref.forces_lower)) if ref.forces_lower is not None else 0.0
        err = max(abs(r.total_force - ref.total_force), abs(lo - ref_lo)) / max(
            abs(ref.total_force), abs(ref_lo), EI / ELL**2)
        conv += bool(r.converged)
        if r.converged:
            outer.append(r.outer_iterations)
            errs.append(err)
        bad_ref += not ref.success
        rows.append(f"| {q:.0f} | {sc.theta:.1f} | {sc.height:.2f} | {sc.channel} | "
                    f"{r.converged} | {r.outer_iterations} | {r.total_force:.6g} | {lo:.6g} | "
                    f"{ref.total_force:.6g} | {ref_lo:.6g} | {err:.1e} | {dt * 1e3:.0f} |")
        print(rows[-1], flush=True)
    head = (f"\n## {a.label}: {a.count} scenes, N = {a.links}, seed {a.seed}\n\n"
            f"lcpbench from `{os.path.dirname(lcpbench.__file__)}`, "
            f"git {subprocess.run(['git', 'rev-parse', '--short', 'HEAD'], capture_output=True, text=True, cwd=os.path.dirname(lcpbench.__file__)).stdout.strip()}, "
            f"{time.perf_counter() - t_all:.0f} s in all; {timing_note(start)}\n\n"
            f"- converged: **{conv} / {a.count}**\n"
            f"- outer iterations of the converged: max {max(outer, default=0)}, "
            f"median {float(np.median(outer)) if outer else 0:.0f}\n"
            f"- largest total-force error vs the reference, relative over the converged: "
            f"{max(errs, default=float('nan')):.1e}\n"
            f"- reference (minimise_energy) not certified: {bad_ref}\n\n"
            "| wℓ³/EI | θ (°) | h (mm) | channel | converged | outer | F (N) | F lower (N) "
            "| F_ref (N) | F_ref lower (N) | rel. error | time (ms) |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    with open(a.out, "a") as f:
        if f.tell() == 0:
            f.write("# Heavy chains (issue 19, target 8)\n\nWritten by "
                    "`benchmarks/heavy_chains.py`.\n")
        f.write(head + "\n".join(rows) + "\n")
    print(head)


if __name__ == "__main__":
    main()
