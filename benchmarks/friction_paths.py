"""Issue 39, target 4 (first part): random frictional scenes and paths, and what became
of each state.

Random scenes (seed 7 by default: θ 100-170°, h 1-5 mm, N 20 or 40, μ 0.05-0.8, 40 %
channels; ends pin–slider, slider–slider, slider–pin, and in channels pin–free,
slider–free, free–pin and free–slider) along the path {}, θ + 10°, a pull (0-150 mN, none on a pinned right end),
a release. Every state the judge calls converged is checked again here, independently
of the judge: Coulomb's law node by node (|T| <= μN; a node that slides more than
1e-6 ℓ at its cone with T opposite; a node inside its cone by more than 1e-9 of the
force scale not sliding) and, with no end holding x, Σ T + P = 0. Prints the counts
(converged, the reasons of the others) and the number of converged states that break
Coulomb (target: 0). Writes nothing; no timings.

    python benchmarks/friction_paths.py [--paths 60] [--seed 7] [--tol 1e-8]
"""

from __future__ import annotations

import argparse
from collections import Counter

import numpy as np

import lcpbench
from lcpbench import ActuatorScene

ENDS = [("pinned", "slider"), ("slider", "slider"), ("slider", "pinned"),
        ("pinned", "free"), ("slider", "free"), ("free", "pinned"), ("free", "slider")]


def breaks_coulomb(res, rtol=1e-9, slip=1e-6) -> bool:
    """Whether a state breaks Coulomb's law or the balance along x (see the note)."""
    mu_up, mu_lo = res.scene.wall_friction
    lower = res.forces_lower if res.forces_lower is not None else 0.0
    limit = mu_up * res.forces + mu_lo * lower
    T, s = res.tangential_forces, res.slip
    F = max(float(np.sum(res.forces + lower)), abs(res.pull))
    sliding = np.abs(s) > slip * res.scene.length
    inside = np.abs(T) < limit - rtol * F
    bad = (np.any(np.abs(T) > limit + rtol * F)
           or np.any(np.abs(np.abs(T[sliding]) - limit[sliding]) > rtol * F)
           or np.any(T[sliding] * s[sliding] > rtol * F * np.abs(s[sliding]))
           or np.any(np.abs(s[inside]) > slip * res.scene.length))
    if "pinned" not in (res.scene.left_end, res.scene.right_end):
        bad |= abs(float(np.sum(T)) + res.pull) > rtol * F
    return bool(bad)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=60)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--tol", type=float, default=1e-8)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    count, reasons, broken = Counter(), Counter(), 0
    for _ in range(args.paths):
        channel = bool(rng.random() < 0.4)
        ends = ENDS[rng.integers(7 if channel else 3)]
        theta = float(rng.uniform(100, 170))
        scene = ActuatorScene(theta=theta, height=float(rng.uniform(1.0, 5.0)),
                              links=int(rng.choice([20, 40])), channel=channel,
                              left_end=ends[0], right_end=ends[1],
                              friction=float(rng.uniform(0.05, 0.8)))
        pull = float(rng.uniform(0.0, 0.15)) if ends[1] != "pinned" else 0.0
        states = [{}, {"theta": theta + 10}, {"pull": pull}, {"pull": 0.0}]
        for res in lcpbench.solve_path(scene, states, tol=args.tol):
            count[res.converged] += 1
            if res.converged:
                broken += breaks_coulomb(res)
            else:
                reasons[res.reason.split(" (")[0].split(":")[0]] += 1
    total = sum(count.values())
    print(f"{total} states in {args.paths} paths (seed {args.seed}, tol {args.tol:g}): "
          f"{count[True]} converged, {count[False]} not")
    for why, n in reasons.most_common():
        print(f"  {n:4d}  {why}")
    print(f"converged states that break Coulomb or the balance: {broken}")
    return 0 if broken == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
