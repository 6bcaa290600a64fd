"""Issue 38, targets 1, 2 and 4: sensitivities against finite differences, and the cost
of sensitivities and inverse queries.

1. Random actuator scenes (θ ∈ [100°, 175°], h ∈ [1.5, 6] mm, N ∈ {40, 140}, a channel
   in a third, elastic walls in a third with k = 10^U(−1, 4) N/mm², weight 1× or 5× the
   paper's; numpy default_rng(seed)), solved at tol 1e-11; those touching a wall with a
   stable contact set (no node at a change of it) are kept, up to ``--scenes``. For
   each parameter, the total force's derivative against the central difference of two
   solves (relative step 1e-4, started from the answer), kept only where both keep
   the centre's contact set (away from a change of it).
2. At N = 140 (θ = 150°, h = 3 mm, tol 1e-10; a row of two sections in a channel; a
   stenosis, a wall profile), interleaved: ``lcpbench.solve``, ``sensitivities`` (all
   parameters, and the first alone); and ``lcpbench.design`` queries (forward solves
   and wall time).
4. The design answers' force error and the force 0.01° beyond.

Writes ``results/design-targets.md`` (``--out``; not overwritten without ``--force``).

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/design_targets.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from perf import interleaved, wall  # (benchmarks/ is the script's directory)

import lcpbench
from lcpbench import ActuatorScene, SectionedScene
from lcpbench.bench.machine import refuse_overwrite, timing_note, timing_start
from lcpbench.model.sensitivity import sensitivities
from lcpbench.problems.walls import WallProfile
from lcpbench.studies.design import design

ROOT = Path(__file__).resolve().parents[1]
ATTR = {"theta_deg": "theta", "height_mm": "height", "EI": "EI", "weight": "weight",
        "length_mm": "length", "wall_stiffness": "wall_stiffness"}
STEP = 1e-4


def _contacts(r) -> int:
    return int(np.count_nonzero(r.forces > 0)) + (
        0 if r.forces_lower is None else int(np.count_nonzero(r.forces_lower > 0)))


def target1(n_scenes: int, seed: int) -> tuple[list[str], dict]:
    rng = np.random.default_rng(seed)
    worst: dict[str, float] = {}
    errors: list[float] = []
    kept = tried = skipped_fd = 0
    while kept < n_scenes and tried < 20 * n_scenes:
        tried += 1
        kw = dict(theta=float(rng.uniform(100, 175)), height=float(rng.uniform(1.5, 6.0)),
                  links=int(rng.choice([40, 140])), channel=bool(rng.random() < 1 / 3),
                  weight=0.000245 * float(rng.choice([1.0, 5.0])))
        if rng.random() < 1 / 3:
            kw["wall_stiffness"] = float(10 ** rng.uniform(-1, 4))
        scene = ActuatorScene(**kw)
        res = lcpbench.solve(scene, tol=1e-11)
        if not res.converged or res.total_force <= 0:
            continue
        sens = sensitivities(res)
        if sens.one_sided.size:
            continue
        kept += 1
        for p in sens.wrt:
            v = getattr(scene, ATTR[p])
            h = STEP * abs(v)
            start = None if p == "length_mm" else res
            up = lcpbench.solve(dataclasses.replace(scene, **{ATTR[p]: v + h}), tol=1e-11,
                                start=start)
            dn = lcpbench.solve(dataclasses.replace(scene, **{ATTR[p]: v - h}), tol=1e-11,
                                start=start)
            if not (up.converged and dn.converged) or _contacts(up) != _contacts(res) \
                    or _contacts(dn) != _contacts(res):
                skipped_fd += 1
                continue
            fd = (up.total_force - dn.total_force) / (2 * h)
            diff = abs(sens.total_force[p] - fd)
            err = diff / abs(fd) if fd else np.inf
            # the same in the derivative's natural unit, F per relative change of p
            scaled = diff * abs(v) / res.total_force
            elastic = abs(fd * v / res.total_force)  # the derivative's size in that unit
            errors.append((err, scaled, elastic))
            w = worst.setdefault(p, [0.0, 0.0, 0.0])
            w[0], w[1] = max(w[0], err), max(w[1], scaled)
            if elastic >= 1e-3:
                w[2] = max(w[2], err)
    e = np.array(errors)
    big = e[:, 2] >= 1e-3
    lines = ["| parameter | largest relative difference | largest, where p ∂F/∂p ≥ 1e-3 F | "
             "largest in units of F per relative change of p |", "|---|---:|---:|---:|",
             *(f"| {p} | {w[0]:.1e} | {w[2]:.1e} | {w[1]:.1e} |" for p, w in worst.items())]
    return lines, {"kept": kept, "tried": tried, "pairs": len(e), "skipped_fd": skipped_fd,
                   "median": float(np.median(e[:, 0])), "p99": float(np.percentile(e[:, 0], 99)),
                   "max": float(e[:, 0].max()), "within": float(np.mean(e[:, 0] <= 1e-6)),
                   "within_big": float(np.mean(e[big, 0] <= 1e-6)), "big": int(big.sum()),
                   "scaled_max": float(e[:, 1].max())}


def _moved(scene, p, d):
    """``scene`` with parameter ``p`` moved by ``d``: a row of sections' θ_k, EI_k, w_k
    (``name[k]``), its height or every length scaled (``length_mm``); a profiled wall's
    ``height_mm`` by the profile moved up by d (no channel here)."""
    if isinstance(scene, SectionedScene):
        secs = list(scene.sections)
        if p == "height_mm":
            return dataclasses.replace(scene, height=scene.height + d)
        if p == "length_mm":
            f = 1 + d / scene.length
            return dataclasses.replace(scene, length=None, sections=[
                dataclasses.replace(x, length=x.length * f) for x in secs])
        name, k = p.split("[")
        attr = {"theta_deg": "theta", "EI": "EI", "weight": "weight"}[name]
        k = int(k[:-1])
        secs[k] = dataclasses.replace(secs[k], **{attr: getattr(secs[k], attr) + d})
        return dataclasses.replace(scene, sections=secs)
    if p == "height_mm":
        w = scene.wall_profile
        return dataclasses.replace(scene, wall_profile=WallProfile.from_function(
            lambda x: w(x) + d, w.slope, w.curvature, x_range=w.x_range))
    return dataclasses.replace(scene, **{ATTR[p]: getattr(scene, ATTR[p]) + d})


def _size(scene, p):
    if isinstance(scene, SectionedScene) and "[" in p:
        name, k = p.split("[")
        return getattr(scene.sections[int(k[:-1])],
                       {"theta_deg": "theta", "EI": "EI", "weight": "weight"}[name])
    if p == "height_mm" and getattr(scene, "wall_profile", None) is not None:
        return 3.0
    return getattr(scene, ATTR[p])


def target1_more(n_scenes: int, seed: int) -> tuple[list[str], dict]:
    """Rows of sections and walls of any profile: random scenes, every parameter against
    central differences (relative step 1e-4, the weights 1e-2), tol 1e-11."""
    rng = np.random.default_rng(seed + 1)
    rows, kept, tried, skipped = [], {"sections": 0, "profile": 0}, 0, 0
    while min(kept.values()) < n_scenes and tried < 20 * n_scenes:
        tried += 1
        if kept["sections"] <= kept["profile"]:
            kind = "sections"
            k = int(rng.choice([2, 3]))
            secs = [(float(rng.uniform(90, 170) * rng.choice([1, -1] if kk else [1])),
                     30.0 / k, float(rng.uniform(20, 50)), 2.45e-4 * float(rng.choice([1, 5])))
                    for kk in range(k)]
            scene = SectionedScene(sections=secs, height=float(rng.uniform(1.0, 4.0)),
                                   links=60 * k // 2 * 2, channel=bool(rng.random() < 0.5))
        else:
            kind = "profile"
            depth, centre = float(rng.uniform(0.2, 1.0)), float(rng.uniform(8, 22))
            width, h0 = float(rng.uniform(2, 6)), float(rng.uniform(2.5, 4.5))
            wall = WallProfile.from_function(
                lambda x, h0=h0, d=depth, c=centre, w=width: h0 - d * np.exp(-((x - c) / w) ** 2),
                lambda x, d=depth, c=centre, w=width: 2 * d * (x - c) / w**2
                * np.exp(-((x - c) / w) ** 2), x_range=(-5.0, 40.0), name="bump")
            scene = ActuatorScene(theta=float(rng.uniform(120, 175)), links=int(rng.choice(
                [60, 140])), wall_profile=wall, weight=2.45e-4 * float(rng.choice([1, 5])))
        res = lcpbench.solve(scene, tol=1e-11)
        if not res.converged or res.total_force <= 0:
            continue
        sens = sensitivities(res)
        if sens.one_sided.size:
            continue
        kept[kind] += 1
        for p in sens.wrt:
            d = (1e-2 if p.startswith("weight") else 1e-4) * abs(_size(scene, p))
            start = None if p == "length_mm" else res
            up = lcpbench.solve(_moved(scene, p, d), tol=1e-11, start=start)
            dn = lcpbench.solve(_moved(scene, p, -d), tol=1e-11, start=start)
            if not (up.converged and dn.converged) or _contacts(up) != _contacts(res) \
                    or _contacts(dn) != _contacts(res):
                skipped += 1
                continue
            fd = (up.total_force - dn.total_force) / (2 * d)
            err = abs(sens.total_force[p] - fd) / abs(fd) if fd else np.inf
            rows.append((kind, p.split("[")[0], err))
    lines = ["| scenes | parameter | pairs | median relative difference | within 1e-6 | "
             "largest |", "|---|---|---:|---:|---:|---:|"]
    for kind in ("sections", "profile"):
        for name in dict.fromkeys(r[1] for r in rows if r[0] == kind):
            e = np.array([r[2] for r in rows if r[0] == kind and r[1] == name])
            lines.append(f"| {kind} | {name} | {e.size} | {np.median(e):.1e} | "
                         f"{np.mean(e <= 1e-6):.0%} | {e.max():.1e} |")
    e = np.array([r[2] for r in rows])
    return lines, {"kept": kept, "tried": tried, "skipped": skipped, "pairs": e.size,
                   "within": float(np.mean(e <= 1e-6)), "median": float(np.median(e))}


#: the scenes of target 2 (N = 140): the paper's, a row of two sections, a stenosis
STENOSIS = WallProfile.from_function(
    lambda x: 3.0 - 0.8 * np.exp(-((x - 14.0) / 3.0) ** 2),
    lambda x: 1.6 * (x - 14.0) / 9.0 * np.exp(-((x - 14.0) / 3.0) ** 2), name="stenosis")
COST_SCENES = {
    "one wall": ActuatorScene(theta=150, height=3.0, links=140),
    "two sections, channel": SectionedScene(sections=[(150.0, 15.0), (-150.0, 15.0)],
                                            height=1.0, links=140, channel=True),
    "wall profile (stenosis)": ActuatorScene(theta=150, links=140, wall_profile=STENOSIS),
}


def target2(rounds: int) -> list[str]:
    lines = ["| scene | call | median (ms) | × its solve |", "|---|---|---:|---:|"]
    for label, scene in COST_SCENES.items():
        res = lcpbench.solve(scene, tol=1e-10)
        first = sensitivities(res).wrt[0]
        calls = {"lcpbench.solve (tol 1e-10)": lambda sc=scene: lcpbench.solve(sc, tol=1e-10),
                 "sensitivities, all parameters": lambda r=res: sensitivities(r),
                 f"sensitivities, {first} alone": lambda r=res, p=first: sensitivities(
                     r, wrt=(p,))}
        times = {name: g["times"] for name, g in interleaved(
            {name: wall(call) for name, call in calls.items()}, rounds).items()}
        base = float(np.median(times["lcpbench.solve (tol 1e-10)"]))
        for name, t in times.items():
            lines.append(f"| {label} | {name} | {1e3 * np.median(t):.3f} | "
                         f"{np.median(t) / base:.2f} |")
    return lines


def design_rows(rounds: int) -> list[str]:
    lines = ["| query | answer θ (deg) | force at it (N) | relative to the limit | "
             "+0.01° (N) | solves | median time (ms) |", "|---|---:|---:|---:|---:|---:|---:|"]
    for kw in (dict(max_force=0.05), dict(max_force=0.3), dict(min_force=0.2),
               dict(max_force=0.05, peak=True)):
        scene = ActuatorScene(theta=150, height=4.0, links=140)
        times = []
        for _ in range(rounds):
            t0 = time.perf_counter()
            got = design(scene, **kw)
            times.append(time.perf_counter() - t0)
        limit = kw.get("max_force", kw.get("min_force"))
        name = ", ".join(f"{k}={v}" for k, v in kw.items())
        lines.append(f"| {name} | {got.theta_deg:.6f} | {got.value:.9g} | "
                     f"{got.value / limit - 1:+.1e} | {got.beyond:.9g} | {got.solves} | "
                     f"{1e3 * np.median(times):.2f} |")
    return lines


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenes", type=int, default=200)
    p.add_argument("--seed", type=int, default=38)
    p.add_argument("--more", type=int, default=40,
                   help="random rows of sections and profiled scenes, each")
    p.add_argument("--rounds", type=int, default=31)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "design-targets.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    start = timing_start()
    t1, s1 = target1(a.scenes, a.seed)
    t1b, s1b = target1_more(a.more, a.seed)
    t2 = target2(a.rounds)
    t4 = design_rows(max(3, a.rounds // 5))
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# Sensitivities and inverse queries (issue 38, targets 1, 2 and 4)", "",
        f"Measured {when}; {timing_note(start)} Command: `python benchmarks/design_targets.py "
        f"--scenes {a.scenes} --seed {a.seed} --more {a.more} --rounds {a.rounds} --force`.", "",
        "## Target 1: sensitivities against central differences", "",
        f"{s1['kept']} random scenes with a stable contact set (of {s1['tried']} drawn; the "
        "rest touch no wall, do not converge at tol 1e-11 or have a node at a change of "
        f"contact set), {s1['pairs']} derivative pairs ({s1['skipped_fd']} differences "
        "dropped where a moved scene changed its contact set). Relative difference of the "
        f"total force's derivative: median {s1['median']:.1e}, 99th percentile "
        f"{s1['p99']:.1e}, largest {s1['max']:.1e}; {s1['within']:.1%} within 1e-6, "
        f"{s1['within_big']:.1%} of the {s1['big']} whose derivative is not tiny "
        "(|p ∂F/∂p| ≥ 1e-3 F). In units of F per relative change of p the largest "
        f"difference is {s1['scaled_max']:.1e}. The central differences carry O(δ²) and "
        "the solves' error over δ (δ = 1e-4 relative, tol 1e-11): where a derivative is "
        "tiny (the wall stiffness near the rigid limit, ∂F/∂k ~ 1/k², or the weight) "
        "that error is larger than 1e-6 of it, and the differences move by as much "
        "between δ = 1e-4, 1e-3 and 1e-2 as they differ from the implicit one; they bound "
        "the error from above.", "", *t1, "",
        f"Rows of sections ({s1b['kept']['sections']}: 2 or 3 sections, θ_k in ±[90°, "
        "170°], EI_k in [20, 50] N mm², w 1× or 5×, h in [1, 4] mm, a channel in half) and "
        f"walls of any profile ({s1b['kept']['profile']}: a Gaussian narrowing of random "
        "depth, centre and width, θ in [120°, 175°], N 60 or 140), drawn from seed + 1 "
        f"({s1b['tried']} drawn), {s1b['pairs']} pairs ({s1b['skipped']} dropped where a "
        "moved scene changed its contact set); central differences with relative steps "
        f"1e-4 (weights 1e-2): median {s1b['median']:.1e}, {s1b['within']:.1%} within 1e-6.",
        "", *t1b, "",
        "## Target 2: cost", "", *t2, "",
        "## Targets 2 and 4: inverse queries (θ from 150°, h = 4 mm, N = 140)", "", *t4, ""])
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
