"""Elastic (tissue-like) walls, issue 17: validation, rigid limit, back-ends, an example.

Writes into ``--out`` (default ``results/elastic``; existing files are not
overwritten unless ``--force``):

- ``validation.md``: the 24 scenes of tests/model/test_elastic_reference.py,
  lcpbench (tol 1e-10 rad) against the independent direct minimisation of the
  total energy with the walls' penalty (Newton on the node heights);
- ``rigid-limit.md`` / ``rigid-limit.png``: |F(k) − F_rigid| / F_rigid against
  the Winkler stiffness k at N = 40 and N = 140, with the log-log slopes
  (lcpbench.studies.rigid_limit);
- ``backends.md``: every installed back-end on three elastic scenes (one wall
  N = 40 and N = 140, the channel N = 40), judged by lcpbench, against the
  active set at tol 1e-10;
- ``tissue-example.png`` / ``.txt``: the README's picture and its numbers (the paper's channel at h = 4.5 mm,
  150 kPa by actuator 1's calibration, walls of k = 0.1 N/mm per mm).

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/elastic_walls.py
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"  # one BLAS thread, before numpy loads (issue 19, item 6)

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import timing_note, timing_start
from lcpbench.problems.calibrations import get_calibration, scene_from_pressure
from lcpbench.solvers import available_backends
from lcpbench.studies.rigid_limit import rigid_limit

ROOT = Path(__file__).resolve().parents[1]


def _write(path: Path, text: str, force: bool) -> None:
    if path.exists() and not force:
        print(f"kept {path} (exists; --force to overwrite)")
        return
    path.write_text(text)
    print(f"wrote {path}")


def validation() -> str:
    sys.path.insert(0, str(ROOT / "tests" / "model"))
    from test_elastic_reference import SCENES, _scene, reference_minimiser

    rows = ["| θ (°) | h (mm) | k (N/mm²) | channel | gravity | F reference (N) | "
            "F lcpbench (N) | relative error | max indentation (mm) | converged |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    worst = 0.0
    for sc in SCENES:
        scene = _scene(*sc)
        u, F, _ = reference_minimiser(scene)
        res = lcpbench.solve(scene, tol=1e-10, max_outer=400)
        err = abs(res.total_force - F) / F
        worst = max(worst, err)
        t, h, k, ch, g = sc
        rows.append(f"| {t:g} | {h:g} | {k:g} | {'yes' if ch else 'no'} | "
                    f"{'yes' if g else 'no'} | {F:.10f} | {res.total_force:.10f} | "
                    f"{err:.1e} | {res.max_indentation:.4g} | {res.converged} |")
    head = ("# Elastic walls: validation against a direct energy minimisation\n\n"
            f"{len(SCENES)} scenes, N = 40, lcpbench at tol 1e-10 rad (default back-end, "
            "compiled) against an independent minimisation of the exact total energy "
            "with the Winkler walls' penalty ½ k a (y − h)₊² over the node heights "
            "(tests/model/test_elastic_reference.py: no lcpbench model code). Largest "
            f"relative error of the total force: **{worst:.1e}** (the test asks 1e-6).\n\n")
    return head + "\n".join(rows) + "\n"


def rigid_limit_tables(out: Path, force: bool) -> str:
    ks = [10.0**e for e in range(-2, 8)]
    parts = ["# Elastic walls: the rigid limit as k grows\n",
             "F(k) of the default scene (θ = 150°, h = 3 mm, one wall) against the rigid "
             "wall's, per Winkler stiffness k (N/mm per mm of wall). Slope: "
             "d log(error) / d log(k) from the previous k. For a fixed chain the penalty's "
             "error is O(1/k) once a node's wall spring k·a exceeds the chain's local "
             "stiffness EI/a³, i.e. k ≫ EI/a⁴ (the crossover below); softer walls are "
             "softer than a link, the contact's edges become boundary layers of width "
             "(4EI/k)^¼ and the force converges more slowly. The force is not monotone "
             "in k: F(k) is above the rigid wall's from some k in (0.01, 0.1) to some k in "
             "(100, 1000) (both N), so the error dips where F(k) crosses F_rigid, "
             "not because it has converged there.\n"]
    studies = {}
    for n, tol in ((40, 1e-9), (140, 1e-8)):
        st = rigid_limit(ActuatorScene(links=n), ks, tol=tol)
        studies[n] = st
        slopes = [math.nan, *st.slopes()]
        parts.append(f"\n## N = {n} (tol {tol:g} rad; crossover EI/a⁴ = {st.crossover:.3g} "
                     f"N/mm²; rigid F = {st.rigid_force:.9f} N)\n")
        parts.append("| k (N/mm²) | F (N) | relative error | slope | max indentation (mm) | "
                     "max pressure (N/mm) | converged |\n|---|---|---|---|---|---|---|")
        for i, k in enumerate(st.stiffness):
            parts.append(f"| {k:g} | {st.total_force[i]:.9f} | {st.relative_error[i]:.2e} | "
                         f"{slopes[i]:.2f} | {st.max_indentation[i]:.3g} | "
                         f"{st.max_pressure[i]:.3g} | {st.converged[i]} |")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.2), constrained_layout=True)
    for n, st in studies.items():
        (line,) = ax.loglog(st.stiffness, st.relative_error, "o-", label=f"N = {n}")
        ax.axvline(st.crossover, color=line.get_color(), ls=":", lw=1)
    k = np.array([1e4, 1e6])
    e0 = studies[40].relative_error[studies[40].stiffness.index(1e4)]
    ax.loglog(k, e0 * 1e4 / k * 2, "k--", lw=1, label="slope −1 (O(1/k))")
    ax.set_xlabel("Winkler wall stiffness k (N/mm per mm of wall)")
    ax.set_ylabel("|F(k) − F_rigid| / F_rigid")
    ax.set_title("Elastic walls tend to the rigid wall (dotted: k = EI/a⁴)", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    png = out / "rigid-limit.png"
    if force or not png.exists():
        fig.savefig(png, dpi=120)
    plt.close(fig)
    parts.append("\n![rigid limit](rigid-limit.png)\n")
    return "\n".join(parts) + "\n"


def backends() -> str:
    cases = [("one wall, N = 40, k = 1", ActuatorScene(links=40, wall_stiffness=1.0)),
             ("one wall, N = 140, k = 0.1", ActuatorScene(links=140, wall_stiffness=0.1)),
             ("channel, N = 40, k = 10", ActuatorScene(links=40, wall_stiffness=10.0,
                                                      channel=True))]
    parts = ["# Elastic walls: every back-end on the elastic step\n",
             "QP back-ends (and the active set) get the spring form, LCP back-ends the "
             "LCP in the reactions (docs/elastic-walls.md); each answer judged by lcpbench's residuals "
             "and result judge, at settings `default`, driver tol 1e-3 rad. Error: "
             "|F − F_ref| / F_ref against the active set at tol 1e-10 rad. A back-end may "
             "fail; none may be converged and off the reference (success rule 1e-3).\n"]
    for title, scene in cases:
        ref = lcpbench.solve(scene, tol=1e-10, max_outer=400)
        parts.append(f"\n## {title} (F_ref = {ref.total_force:.9f} N)\n")
        parts.append("| back-end | converged | error | outer | time (s) | why not |\n"
                     "|---|---|---|---|---|---|")
        for b in available_backends():
            t0 = time.perf_counter()
            r = lcpbench.solve(scene, solver=b)
            dt = time.perf_counter() - t0
            err = abs(r.total_force - ref.total_force) / ref.total_force
            why = "" if r.converged else r.reason.replace("|", "/")[:110]
            parts.append(f"| {b} | {'yes' if r.converged else 'no'} | {err:.1e} | "
                         f"{r.outer_iterations} | {dt:.2f} | {why} |")
            assert not (r.converged and err > 1e-3), f"{b}: converged off the reference"
    return "\n".join(parts) + "\n"


def tissue_example(path: Path, force: bool) -> str:
    cal = get_calibration(1)
    scene = scene_from_pressure(150.0, 1, height=4.5, channel=True, wall_stiffness=0.1)
    res = lcpbench.solve(scene, pressure_limit=0.03)
    rigid = lcpbench.solve(scene_from_pressure(150.0, 1, height=4.5, channel=True))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(2, 1, figsize=(7.5, 5.2), sharex=True,
                                 gridspec_kw={"height_ratios": [2, 1]},
                                 constrained_layout=True)
    h = scene.height
    x, y = res.x, res.y
    surface = np.maximum(y, h)  # the tissue's surface, pushed up where the node indents it
    ax.fill_between(x, surface, h + 1.5, color="#f4b6b6", label="tissue (k = 0.1 N/mm²)")
    ax.fill_between(x, -h - 1.5, -h, color="#f4b6b6")
    ax.plot(rigid.x, rigid.y, "--", color="0.5", lw=1, label="rigid walls")
    ax.plot(x, y, "-", color="#1f4e9a", lw=2, label="actuator")
    ax.axhline(h, color="0.3", lw=0.6, ls=":")
    ax.set_ylabel("y (mm)")
    ax.set_ylim(-h - 1.0, h + 1.5)
    ax.legend(fontsize=7, loc="lower center", ncol=3)
    ax.set_title(f"P = 150 kPa (θ = {cal.theta(150.0):.1f}°), channel h = ±{h:g} mm: "
                 f"F = {1e3 * res.total_force:.1f} mN (rigid {1e3 * rigid.total_force:.1f}), "
                 f"max indentation {res.max_indentation:.2f} mm", fontsize=8)
    xf = x[res.free_nodes]
    bx.plot(xf, res.pressure, "-", color="#b22222", label="contact pressure p = k δ")
    bx.axhline(res.pressure_limit, color="k", ls="--", lw=1,
               label=f"limit {res.pressure_limit:g} N/mm "
                     f"({'exceeded' if res.pressure_exceeded else 'not reached'})")
    bx.set_xlabel("x (mm)")
    bx.set_ylabel("p (N/mm)")
    bx.legend(fontsize=7)
    for a in (ax, bx):
        a.grid(True, alpha=0.3)
    if force or not path.exists():
        fig.savefig(path, dpi=120)
        print(f"wrote {path}")
    plt.close(fig)
    return (f"tissue example: F = {res.total_force:.6f} N (rigid {rigid.total_force:.6f} N), "
            f"max indentation {res.max_indentation:.4f} mm, max pressure "
            f"{res.max_pressure:.4f} N/mm, limit 0.03 exceeded: {res.pressure_exceeded}, "
            f"converged {res.converged}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(ROOT / "results" / "elastic"))
    p.add_argument("--force", action="store_true", help="overwrite existing files")
    p.add_argument("--only", default="validation,rigid,backends,example")
    args = p.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    only = set(args.only.split(","))
    start = timing_start()
    if "validation" in only:
        _write(out / "validation.md", validation(), args.force)
    if "rigid" in only:
        _write(out / "rigid-limit.md", rigid_limit_tables(out, args.force), args.force)
    if "backends" in only:
        _write(out / "backends.md", backends() + f"\nMachine: {timing_note(start)}\n",
               args.force)
    if "example" in only:
        _write(out / "tissue-example.txt", tissue_example(out / "tissue-example.png",
                                                          args.force) + "\n", args.force)


if __name__ == "__main__":
    main()
