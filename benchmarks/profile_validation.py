"""Walls of any profile (issue 17, item 3): validation, convergence and cost.

For each profile scene of ``tests/model/test_profile.py`` (SCENES: stenoses,
ramps, bends, smoothed steps; upper wall, channel, lower wall):

- the relative error of the total force (and the lower wall's, in a channel)
  and the shape error (max |Δx|, |Δy| over ℓ) of ``lcpbench.solve`` at tol
  1e-10 against the independent energy minimisation with h(x) rows
  (``minimise_energy``: SLSQP + Newton polish on the KKT system);
- outer iterations at tol 1e-3 (the paper's) and 1e-10, beside those of the
  flat wall at the profile's lowest height (same θ, N, tol);
- every installed back-end on two scenes (a stenosis, a channel whose lower
  wall is a ramp; another back-end runs the compiled driver, its walls a profile):
  converged and within the judge's rule of the reference,
  not converged, or converged and wrong (must be 0);
- the cost per outer iteration at N = 140 (the default compiled solve for both): a
  stenosis against the flat wall, median of interleaved repeats, one BLAS
  thread, the load recorded.

It also draws results/profile-stenosis.png (examples/profiles/stenosis.csv, the
paper's default actuator, θ = 150°, N = 140)::

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/profile_validation.py \
        --out results/profile-validation.md --picture results/profile-stenosis.png
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
import importlib.util
import time
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.api import solve_internal
from lcpbench.bench.machine import timing_note, timing_start
from lcpbench.problems.walls import WallProfile, load_profile_csv
from lcpbench.reference.energy import minimise_energy
from lcpbench.solvers.registry import available_backends

ROOT = Path(__file__).resolve().parents[1]


def _test_module():
    spec = importlib.util.spec_from_file_location("test_profile",
                                                  ROOT / "tests" / "model" / "test_profile.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _flat_height(profile: WallProfile, scene: ActuatorScene) -> float:
    return float(np.min(profile(np.linspace(*scene.x_reach, 2001))))


def validation(mod) -> tuple[list[str], dict]:
    lines = ["| scene | θ | F (mN) | rel. error F | rel. error lower F | shape error / ℓ | "
             "outer 1e-3 (flat) | outer 1e-10 (flat) |", "|---|---|---|---|---|---|---|---|"]
    worst = {"force": 0.0, "shape": 0.0, "n": 0}
    for p in mod.SCENES:
        theta, profile, channel, weight, lower = p.values
        scene = mod._scene(theta, profile, channel, weight, lower)
        res = lcpbench.solve(scene, tol=1e-10)
        coarse = lcpbench.solve(scene, tol=1e-3)
        ref = minimise_energy(scene)
        flat = ActuatorScene(theta=theta, height=_flat_height(profile, scene), links=mod.LINKS,
                             channel=channel, **({} if weight is None else {"weight": weight}))
        f_fine = solve_internal(flat, tol=1e-10)
        f_coarse = solve_internal(flat, tol=1e-3)
        F0 = max(abs(ref.total_force), scene.EI / scene.length**2)
        e_f = abs(res.total_force - ref.total_force) / F0
        e_lo = (abs(res.forces_lower.sum() - ref.forces_lower.sum()) / F0
                if channel else float("nan"))
        e_s = max(np.max(np.abs(res.y - ref.y)), np.max(np.abs(res.x - ref.x))) / scene.length
        ok = res.converged and ref.success
        worst["force"] = max(worst["force"], e_f, 0.0 if np.isnan(e_lo) else e_lo)
        worst["shape"] = max(worst["shape"], e_s)
        worst["n"] += 1
        F = res.total_force + (res.forces_lower.sum() if channel else 0.0)
        lines.append(f"| {p.id}{'' if ok else ' (NOT converged)'} | {theta} | {1e3 * F:.4g} | "
                     f"{e_f:.1e} | {'' if np.isnan(e_lo) else f'{e_lo:.1e}'} | {e_s:.1e} | "
                     f"{coarse.outer_iterations}{'' if coarse.converged else ' refused*'} "
                     f"({f_coarse.outer_iterations}) | "
                     f"{res.outer_iterations} ({f_fine.outer_iterations}) |")
    return lines, worst


def backends(mod) -> list[str]:
    cases = {
        "stenosis": mod._scene(150, mod.bump(3, .8, 14, 3), False, None, None, links=30),
        "lower-ramp channel": mod._scene(90, mod.bump(2.0, .3, 15, 4), True, 0.1,
                                         mod.ramp(-0.5, -0.9), links=30),
    }
    refs = {k: minimise_energy(s) for k, s in cases.items()}
    lines = ["| back-end | " + " | ".join(cases) + " |", "|---|" + "---|" * len(cases)]
    for name in available_backends():
        row = []
        for key, scene in cases.items():
            ref = refs[key]
            res = lcpbench.solve(scene, solver=name, tol=1e-6, settings="high")
            F0 = max(ref.total_force, scene.EI / scene.length**2,
                     0.0 if ref.forces_lower is None else ref.forces_lower.sum())
            if not res.converged:
                row.append("not converged")
                continue
            err = abs(res.total_force - ref.total_force) / F0
            if res.forces_lower is not None:
                err = max(err, abs(res.forces_lower.sum() - ref.forces_lower.sum()) / F0)
            row.append(f"{'WRONG ' if err > res.judgement.force_tol else ''}converged, "
                       f"{err:.0e}, {res.outer_iterations} outer")
        lines.append(f"| {name} | " + " | ".join(row) + " |")
    return lines


def cost(repeats: int) -> list[str]:
    start = timing_start()
    sten = ActuatorScene(theta=150, links=140, wall_profile=load_profile_csv(
        ROOT / "examples" / "profiles" / "stenosis.csv"))
    flat = ActuatorScene(theta=150, height=2.2, links=140)
    times: dict[str, list[float]] = {"flat": [], "stenosis": []}
    outer = {}
    for _ in range(repeats):
        for key, scene in (("flat", flat), ("stenosis", sten)):
            t0 = time.perf_counter()
            r = solve_internal(scene)
            times[key].append(time.perf_counter() - t0)
            outer[key] = r.outer_iterations
    med = {k: float(np.median(v)) for k, v in times.items()}
    per = {k: med[k] / outer[k] for k in med}
    return [f"N = 140, tol 1e-3, the default (compiled) solve for both, median of {repeats} interleaved "
            f"repeats; {timing_note(start)}", "",
            "| scene | outer | solve (ms) | per outer iteration (ms) |", "|---|---|---|---|",
            f"| flat wall h = 2.2 mm | {outer['flat']} | {1e3 * med['flat']:.3g} | "
            f"{1e3 * per['flat']:.3g} |",
            f"| stenosis.csv (narrowest 2.2 mm) | {outer['stenosis']} | "
            f"{1e3 * med['stenosis']:.3g} | {1e3 * per['stenosis']:.3g} |", "",
            f"Ratio per outer iteration: {per['stenosis'] / per['flat']:.2f}."]


def picture(path: Path) -> None:
    from lcpbench.bench.wall_plot import plot_profile_shape

    scene = ActuatorScene(theta=150, links=140, wall_profile=load_profile_csv(
        ROOT / "examples" / "profiles" / "stenosis.csv"))
    plot_profile_shape(lcpbench.solve(scene), path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=Path("/tmp/profile-validation.md"))
    ap.add_argument("--picture", type=Path, default=None)
    ap.add_argument("--repeats", type=int, default=9)
    args = ap.parse_args()
    mod = _test_module()
    t0 = time.perf_counter()
    table, worst = validation(mod)
    back = backends(mod)
    timing = cost(args.repeats)
    text = "\n".join([
        "# Walls of any profile: validation against the energy minimisation",
        "",
        "Written by `benchmarks/profile_validation.py` (issue 17, item 3; formulation: "
        "docs/profile.md).",
        "",
        f"## {worst['n']} scenes, N = {mod.LINKS}, against `minimise_energy` with h(x) rows",
        "",
        f"Largest relative force error {worst['force']:.1e}, largest shape error "
        f"{worst['shape']:.1e} ℓ (the issue's rule: 1e-6). Outer iterations in brackets: the "
        "flat wall at the profile's lowest height (same θ, N, tol). refused*: the driver "
        "stopped (max|Δα| < tol) but lcpbench's judge did not accept the answer (its force "
        "error bound above min(1e-3, 100·tol)): a status, the answer is not marked converged.",
        "",
        *table,
        "",
        "## Every installed back-end (tol 1e-6, settings high, N = 30)",
        "",
        "Converged answers with their relative force error against the reference "
        "(WRONG would mark one outside the judge's rule: none may be).",
        "",
        *back,
        "",
        "## Cost",
        "",
        *timing,
        "",
        f"(run time {time.perf_counter() - t0:.0f} s)",
        "",
    ])
    args.out.write_text(text)
    if args.picture is not None:
        picture(args.picture)
    print(text)


if __name__ == "__main__":
    main()
