"""Condition numbers of the five formulations of the contact step, and the accuracy each reaches.

For the step at the converged configuration of θ = 150°, h = 3 mm at each N (the
formulations of docs/formulations.md, nondimensionalised as handed to a back-end):

* F1 gaps: cond of the condensed LCP matrix M (dense, symmetric);
* F2 heights: cond of H (banded);
* F3 lifted: cond of its KKT matrix [[P, Aᵀ], [A, 0]] (the kinematic equality);
* F4 reactions: cond of the compliance W (F1's M inverted: the same cond);
* F5 angles: cond of its KKT matrix with the fixed nodes' equalities (no wall row).

Symmetric matrices' extreme eigenvalues by ARPACK (shift-invert at 0 for the smallest),
dense ones by ``numpy.linalg.eigvalsh``. Then each formulation is solved at settings
``high`` by one back-end (:data:`SOLVER`) and the accuracy it reaches is the largest
error of its reactions (mapped back) against the built-in active set's, over the
largest reaction, with the judge's verdict.

    python benchmarks/formulation_conditioning.py [--links 40,140,1000,4000]
        [--accuracy-up-to N] [--out results/formulations/conditioning] [--force]
        [--from-log FILE[,FILE]]

Writes PATH.md and PATH.json; refuses to overwrite committed results without --force.
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

#: the back-end each formulation is solved by (the best of the step screen), and the
#: largest N it is run at (a dense form beyond: tens of minutes; ProxQP dense took 38 s
#: on the 1000 x 1000 compliance)
SOLVER = {"gaps": ("lemke", 1000), "heights": ("proxsuite-sparse", 10**6),
          "lifted": ("osqp", 10**6), "reactions": ("proxsuite-dense", 1000),
          "angles+ruiz": ("osqp", 1000), "reactions+ruiz": ("proxsuite-dense", 1000),
          "lifted+ruiz": ("osqp", 10**6)}


def _extremes(A, dense: bool) -> float:
    """|λ|max / |λ|min of a symmetric matrix."""
    if dense:
        ev = np.abs(np.linalg.eigvalsh(A.toarray() if hasattr(A, "toarray") else A))
        return float(ev.max() / ev.min())
    import scipy.sparse as sp
    from scipy.sparse.linalg import eigsh

    A = sp.csc_matrix(A)
    big = abs(eigsh(A, k=1, which="LM", return_eigenvectors=False)[0])
    small = abs(eigsh(A, k=1, sigma=0, which="LM", return_eigenvectors=False)[0])
    return float(big / small)


def conditioning(step) -> dict:
    import scipy.sparse as sp

    from lcpbench.model.formulations import angle_qp, lifted_qp, wall_rows
    from lcpbench.model.step_solver import step_lcp, step_qp

    out = {"heights": _extremes(step_qp(step).P, dense=False)}
    q3 = lifted_qp(step)
    out["lifted"] = _extremes(sp.bmat([[q3.P, q3.A.T], [q3.A, None]]), dense=False)
    if step.size <= 4000:
        _, M, *_ = step_lcp(step)
        out["gaps"] = _extremes(M, dense=True)
        out["reactions"] = out["gaps"]  # W = M⁻¹ (tests/model/test_formulations.py)
    if step.size <= 1000:
        q5 = angle_qp(step)
        nw = np.union1d(*wall_rows(step)).size
        Af = q5.A[nw:]
        out["angles"] = _extremes(sp.bmat([[q5.P, Af.T], [Af, None]]), dense=True) \
            if Af.shape[0] else _extremes(q5.P, dense=True)
    return out


def accuracy(step, links: int, up_to: int) -> dict:
    from lcpbench.model.step_solver import solve_step

    ref = solve_step(step, "active-set", "high")
    R0 = ref.forces_net
    scale = float(np.max(np.abs(R0)))
    out = {}
    for form, (backend, top) in SOLVER.items():
        if links > min(top, up_to):
            out[form] = {"backend": backend, "run": False,
                         "why": "dense form too large for this back-end" if links > top
                         else f"--accuracy-up-to {up_to}"}
            continue
        t0 = time.perf_counter()
        sol = solve_step(step, backend, "high", formulation=form)
        R = sol.forces_upper - sol.forces_lower
        err = float(np.max(np.abs(R - R0)) / scale) if np.all(np.isfinite(R)) else float("inf")
        out[form] = {"backend": backend, "run": True, "status": sol.status.value,
                     "error": err, "natural": sol.residuals.get("natural"),
                     "time_s": time.perf_counter() - t0}
    return out


def render(data: dict, command: str, machine: str) -> str:
    """The markdown of the results ``data`` (N -> {"cond", "accuracy"})."""
    forms = ("gaps", "heights", "lifted", "reactions", "angles")
    lines = ["| N | " + " | ".join(f"cond {f}" for f in forms) + " |",
             "| ---: |" + " ---: |" * len(forms)]
    for n, d in data.items():
        lines.append(f"| {n} | " + " | ".join(
            f"{d['cond'][f]:.2e}" if f in d["cond"] else "—" for f in forms) + " |")
    slopes = []
    ns = list(data)
    for f in forms:
        pts = [(n, data[n]["cond"][f]) for n in ns if f in data[n]["cond"]]
        if len(pts) >= 2:
            x, y = np.log([q[0] for q in pts]), np.log([q[1] for q in pts])
            slopes.append(f"{f} N^{np.polyfit(x, y, 1)[0]:.2f}")
    acc = ["| N | formulation | back-end | status | max reaction error / max R | "
           "judge's natural residual | time (s) |", "| ---: | --- | --- | --- | ---: | ---: | ---: |"]
    for n, d in data.items():
        for f, r in d["accuracy"].items():
            if not r["run"]:
                why = r.get("why", "dense form too large for this back-end")
                acc.append(f"| {n} | {f} | `{r['backend']}` | not run ({why}) | — | — | — |")
                continue
            nat = r["natural"]
            acc.append(f"| {n} | {f} | `{r['backend']}` | {r['status']} | {r['error']:.1e} | "
                       f"{'—' if nat is None else f'{nat:.1e}'} | {r['time_s']:.2f} |")
    return (f"# Conditioning of the formulations (θ = 150°, h = 3 mm)\n\n"
            f"Command: `{command}`. "
            f"Each step at its converged configuration, nondimensionalised as handed to a "
            f"back-end. Derivation: docs/formulations.md.\n\nMachine: {machine}"
            f"\n\n" + "\n".join(lines) + f"\n\nFitted growth: {', '.join(slopes)}.\n\n"
            "## Accuracy each formulation reaches at settings `high`\n\n"
            "Reactions mapped back from the formulation's multipliers, against the built-in "
            "active set's (exact to round-off).\n\n" + "\n".join(acc) + "\n")


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--links", default="40,140,1000,4000")
    p.add_argument("--out", default="results/formulations/conditioning")
    p.add_argument("--force", action="store_true")
    p.add_argument("--accuracy-up-to", type=int, default=10**6, metavar="N",
                   help="solve the formulations (the accuracy table) up to N links only")
    p.add_argument("--from-log", default=None, metavar="FILE[,FILE]",
                   help="write the results from the 'N {json}' lines runs printed")
    a = p.parse_args(argv)

    import lcpbench
    from lcpbench import ActuatorScene
    from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
    from lcpbench.model.compiled_driver import assemble_step

    out = Path(a.out)
    md, js = out.with_suffix(".md"), out.with_suffix(".json")
    refuse_overwrite([md, js], a.force)
    start = timing_start()
    data = {}
    if a.from_log:  # a run stopped before its end: the sizes it finished
        for log in a.from_log.split(","):
            for line in Path(log).read_text().splitlines():
                n, _, rest = line.partition(" ")
                if n.isdigit() and rest.startswith("{"):
                    data[int(n)] = json.loads(rest)
        data = dict(sorted(data.items()))
        a.links = ",".join(map(str, data))
    for n in ([] if a.from_log else (int(x) for x in a.links.split(","))):
        scene = ActuatorScene(theta=150, height=3, links=n)
        res = lcpbench.solve(scene, settings="high", tol=1e-10)
        step = assemble_step(scene.chain(), np.asarray(res.alpha))
        data[n] = {"cond": conditioning(step), "accuracy": accuracy(step, n, a.accuracy_up_to)}
        print(n, json.dumps(data[n]), flush=True)
    text = render(data, command_line("formulation_conditioning.py", argv), timing_note(start))
    md.parent.mkdir(parents=True, exist_ok=True)
    md.write_text(text)
    js.write_text(json.dumps({str(k): v for k, v in data.items()}, indent=1) + "\n")
    print(text)


if __name__ == "__main__":
    main()
