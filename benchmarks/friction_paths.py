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
Coulomb (target: 0); with ``--out`` (``--force`` to overwrite) also writes them as a
results file, with the machine and the load (the issue's run, 200 scenes and paths of
4 states: ``--paths 200 --seed 39 --out results/friction/paths.md``).

    python benchmarks/friction_paths.py [--paths 60] [--seed 7] [--tol 1e-8]
        [--out FILE.md] [--force]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import time
from collections import Counter
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.model.judge import NODE_SHARE as JUDGE_SHARE
from lcpbench.model.judge import force_tol

ENDS = [("pinned", "slider"), ("slider", "slider"), ("slider", "pinned"),
        ("pinned", "free"), ("slider", "free"), ("free", "pinned"), ("free", "slider")]


def broken_conditions(res, rtol=1e-9, slip=1e-6) -> list[str]:
    """The conditions a state breaks (see the note): "cone", "slide" (a sliding node off
    its cone or with T along its slip), "stick" (a node inside its cone that slides),
    "balance" (Σ T + P with no end holding x); forces to ``rtol`` of the largest of ΣN
    and |P|, slips to ``slip`` ℓ."""
    mu_up, mu_lo = res.scene.wall_friction
    lower = res.forces_lower if res.forces_lower is not None else 0.0
    limit = mu_up * res.forces + mu_lo * lower
    T, s = res.tangential_forces, res.slip
    F = max(float(np.sum(res.forces + lower)), abs(res.pull))
    sliding = np.abs(s) > slip * res.scene.length
    inside = np.abs(T) < limit - rtol * F
    out = []
    if np.any(np.abs(T) > limit + rtol * F):
        out.append("cone")
    if (np.any(np.abs(np.abs(T[sliding]) - limit[sliding]) > rtol * F)
            or np.any(T[sliding] * s[sliding] > rtol * F * np.abs(s[sliding]))):
        out.append("slide")
    if np.any(np.abs(s[inside]) > slip * res.scene.length):
        out.append("stick")
    if ("pinned" not in (res.scene.left_end, res.scene.right_end)
            and abs(float(np.sum(T)) + res.pull) > rtol * F):
        out.append("balance")
    return out


def breaks_coulomb(res, rtol=1e-9, slip=1e-6) -> bool:
    """Whether a state breaks Coulomb's law or the balance along x (see the note)."""
    return bool(broken_conditions(res, rtol, slip))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=60)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--out", default=None, help="also write the counts here (markdown)")
    ap.add_argument("--force", action="store_true")
    args = ap.parse_args(argv)
    if args.out:
        refuse_overwrite([args.out], args.force)
    cmd = command_line("friction_paths.py", argv)
    start, t0 = timing_start(), time.perf_counter()
    rng = np.random.default_rng(args.seed)
    judge_rtol = JUDGE_SHARE * force_tol(args.tol)
    count, reasons = Counter(), Counter()
    broken = {"1e-9": Counter(), "judge": Counter()}  # condition -> states
    where: dict = {}  # path.state -> the conditions it breaks at 1e-9
    for index in range(args.paths):
        channel = bool(rng.random() < 0.4)
        ends = ENDS[rng.integers(7 if channel else 3)]
        theta = float(rng.uniform(100, 170))
        scene = ActuatorScene(theta=theta, height=float(rng.uniform(1.0, 5.0)),
                              links=int(rng.choice([20, 40])), channel=channel,
                              left_end=ends[0], right_end=ends[1],
                              friction=float(rng.uniform(0.05, 0.8)))
        pull = float(rng.uniform(0.0, 0.15)) if ends[1] != "pinned" else 0.0
        states = [{}, {"theta": theta + 10}, {"pull": pull}, {"pull": 0.0}]
        for si, res in enumerate(lcpbench.solve_path(scene, states, tol=args.tol)):
            count[res.converged] += 1
            if res.converged:
                for key, rtol in (("1e-9", 1e-9), ("judge", judge_rtol)):
                    bad = broken_conditions(res, rtol)
                    broken[key].update(bad)
                    broken[key]["any"] += bool(bad)
                    if bad and key == "1e-9":
                        where[f"{index}.{si}"] = bad
            else:
                reasons[res.reason.split(" (")[0].split(":")[0]] += 1
    total = sum(count.values())
    lines = [f"{total} states in {args.paths} paths (seed {args.seed}, tol {args.tol:g}): "
             f"{count[True]} converged, {count[False]} not"]
    lines += [f"  {n:4d}  {why}" for why, n in reasons.most_common()]
    for key, label in (("1e-9", "1e-9 of the force"),
                       ("judge", f"the judge's ε_F = {judge_rtol:g} of the force")):
        b = broken[key]
        lines.append(f"converged states that break Coulomb or the balance, at {label}: "
                     f"{b['any']} (cone {b['cone']}, slide {b['slide']}, stick "
                     f"{b['stick']}, balance {b['balance']})")
    if where:
        lines.append("  at 1e-9: " + "; ".join(f"{k} {', '.join(v)}" for k, v in where.items()))
    print("\n".join(lines))
    if args.out:
        text = [
            "# Random frictional paths: converged answers that break Coulomb "
            "(issue 39, target 4)", "",
            f"{datetime.now(timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}; `{cmd}`; "
            f"{timing_note(start)} ({time.perf_counter() - t0:.0f} s in all).", "",
            f"{args.paths} random scenes (θ 100-170°, h 1-5 mm, N 20 or 40, μ 0.05-0.8, "
            "40 % channels; every end pair, free ends in channels), each along the path "
            "{}, θ + 10°, a pull of 0-150 mN (none on a pinned right end), a release. "
            "Every state the judge calls converged is checked again outside the judge "
            "(`breaks_coulomb`): |T| <= μN, a node sliding more than 1e-6 ℓ at its cone "
            "with T opposite, a node inside its cone by more than 1e-9 of the force not "
            "sliding, and Σ T + P = 0 where no end holds x; to 1e-9 of the force and to "
            "the judge's own ε_F (the tolerance of its verdict). Target: 0 break. The "
            "balance is held by the outer loop's stopping rule: Σ T + P = k_τ τ with "
            "τ < tol·ℓ, so |Σ T + P| < tol·EI/ℓ² (docs/friction.md, \"The translation "
            "τ\"), which can exceed 1e-9 of a small force.", "",
            "```", *lines, "```"]
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text("\n".join(text) + "\n")
    return 0 if broken["judge"]["any"] == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
