"""Issue 37's targets, table by table, from the committed runs and one contact step.

1. Success at ``high`` (tol 1e-9) and ``default`` (tol 1e-3) of each back-end in its
   best formulation (``formulation="best"``), read from results/formulations/
   success-high.jsonl and success-default.jsonl (benchmarks/formulation_success.py), and
   for a recipe with an ε (``best_formulations.json``'s ``eps``) recipe-default.jsonl.
2. The relative force error of the N = 140 step (θ = 150°, h = 3 mm, at its answer)
   at ``high``, for the design card's back-ends (Lemke, PGS, OSQP, Clarabel, ProxSuite)
   and the accelerated projected method (PGS-SM) in every form each takes: max |R − R_ref| / max |R_ref|, R_ref the step's
   exact answer on its contact set, in rational arithmetic (``exact_step.py``): no
   double-precision method is the reference, so each row's error is its own.

    python benchmarks/formulation_targets.py [--out results/formulations/targets] [--force]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

for _k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_k] = "1"

import numpy as np  # noqa: E402

#: the design card's back-ends, and the accelerated projected method held to their 1e-6
CARD = ("lemke", "pgs", "pgs-sm", "osqp", "clarabel", "proxsuite-dense", "proxsuite-sparse")
TARGETS = ("osqp", "clarabel", "proxsuite-dense", "proxsuite-sparse", "qpsolvers-piqp",
           "qpsolvers-scs", "cvxpy")
OWN_AT = {"high": "results/sweep/report.md", "default": "results/sweep/report.md"}


def own_form(settings: str, tol: float) -> dict:
    """back-end -> (success, wrong, scenes) of its own form in the committed standard run
    (results/sweep/runs.csv, method globalised), by the same rule."""
    import csv

    out: dict[str, list] = {}
    with open(OWN_AT[settings].replace("report.md", "runs.csv"), newline="") as fh:
        for r in csv.DictReader(fh):
            if r["settings"] != settings or r["method"] != "globalised" \
                    or r["backend"] not in TARGETS:
                continue
            F, F0 = float(r["total_force"] or "nan"), float(r["reference_force"])
            err = abs(F - F0) / max(abs(F0), 32.01 / 30.0 ** 2)
            out.setdefault(r["backend"], []).append((r["converged"] == "1", err))
    thr = min(1e-3, 100 * tol)
    return {b: (sum(c and e <= thr for c, e in v) / len(v),
                sum(c and e > thr for c, e in v), len(v)) for b, v in out.items()}


def _recipe(row: dict) -> tuple:
    """(form, ε) of a row: ``F@E`` the form F with the back-end handed E, else (F, None)."""
    name, _, eps = row["formulation"].partition("@")
    return name, float(eps) if eps else None


def success(paths, tol: float, best: dict, eps: dict) -> dict:
    """back-end -> (form, success, wrong, scenes) of its best recipe (its form, and the ε
    it is handed where ``eps`` gives one) in the rows at ``paths``."""
    rows = [json.loads(x) for path in paths if path.exists()
            for x in path.read_text().splitlines() if x.strip()]
    out = {}
    for b in TARGETS:
        form = best.get(b)
        rs = [r for r in rows if r["backend"] == b and _recipe(r) == (form, eps.get(b))]
        if not rs:
            continue
        if b in eps:
            form = f"{form}, ε {eps[b]:g}"
        thr = min(1e-3, 100 * tol)
        ok = sum(r["converged"] and r["error"] <= thr for r in rs)
        wrong = sum(r["converged"] and r["error"] > thr for r in rs)
        out[b] = (form, ok / len(rs), wrong, len(rs), _why(r for r in rs if not (
            r["converged"] and r["error"] <= thr)))
    return out


def _why(rows) -> str:
    """The unsuccessful runs by the judge's reason."""
    from collections import Counter

    kinds = Counter("the force error bound" if "force error bound" in r["reason"]
                    else "the last step inaccurate" if "last step" in r["reason"]
                    else "200 outer iterations" if "outer iterations" in r["reason"]
                    else "complementarity" if "complementarity" in r["reason"]
                    else "converged, off the reference" if r["converged"]
                    else r["reason"][:40] for r in rows)
    return "; ".join(f"{n} {k}" for k, n in kinds.most_common()) or "—"


