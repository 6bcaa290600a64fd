"""Writing an exported test set: the files of :mod:`.testset` and its README."""

from __future__ import annotations

import csv
import json
import os
from pathlib import Path

from .testset import (
    PROBLEM_COLUMNS,
    SETTINGS_NAMES,
    result_rows,
    save_problem,
    scene_problems,
    write_results,
)

#: the qpbenchmark tolerances of the exported test set (primal, dual, gap), per settings
TOLERANCES = {"default": 1e-6, "low_accuracy": 1e-3, "mid_accuracy": 1e-6,
              "high_accuracy": 1e-9}
RUNTIME_LIMIT = 60.0  # s, as lcpbench's sweep

TEST_SET_MODULE = '''"""lcpbench contact steps: a qpbenchmark test set.

Written by `lcpbench export-testset`; see README.md. Run with qpbenchmark
installed: python lcpbench_contact.py run
"""

import os
from typing import Iterator

import qpbenchmark
from qpbenchmark.benchmark import main
from qpbenchmark.problem import Problem
from qpbenchmark.tolerance import Tolerance

TOLERANCES = {tolerances}


class LcpbenchContact(qpbenchmark.TestSet):
    """Contact steps of a soft actuator against a wall (bound-constrained QPs)."""

    @property
    def description(self) -> str:
        return ("Linearised contact steps of a discretised elastica pressed against a "
                "wall, from lcpbench: box-constrained QPs with a pentadiagonal Hessian "
                "whose condition number grows as N^4.")

    @property
    def title(self) -> str:
        return "lcpbench contact-step test set"

    @property
    def sparse_only(self) -> bool:
        return False

    def define_tolerances(self) -> None:
        self.tolerances = {{
            name: Tolerance(primal=tol, dual=tol, gap=tol, runtime={runtime})
            for name, tol in TOLERANCES.items()
        }}

    def __init__(self):
        super().__init__()
        self.data_dir = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")

    def __iter__(self) -> Iterator[Problem]:
        for fname in sorted(os.listdir(self.data_dir)):
            if fname.endswith(".npz"):
                yield Problem.load(os.path.join(self.data_dir, fname))


if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))
    main(test_set_path=os.path.abspath(__file__),
         results_path=os.path.join(here, "results", "qpbenchmark_results.csv"))
'''


def _readme(problems, grid: str, solvers, settings, results: bool) -> str:
    sizes = sorted({p.q.size for p in problems})
    conds = [p.cond for p in problems]
    return "\n".join([
        "# lcpbench contact steps: a qpbenchmark test set",
        "",
        f"Written by `lcpbench export-testset --grid {grid}`: {len(problems)} problems, "
        f"n = {', '.join(map(str, sizes))} unknowns, cond(P) from {min(conds):.2g} to "
        f"{max(conds):.2g}.",
        "",
        "## What the problems are",
        "",
        "A soft bending actuator is a chain of N rigid links with rotational springs, "
        "bent to an angle θ and pressed against a wall at height h. lcpbench finds its "
        "equilibrium by a sequence of contact steps, each a convex QP in the heights u of "
        "the free nodes:",
        "",
        "    minimise ½ xᵀ P x + qᵀ x   subject to   lb ≤ x ≤ ub",
        "",
        "with x = u/ℓ, P the pentadiagonal Hessian of the linearised spring energy and q "
        "the linear term (the objective in units of EI/ℓ), ub the wall h/ℓ at the nodes that may touch "
        "it (+∞ at the others; lb the second wall of a "
        "channel, else −∞). The multiplier of ub is the wall's reaction at each node, in "
        "units of EI/ℓ². P's condition number grows as N⁴, so at N = 140 these are badly "
        "conditioned QPs with many active bounds. Two problems per scene: the step at "
        "the driver's first configuration (`-first`: the unconstrained arc clipped to the "
        "wall) and at the converged equilibrium (`-converged`).",
        "",
        "`problems.csv` lists each problem's scene (θ in degrees, h and ℓ in mm, EI in "
        "N·mm², w in N/mm), size, cond(P) and the optimal cost found by lcpbench's "
        "active set at high accuracy.",
        "",
        "## Files",
        "",
        "- `data/*.npz`: one problem each, in `qpsolvers.Problem.save`'s layout "
        "(compressed); `qpsolvers.Problem.load` and `qpbenchmark.Problem.load` read them.",
        "- `lcpbench_contact.py`: the qpbenchmark test set over `data/`.",
        "- `problems.csv`: what each problem is.",
        ("- `results/lcpbench_contact.csv`: lcpbench's back-ends "
         f"({', '.join(solvers)}) at settings {', '.join(SETTINGS_NAMES[s] for s in settings)}"
         ", in qpbenchmark's results schema (residuals by qpsolvers' `Solution`; `found` is "
         "lcpbench's judged status; runtime is the wall time of one step solve, building "
         "the back-end's form included).") if results else "",
        "",
        "## Running qpbenchmark on it",
        "",
        "    pip install qpbenchmark qpsolvers[open_source_solvers]",
        "    python lcpbench_contact.py run",
        "",
        "The report goes to `results/`. To compare with lcpbench's back-ends in one "
        "report, append the rows of `results/lcpbench_contact.csv` to "
        "`results/qpbenchmark_results.csv` (same columns) and run "
        "`python lcpbench_contact.py report`.",
        "",
        f"Tolerances (primal, dual, gap) per settings: {json.dumps(TOLERANCES)}; time "
        f"limit {RUNTIME_LIMIT:g} s.",
        "",
    ])


def export_testset(scenes, out: str | os.PathLike, *, solvers=(), settings=("default",),
                   results: bool = True, grid: str = "custom", progress=None) -> dict:
    """Write the test set of ``scenes`` into ``out`` (see :mod:`.testset`); returns a summary.

    Existing files of the same names are replaced; nothing else in ``out`` is
    touched.
    """
    out = Path(out)
    (out / "data").mkdir(parents=True, exist_ok=True)
    problems = []
    for s in scenes:
        for p in scene_problems(s):
            save_problem(p, out / "data" / f"{p.name}.npz")
            problems.append(p)
    with open(out / "problems.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=PROBLEM_COLUMNS)
        w.writeheader()
        for p in problems:
            w.writerow({k: repr(v) if isinstance(v, float) else v for k, v in p.meta().items()})
    (out / "lcpbench_contact.py").write_text(TEST_SET_MODULE.format(
        tolerances=json.dumps(TOLERANCES), runtime=RUNTIME_LIMIT))
    rows = []
    if results and solvers:
        (out / "results").mkdir(exist_ok=True)
        rows = result_rows(problems, list(solvers), list(settings), progress=progress)
        write_results(rows, out / "results" / "lcpbench_contact.csv")
    (out / "README.md").write_text(_readme(problems, grid, solvers, settings,
                                           bool(results and solvers)))
    return {"problems": len(problems), "results": len(rows), "out": str(out)}
