"""Success of each back-end in each formulation of the contact step (issue 37, item 4).

Every scene of the paper grid (θ 10…180°, h 2…7 mm, N = 140) is solved by
``lcpbench.solve(scene, solver=B, settings=S, tol=T, formulation=F)`` for each
back-end B and formulation F (docs/formulations.md). A run **succeeds** when
lcpbench's judge accepts it (``converged``) and its total force is within
min(1e-3, 100·T) of the reference (|F − F_ref| / max(|F_ref|, EI/ℓ²), the sweep
report's rule); **wrong** counts converged runs off the reference. The reference per
scene is the built-in active set at ``high`` and tol 1e-11.

``--level step`` screens faster: the contact step at each scene's reference
configuration, solved once per (B, F) by ``solve_step`` and judged by the same judge;
success is SOLVED with the total reaction within 100·T·max(|R|, EI/ℓ²) of the
active set's.

Rows go to PATH.jsonl as they finish (``--resume`` goes on where a run stopped); PATH.md
holds the back-end × formulation table (success, wrong, shifted geometric mean of
the solve time over every scene with failures charged at 60 s, shift 1 ms) and
``--best`` writes each back-end's best formulation to the package's evidence table
(``src/lcpbench/model/best_formulations.json``), which ``formulation="best"`` reads.

``--pairs B:best`` runs B through ``formulation="best"`` itself (the committed table at
``--settings``): the library call of issue 37's target 1; a row "best" is never a
candidate for ``--best``.

A pair ``B:F@E`` (``osqp:angles+ruiz@1e-5``) hands B the tolerance E in form F while
lcpbench's judge keeps ``--settings``' own: what a ``best`` recipe with ε = E does
(``best_formulations.json``'s ``eps``); such rows are never candidates for ``--best``.

``--eps E`` is an experiment, not a profile: every back-end is handed the tolerance E
(``Settings(name=--settings, eps=E)``, so lcpbench's step judge also asks 10·E of each
step) at the driver tol ``--tol``. With ``--settings default --eps 1e-6`` it is the
`default` profile with the back-end told what lcpbench's judge already asks of every
step there (``solvers.judge.DEFAULT_TOL``); ``--best`` is refused with it.

    python benchmarks/formulation_success.py [--level solve|step] [--backends a,b]
        [--formulations f,g | --pairs b:f,c:g] [--settings high] [--tol 1e-9] [--theta 10:180:10]
        [--height 2:7:1] [--workers 2] [--out results/formulations/success-high]
        [--eps E] [--best] [--force | --resume]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

for _k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_k] = "1"

import numpy as np  # noqa: E402

BACKENDS = ("osqp", "clarabel", "proxsuite-dense", "proxsuite-sparse", "qpsolvers-piqp",
            "qpsolvers-scs", "cvxpy")
CHARGE_S, SHIFT_S = 60.0, 1e-3
ROOT = Path(__file__).resolve().parents[1]
BEST = ROOT / "src" / "lcpbench" / "model" / "best_formulations.json"


def _reference(key: str) -> dict:
    import lcpbench
    from lcpbench.bench.grid import scene_from_key

    scene = scene_from_key(key)
    res = lcpbench.solve(scene, settings="high", tol=1e-11)
    return {"key": key, "force": float(res.total_force), "alpha": np.asarray(res.alpha).tolist(),
            "unit": float(scene.EI / scene.length ** 2)}


def _run(task) -> dict:
    import lcpbench
    from lcpbench.bench.grid import scene_from_key

    key, backend, form, settings, tol, ref, level = task
    scene = scene_from_key(key)
    row = {"key": key, "backend": backend, "formulation": form}
    t0 = time.perf_counter()
    if level == "step":
        from lcpbench.model.compiled_driver import assemble_step
        from lcpbench.model.step_solver import solve_step

        step = assemble_step(scene.chain(), np.asarray(ref["alpha"]))
        base = solve_step(step, "active-set", "high")
        t0 = time.perf_counter()
        sol = solve_step(step, backend, settings, formulation=form)
        elapsed = time.perf_counter() - t0
        R0, R = float(np.sum(base.forces_net)), sol.forces_net
        err = (abs(float(np.sum(R)) - R0) / max(abs(R0), ref["unit"])
               if R is not None and np.all(np.isfinite(R)) else float("inf"))
        row.update(converged=sol.status.value == "solved", error=err, time=elapsed,
                   outer=1, reason=sol.message[:160])
    else:
        try:
            res = lcpbench.solve(scene, solver=backend, settings=settings, tol=tol,
                                 formulation=form)
        except Exception as exc:  # noqa: BLE001 - a row, not a crash
            row.update(converged=False, error=float("inf"), time=time.perf_counter() - t0,
                       outer=200, reason=f"{type(exc).__name__}: {exc}"[:160])
            return row
        elapsed = time.perf_counter() - t0
        err = abs(float(res.total_force) - ref["force"]) / max(abs(ref["force"]), ref["unit"])
        row.update(converged=bool(res.converged), error=float(err) if np.isfinite(err)
                   else float("inf"), time=elapsed, outer=int(res.outer_iterations),
                   reason="" if res.converged else str(res.reason)[:160])
    return row


def table(rows: list[dict], tol: float, backends, forms) -> tuple[str, dict]:
    """The back-end × formulation table (markdown) and each back-end's best."""
    from lcpbench.bench.metrics import charged_sgm

    threshold = min(1e-3, 100 * tol)
    by = {}
    for r in rows:
        by.setdefault((r["backend"], r["formulation"]), []).append(r)
    best: dict[str, tuple] = {}
    lines = ["| back-end | formulation | scenes | success | wrong (converged, off) | "
             "time sgm (ms; all scenes, failure = 60 s, shift 1 ms) | median error |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: |"]
    for b in backends:
        for f in forms:
            rs = by.get((b, f), [])
            if not rs:
                continue
            ok = [r["converged"] and r["error"] <= threshold for r in rs]
            wrong = sum(r["converged"] and r["error"] > threshold for r in rs)
            sgm = charged_sgm([r["time"] for r in rs], ok, CHARGE_S, SHIFT_S) * 1e3
            med = float(np.median([r["error"] for r in rs]))
            rate = sum(ok) / len(rs)
            lines.append(f"| `{b}` | {f} | {len(rs)} | {100 * rate:.0f} % | {wrong} | "
                         f"{sgm:.3g} | {med:.1e} |")
            score = (rate, -wrong, -sgm)
            if f != "best" and "@" not in f and (b not in best or score > best[b][0]):
                best[b] = (score, f, rate, wrong)
    if best:  # none when every row ran formulation="best"
        lines += ["", "Best per back-end (highest success, then fewest wrong, then time):", "",
                  "| back-end | best formulation | success | wrong |",
                  "| --- | --- | ---: | ---: |"]
    for b, (_, f, rate, wrong) in best.items():
        lines.append(f"| `{b}` | {f} | {100 * rate:.0f} % | {wrong} |")
    return "\n".join(lines), {b: v[1] for b, v in best.items()}


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--level", choices=("solve", "step"), default="solve")
    p.add_argument("--backends", default=",".join(BACKENDS))
    p.add_argument("--formulations", default=None)
    p.add_argument("--pairs", default=None,
                   help="back-end:formulation pairs, comma-separated (instead of the cross)")
    p.add_argument("--settings", default="high")
    p.add_argument("--tol", type=float, default=1e-9)
    p.add_argument("--eps", type=float, default=None,
                   help="hand every back-end this tolerance (an experiment; not with --best)")
    p.add_argument("--theta", default="10:180:10")
    p.add_argument("--height", default="2:7:1")
    p.add_argument("--links", type=int, default=140)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--out", default="results/formulations/success-high")
    p.add_argument("--best", action="store_true", help="write the best-formulation table")
    p.add_argument("--force", action="store_true", help="overwrite committed results")
    p.add_argument("--resume", action="store_true", help="go on with PATH.jsonl's rows")
    a = p.parse_args(argv)

    from lcpbench import ActuatorScene
    from lcpbench.bench.grid import parse_range, scene_key
    from lcpbench.bench.machine import refuse_overwrite, timing_note, timing_start
    from lcpbench.model.formulations import NAMES

    if a.eps is not None and a.best:
        p.error("--eps is an experiment: --best reads the profiles' own runs only")
    settings = a.settings
    if a.eps is not None:
        from lcpbench.solvers.base import Settings

        settings = Settings(a.settings, a.eps, driver_tol=a.tol)
    out = Path(a.out)
    md, jl = out.with_suffix(".md"), out.with_suffix(".jsonl")
    start = timing_start()
    backends = a.backends.split(",")
    forms = a.formulations.split(",") if a.formulations else list(NAMES)
    keys = [scene_key(ActuatorScene(theta=t, height=h, links=a.links))
            for h in parse_range(a.height, "height") for t in parse_range(a.theta, "theta")]
    if not a.resume:
        refuse_overwrite([md, jl], a.force)
        jl.unlink(missing_ok=True)
    done = []
    if jl.exists():
        done = [json.loads(x) for x in jl.read_text().splitlines() if x.strip()]
    seen = {(r["key"], r["backend"], r["formulation"]) for r in done}
    out.parent.mkdir(parents=True, exist_ok=True)
    with ProcessPoolExecutor(a.workers) as pool:
        refs = {r["key"]: r for r in pool.map(_reference, keys)}
        pairs = ([tuple(x.split(":", 1)) for x in a.pairs.split(",")] if a.pairs
                 else [(b, f) for b in backends for f in forms])
        tasks = [(k, b, f, settings, a.tol, refs[k], a.level) for b, f in pairs
                 for k in keys if (k, b, f) not in seen]
        print(f"{len(tasks)} runs ({len(seen)} done before)", file=sys.stderr)
        with jl.open("a") as fh:
            for row in pool.map(_run, tasks, chunksize=1):
                fh.write(json.dumps(row) + "\n")
                fh.flush()
                done.append(row)
    rows = [r for r in done if r["key"] in refs]  # every back-end and form run so far
    order = list(dict.fromkeys([r["backend"] for r in rows]))
    forms_run = list(dict.fromkeys(r["formulation"] for r in rows))
    text, best = table(rows, a.tol, order,  # NAMES' order, then B:best and B:F@E
                       [f for f in (*NAMES, "best") if f in forms_run]
                       + [f for f in forms_run if "@" in f])
    head = (f"# Back-end x formulation on the paper grid ({a.level} level)\n\n"
            f"{len(keys)} scenes (θ {a.theta}°, h {a.height} mm, N = {a.links}), settings "
            f"`{a.settings}`" + ("" if a.eps is None else f" with every back-end handed eps "
                                 f"{a.eps:g} (an experiment)") + f", driver tol {a.tol:g}; success: lcpbench's judge accepts and the "
            f"total force is within {min(1e-3, 100 * a.tol):g} of the reference (the active "
            f"set at `high`, tol 1e-11). Command: `python benchmarks/formulation_success.py "
            f"{' '.join(argv if argv is not None else sys.argv[1:])}`.\n\n"
            f"Machine: {timing_note(start)}\n\n")
    md.write_text(head + text + "\n")
    print(head + text)
    if a.best:  # this profile's row of the table, the others kept
        table_ = json.loads(BEST.read_text()) if BEST.exists() else {"best": {}}
        table_.setdefault("source", {})[a.settings] = f"{md} (driver tol {a.tol:g})"
        old = table_["best"].get(a.settings, {})  # a recipe with an ε keeps its form:
        best.update({b: old[b] for b in table_.get("eps", {}).get(a.settings, {})
                     if b in old})  # it was chosen at that ε, not the profile's own
        table_["best"][a.settings] = best
        BEST.write_text(json.dumps(table_, indent=1) + "\n")


if __name__ == "__main__":
    main()