def step_errors() -> list[tuple]:
    from exact_step import exact_reactions

    import lcpbench
    from lcpbench import ActuatorScene
    from lcpbench.model.compiled_driver import assemble_step
    from lcpbench.model.formulations import NAMES, accepts, parse_formulation
    from lcpbench.model.step_solver import solve_step
    from lcpbench.solvers.registry import available_backends, get_backend

    scene = ActuatorScene(theta=150, height=3, links=140)
    res = lcpbench.solve(scene, settings="high", tol=1e-10)
    step = assemble_step(scene.chain(), np.asarray(res.alpha))
    own = solve_step(step, "active-set", "high")
    R0, confirmed = exact_reactions(step, own.forces_upper > 0, own.forces_lower > 0)
    if not confirmed:
        raise SystemExit("the active set's contact set is not the exact step's: no oracle")
    scale, total = np.max(np.abs(R0)), np.sum(R0)  # one wall: F = ΣR

    def errors(R):  # (node-wise, total force), relative
        if not np.all(np.isfinite(R)):
            return float("inf"), float("inf")
        return (float(np.max(np.abs(R - R0)) / scale),
                float(abs(np.sum(R) - total) / abs(total)))

    out = [("active-set", "heights (its own)", own.status.value, *errors(own.forces_net))]
    for b in CARD:
        if b not in available_backends():
            continue
        for name in NAMES:
            if not accepts(get_backend(b), parse_formulation(name)):
                continue
            sol = solve_step(step, b, "high", formulation=name)
            out.append((b, name, sol.status.value, *errors(sol.forces_upper - sol.forces_lower)))
    return out


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", default="results/formulations/targets")
    p.add_argument("--force", action="store_true")
    a = p.parse_args(argv)

    from lcpbench.bench.machine import refuse_overwrite, timing_note, timing_start
    from lcpbench.model.formulations import best_eps, best_formulations

    md = Path(a.out).with_suffix(".md")
    refuse_overwrite([md], a.force)
    start = timing_start()
    here = Path("results/formulations")
    lines = ["# Issue 37's targets", "",
             "Command: `python benchmarks/formulation_targets.py`, from the committed runs of "
             "`benchmarks/formulation_success.py` (their commands are in success-high.md, "
             "success-default.md and recipe-default.md) and one contact step computed "
             "here.", "",
             "## 1. Success in each back-end's best formulation (paper grid, N = 140)", "",
             "Through `lcpbench.solve(scene, solver=B, settings=S, tol=T, "
             "formulation=\"best\")` (the rows ran the same call with the form `best` "
             "resolves to, and the ε it hands the back-end where the recipe gives one: "
             "recipe-default.md's rows `F@E`). Target: >= 99 % and 0 wrong at `high`, "
             ">= 95 % at `default`.", "",
             "| back-end | settings | best form | success | wrong | scenes | target met | "
             "refused by |",
             "| --- | --- | --- | ---: | ---: | ---: | --- | --- |"]
    for settings, tol, need in (("high", 1e-9, 0.99), ("default", 1e-3, 0.95)):
        best = best_formulations(settings)
        got = success([here / f"success-{settings}.jsonl", here / f"recipe-{settings}.jsonl"],
                      tol, best, best_eps(settings))
        for b in TARGETS:
            if b in got:
                form, rate, wrong, n, why = got[b]
                lines.append(f"| `{b}` | {settings} | {form} | {100 * rate:.0f} % | {wrong} | "
                             f"{n} | {'yes' if rate >= need and wrong == 0 else 'no'} | "
                             f"{why} |")
            elif b in (own := own_form(settings, tol)):
                rate, wrong, n = own[b]
                lines.append(f"| `{b}` | {settings} | its own ({OWN_AT[settings]}) | "
                             f"{100 * rate:.0f} % | {wrong} | {n} | "
                             f"{'yes' if rate >= need and wrong == 0 else 'no'} | — |")
    rows = [json.loads(x) for x in (here / "success-high.jsonl").read_text().splitlines()
            if x.strip()]
    bound = np.array([r["error"] for r in rows if "force error bound" in r["reason"]])
    lines += ["", "\"The force error bound\": the result judge's bound on the total force's "
              f"error exceeds 100·tol; in success-high.jsonl {int(np.sum(bound <= 1e-7))} "
              f"of the {bound.size} runs refused on that bound alone are within 100·tol of "
              f"the reference (median error {np.median(bound):.1e})"
              + (": the bound, not the answer, stops them" if np.mean(bound <= 1e-7) > 0.5
                 else "") + ". \"The last step "
              "inaccurate\": the back-end's answer to the last contact step failed lcpbench's "
              "residual check at the tolerance it was handed (its own, or the recipe's ε).", "", "## 2. The N = 140 step at `high` (θ = 150°, h = 3 mm)", "",
              "Max |R − R_ref| / max |R_ref| of the reactions mapped back from each form; "
              "R_ref the step's exact answer on the built-in active set's contact set, "
              "computed in rational arithmetic from the step's doubles and its contact set "
              "confirmed there (benchmarks/exact_step.py). Target: 1e-6 for the design "
              "card's back-ends in some form; 1e-9 for Clarabel. A method that works on the "
              "assembled Hessian H of the height form (cond H ≈ 1e8) is limited to about "
              "cond H · ε ≈ 1e-8 in this measure (Lemke 8.9e-9 in gaps); the active set "
              "solves with the factored gradient Jᵀk(Ju + φ₀ − φ*) − f and comes within "
              "its first row's error of the exact answer. The total force F = ΣR (the "
              "paper's measured quantity; the scene has one wall) is far less sensitive: "
              "its relative error is the last column.", "",
              "| back-end | formulation | status | relative force error (node-wise) | "
              "relative total-force error |",
              "| --- | --- | --- | ---: | ---: |"]
    for b, name, status, err, err_total in step_errors():
        lines.append(f"| `{b}` | {name} | {status} | {err:.1e} | {err_total:.1e} |")
    lines += ["", f"Run {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}. Machine: "
              f"{timing_note(start)}"]
    md.parent.mkdir(parents=True, exist_ok=True)
    md.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
