"""Conditioning of the contact step against N and θ, and what it does to iterative back-ends.

For the step at the converged configuration of θ = 150°, h = 3 mm (and of
θ = 60…180° at N = 140): cond(K) of the banded stiffness and cond(M) of the
condensed LCP, raw (mm, N) and nondimensionalised (lengths / ℓ, forces /
(EI/ℓ²)); then the iterations each iterative back-end needs at settings
`mid` (1e-6), scaled and raw, and whether it got there.

    python benchmarks/conditioning.py [--links 10,20,40,80,140,280] [--out results/conditioning]

Writes PATH.md, PATH.json and PATH.png.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.step_solver import solve_step, step_lcp
from lcpbench.solvers.registry import available_backends

ITERATIVE = ["pgs", "psor", "osqp", "qpsolvers-scs", "clarabel", "siconos-pgs",
             "siconos-newton-min", "siconos-newton-fb"]


def converged_step(scene):
    res = lcpbench.solve(scene, tol=1e-10, settings="high")
    return assemble_step(scene.with_links(res.links).chain(), res.alpha)


def conditioning(step) -> dict:
    K = step.dense_hessian()
    out = {"cond_K": float(np.linalg.cond(K))}
    for scaled in (False, True):
        _, M, *_ = step_lcp(step, scaled=scaled)
        out[f"cond_M_{'scaled' if scaled else 'raw'}"] = float(np.linalg.cond(M))
        out["rows"] = int(M.shape[0])
    return out


def iterations(step, backends) -> dict:
    out = {}
    for b in backends:
        for scaled in (True, False):
            sol = solve_step(step, b, "mid", scaled=scaled)
            out[f"{b}|{'scaled' if scaled else 'raw'}"] = {
                "status": sol.status.value, "iterations": int(sol.iterations)}
    return out


def plot(data: dict, path) -> None:
    """Condition numbers (left) and iterations of the iterative back-ends (right) against N."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    by_n, backends, slope = data["by_links"], data["backends"], data["cond_K_slope"]
    links = [r["links"] for r in by_n]
    fig = Figure(figsize=(11.5, 4), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 2, 1)
    ax.loglog(links, [r["cond_K"] for r in by_n], "o-", label="cond(K)")
    ax.loglog(links, [r["cond_M_scaled"] for r in by_n], "s--", label="cond(M), scaled")
    ax.set_xlabel("N")
    ax.set_ylabel("2-norm condition number (σ_max / σ_min)")
    ax.set_title(f"condition numbers (cond(K) ~ N^{slope:.2f})", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    ax = fig.add_subplot(1, 2, 2)
    for k, b in enumerate(backends):
        its = [r["iterations"][f"{b}|scaled"] for r in by_n]
        ok = [i["status"] == "solved" for i in its]
        ax.loglog(links, [max(i["iterations"], 1) for i in its], "-", color=f"C{k}", label=b)
        ax.loglog([n for n, o in zip(links, ok) if o],
                  [max(i["iterations"], 1) for i, o in zip(its, ok) if o], "o", color=f"C{k}")
        ax.loglog([n for n, o in zip(links, ok) if not o],
                  [max(i["iterations"], 1) for i, o in zip(its, ok) if not o], "x",
                  color=f"C{k}")
    ax.set_xlabel("N")
    ax.set_ylabel("iterations at `mid` (x: not solved)")
    fig.legend(handles=ax.get_lines()[::3], fontsize=7, loc="outside right upper")
    ax.grid(True, which="both", alpha=0.3)
    fig.savefig(path, dpi=130)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", default="10,20,40,80,140,280")
    ap.add_argument("--thetas", default="60,90,120,150,180")
    ap.add_argument("--out", default="results/conditioning")
    ap.add_argument("--plot-only", action="store_true",
                    help="redraw the figure from OUT.json without computing anything")
    args = ap.parse_args()
    if args.plot_only:
        out = Path(args.out)
        plot(json.loads(out.with_suffix(".json").read_text()), out.with_suffix(".png"))
        return
    links = [int(v) for v in args.links.split(",")]
    thetas = [float(v) for v in args.thetas.split(",")]
    backends = [b for b in ITERATIVE if b in available_backends()]

    by_n = []
    for n in links:
        step = converged_step(lcpbench.ActuatorScene(theta=150.0, height=3.0, links=n))
        by_n.append({"links": n, **conditioning(step), "iterations": iterations(step, backends)})
        print(f"N = {n}: cond(K) = {by_n[-1]['cond_K']:.2e}", flush=True)
    by_theta = []
    for th in thetas:
        step = converged_step(lcpbench.ActuatorScene(theta=th, height=3.0, links=140))
        by_theta.append({"theta": th, **conditioning(step)})
    slope = float(np.polyfit(np.log(links), np.log([r["cond_K"] for r in by_n]), 1)[0])

    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    data = {"by_links": by_n, "by_theta": by_theta, "cond_K_slope": slope,
            "backends": backends}
    out.with_suffix(".json").write_text(json.dumps(data, indent=1) + "\n")

    L = ["# Conditioning of the contact step", "",
         "Made by `python benchmarks/conditioning.py`. The step at the converged "
         "configuration (θ = 150°, h = 3 mm unless stated). cond(K): the banded stiffness "
         "(the QP's Hessian); cond(M): the condensed LCP over the contact rows, raw (mm, N) "
         "and nondimensionalised (gaps / ℓ, reactions / (EI/ℓ²)).", "",
         f"cond(K) grows as N^{slope:.2f} (fitted over N = {links[0]}…{links[-1]}).", "",
         "| N | rows | cond(K) | cond(M) raw | cond(M) scaled |", "|---:|---:|---:|---:|---:|"]
    for r in by_n:
        L.append(f"| {r['links']} | {r['rows']} | {r['cond_K']:.2e} | {r['cond_M_raw']:.2e} | "
                 f"{r['cond_M_scaled']:.2e} |")
    L += ["", "Against θ at N = 140:", "", "| θ (deg) | rows | cond(K) | cond(M) raw | "
          "cond(M) scaled |", "|---:|---:|---:|---:|---:|"]
    for r in by_theta:
        L.append(f"| {r['theta']:g} | {r['rows']} | {r['cond_K']:.2e} | {r['cond_M_raw']:.2e} | "
                 f"{r['cond_M_scaled']:.2e} |")
    L += ["", "Scaling by ℓ and EI/ℓ² multiplies the whole single-wall LCP by constants, so "
          "it leaves every condition number as it is (the columns agree to round-off); what "
          "it changes is what an absolute tolerance means (docs/solvers.md).", "",
          "## Iterative back-ends at settings `mid` (1e-6): iterations, and the status "
          "(solved / inaccurate / max_iterations)", "",
          "| back-end | " + " | ".join(f"N = {n}" for n in links) + " |",
          "|---|" + "---:|" * len(links)]
    for b in backends:
        for sc in ("scaled", "raw"):
            cells = []
            for r in by_n:
                it = r["iterations"][f"{b}|{sc}"]
                mark = "" if it["status"] == "solved" else f" ({it['status']})"
                cells.append(f"{it['iterations']}{mark}")
            L.append(f"| {b} ({sc}) | " + " | ".join(cells) + " |")
    text = "\n".join(L) + "\n"
    out.with_suffix(".md").write_text(text)

    plot(data, out.with_suffix(".png"))
    print(text)


if __name__ == "__main__":
    main()
