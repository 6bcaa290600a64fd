"""Issue 39 with walls of any profile: random frictional scenes and paths against
profiled walls, and what became of each state.

Random walls (seed 5 by default): a stenosis (3 mm, 0.2-0.9 mm deep at x 8-22 mm,
2.5-5 mm wide), a straight ramp (2.5-3.5 mm at x = 15 mm, slope ±0.1) or a PCHIP table
(9 heights in 2.2-3.8 mm over x −5…35 mm); 30 % channels (the lower wall the mirror);
θ 120-170° (+40° in a channel), N 20 or 40, μ 0.1-0.8; ends pin–slider, slider–slider or
slider–pin; the path {}, θ + 8°, a pull (0-60 mN, none on a pinned right end), a
release. Every state the judge calls converged is checked again here, independently
of the judge and of lcpbench's frames: with the slopes read from the scene's own
profiles at the answer's x, Coulomb's law node by node in the wall's frame (|T| <= μN;
a node whose slip t·Δp along the wall exceeds 1e-6 ℓ at its cone with T opposite; a
node inside its cone by more than 1e-9 of the force scale not sliding) and, with no end
holding x, P + Σ (N n_x + T t_x) = 0 (to 1e-9 of the force scale). Prints the counts
and the number of converged states that break Coulomb or the balance (target: 0).
Writes nothing; no timings.

    python benchmarks/friction_profile_paths.py [--paths 50] [--seed 5] [--tol 1e-8]
"""

from __future__ import annotations

import argparse
from collections import Counter
from dataclasses import replace

import numpy as np

import lcpbench
from lcpbench import ActuatorScene, WallProfile

ENDS = [("pinned", "slider"), ("slider", "slider"), ("slider", "pinned")]


def random_wall(rng) -> WallProfile:
    kind = rng.integers(3)
    if kind == 0:
        depth, at, width = rng.uniform(0.2, 0.9), rng.uniform(8, 22), rng.uniform(2.5, 5)
        return WallProfile.from_function(
            lambda x: 3.0 - depth * np.exp(-((x - at) / width) ** 2),
            lambda x: depth * 2 * (x - at) / width**2 * np.exp(-((x - at) / width) ** 2),
            name="stenosis")
    if kind == 1:
        h0, slope = rng.uniform(2.5, 3.5), rng.uniform(-0.1, 0.1)
        return WallProfile.from_function(
            lambda x: h0 + slope * (np.asarray(x) - 15.0),
            lambda x: np.full_like(np.asarray(x, float), slope), name="ramp")
    return WallProfile.from_table(np.linspace(-5, 35, 9), rng.uniform(2.2, 3.8, 9))


def breaks_coulomb(res, prev, rtol=1e-9, slip=1e-6) -> bool:
    """Whether a state breaks Coulomb's law in the wall's frame or the balance along x,
    read off with the scene's profiles (see the note); ``prev``: the previous state."""
    up, lo = res.scene.profiles
    mu_up, mu_lo = res.scene.wall_friction
    xf = res.x[1:-1]
    h1 = up.slope(xf)
    l1 = lo.slope(xf) if lo is not None else np.zeros_like(xf)
    Nu = res.forces
    Nl = res.forces_lower if res.forces_lower is not None else np.zeros_like(Nu)
    slope = np.where(Nl > 0, l1, h1)
    c, cu, cl = (np.sqrt(1 + v * v) for v in (slope, h1, l1))
    s = ((res.x - prev.x)[1:-1] + slope * (res.y - prev.y)[1:-1]) / c
    T, limit = res.tangential_forces, mu_up * Nu + mu_lo * Nl
    F = max(float(np.sum(Nu + Nl)), abs(res.pull))
    sliding = np.abs(s) > slip * res.scene.length
    inside = np.abs(T) < limit - rtol * F
    bad = (np.any(np.abs(T) > limit + rtol * F)
           or np.any(np.abs(np.abs(T[sliding]) - limit[sliding]) > rtol * F)
           or np.any(T[sliding] * s[sliding] > rtol * F * np.abs(s[sliding]))
           or np.any(np.abs(s[inside]) > slip * res.scene.length))
    if "pinned" not in (res.scene.left_end, res.scene.right_end):
        fx = Nu * h1 / cu - Nl * l1 / cl + T / c
        bad |= abs(float(np.sum(fx)) + res.pull) > rtol * F
    return bool(bad)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=50)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--tol", type=float, default=1e-8)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    count, reasons, broken = Counter(), Counter(), 0
    for _ in range(args.paths):
        wall = random_wall(rng)
        channel = bool(rng.random() < 0.3)
        ends = ENDS[rng.integers(3)]
        theta = float(rng.uniform(120, 170)) + (40.0 if channel else 0.0)
        scene = ActuatorScene(theta=theta, wall_profile=wall, links=int(rng.choice([20, 40])),
                              channel=channel, left_end=ends[0], right_end=ends[1],
                              friction=float(rng.uniform(0.1, 0.8)))
        pull = float(rng.uniform(0.0, 0.06)) if ends[1] == "slider" else 0.0
        prev = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                      right_end="pinned"), tol=args.tol)
        states = [{}, {"theta": theta + 8}, {"pull": pull}, {"pull": 0.0}]
        for res in lcpbench.solve_path(scene, states, tol=args.tol):
            count[res.converged] += 1
            if res.converged:
                broken += breaks_coulomb(res, prev)
                prev = res
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
