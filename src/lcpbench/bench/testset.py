"""The contact steps as a qpbenchmark test set, and results in qpbenchmark's row schema.

``lcpbench export-testset --grid paper --out DIR`` writes:

``DIR/data/<name>.npz``
    one bound-constrained QP per file, ``minimise ½ xᵀPx + qᵀx subject to
    lb ≤ x ≤ ub``, in the layout of ``qpsolvers.Problem.save`` (keys P, q,
    G, h, A, b, lb, ub; the absent G, h, A, b stored as empty object arrays,
    which ``qpsolvers.Problem.load`` reads back as None), so
    ``qpbenchmark.Problem.load`` (which calls it) loads each file. Compressed
    (``np.savez_compressed``; ``np.load`` reads both). P is dense, as that
    layout stores it.
``DIR/lcpbench_contact.py``
    a qpbenchmark ``TestSet`` over those files (``python lcpbench_contact.py
    run`` with qpbenchmark installed), as the free-for-all test set does.
``DIR/problems.csv``
    what each problem is: scene, which step, size, condition number of P,
    and the optimal cost found by lcpbench's active set at ``high``.
``DIR/README.md``
    what the problems are and how to run qpbenchmark on them.
``DIR/results/lcpbench_contact.csv``
    (unless ``results=False``) every chosen lcpbench back-end on every problem
    in qpbenchmark's results schema: problem, solver, settings, runtime,
    found, primal_residual, dual_residual, duality_gap, with the residuals
    computed by qpsolvers' own ``Solution`` methods (qpbenchmark's
    definitions) and ``found`` lcpbench's judged SOLVED; a failure is written
    as qpbenchmark writes one (residuals inf).

The problems (paper eqs. 25-30, nondimensionalised: lengths by ℓ, forces by
EI/ℓ², as every back-end receives them): for each scene, the contact step
at the driver's first configuration (the unconstrained arc clipped to the
wall, ``first``) and at the converged configuration of the scene's
reference (``converged``). x are the free node heights u/ℓ, P the
pentadiagonal Hessian H (its condition number grows as N⁴), q the linear
term c, ub the wall h/ℓ at the nodes that may touch it (+inf at the
others), lb the second wall of a channel (else −inf).
"""

from __future__ import annotations

import csv
import math
import os
import time
from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError

#: lcpbench settings profile -> qpbenchmark settings name
SETTINGS_NAMES = {"default": "default", "low": "low_accuracy", "mid": "mid_accuracy",
                  "high": "high_accuracy"}
#: qpbenchmark's results columns (qpbenchmark/results.py)
RESULT_COLUMNS = ("problem", "solver", "settings", "runtime", "found", "primal_residual",
                  "dual_residual", "duality_gap")
PROBLEM_COLUMNS = ("name", "step", "theta", "height", "links", "length", "EI", "weight",
                   "channel", "n", "cond_P", "optimal_cost")
STEPS = ("first", "converged")


@dataclass
class ExportedProblem:
    """One exported QP and what it is."""

    name: str
    step_kind: str  # "first" or "converged"
    scene: object
    step: object  # the ContactStep (kept to solve it with lcpbench's back-ends)
    P: np.ndarray
    q: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    cond: float
    optimal_cost: float

    def meta(self) -> dict:
        s = self.scene
        return {"name": self.name, "step": self.step_kind, "theta": s.theta,
                "height": s.height, "links": s.links, "length": s.length, "EI": s.EI,
                "weight": s.weight, "channel": int(s.channel), "n": self.q.size,
                "cond_P": self.cond, "optimal_cost": self.optimal_cost}


def problem_name(scene, kind: str) -> str:
    """A file-safe qpbenchmark problem name, e.g. ``LCPB-N140-T150-H3-first``."""
    def num(v):
        return f"{v:g}".replace(".", "p").replace("-", "m")

    name = f"LCPB-N{scene.links}-T{num(scene.theta)}-H{num(scene.height)}"
    default = type(scene)(theta=scene.theta, height=scene.height, links=scene.links)
    for key, tag in (("length", "L"), ("EI", "EI"), ("weight", "W")):
        if getattr(scene, key) != getattr(default, key):
            name += f"-{tag}{num(getattr(scene, key))}"
    if scene.channel:
        name += "-C"
    return f"{name}-{kind}"


def _cond(step) -> float:
    """cond(P) of the scaled step from the eigenvalues of its banded Hessian."""
    from scipy.linalg import eigvals_banded

    from ..model.step_solver import step_qp

    b = step_qp(step, True).bands
    ev = eigvals_banded(b, lower=True)
    return float(ev.max() / ev.min()) if ev.min() > 0 else math.inf


def scene_problems(scene) -> list[ExportedProblem]:
    """The first and the converged contact step of ``scene`` as exported QPs."""
    from ..api import solve
    from ..model.chain import alpha_from_heights, heights
    from ..model.compiled_driver import assemble_step
    from ..model.step_solver import solve_step, step_qp
    from .jobs import REFERENCE_TOL

    chain = scene.chain()
    u0 = np.clip(heights(chain, chain.rest_alpha), chain.lower, chain.upper)
    alpha0 = alpha_from_heights(chain, u0, chain.rest_alpha)
    configs = []
    if alpha0 is not None:
        configs.append(("first", alpha0))
    ref = solve(scene, solver="active-set", tol=REFERENCE_TOL, settings="high")
    if ref.converged:
        configs.append(("converged", np.asarray(ref.alpha, float)))
    out = []
    for kind, alpha in configs:
        step = assemble_step(chain, alpha)
        qp = step_qp(step, True)
        sol = solve_step(step, "active-set", "high")
        cost = math.nan
        if sol.solved:
            x = sol.u / step.length_scale
            cost = float(0.5 * x @ (qp.P @ x) + qp.c @ x)
        out.append(ExportedProblem(problem_name(scene, kind), kind, scene, step,
                                   qp.dense(), qp.c.copy(), qp.lower.copy(),
                                   qp.upper.copy(), _cond(step), cost))
    return out


def save_problem(p: ExportedProblem, path: str | os.PathLike) -> None:
    """One QP in ``qpsolvers.Problem.save``'s layout (compressed)."""
    none = np.array(None)  # qpsolvers stores an absent matrix so; load gives None
    np.savez_compressed(path, P=p.P, q=p.q, G=none, h=none, A=none, b=none, lb=p.lb,
                        ub=p.ub)


def load_problem(path: str | os.PathLike) -> dict:
    """A saved QP as a dict of arrays (None for absent ones), as qpsolvers reads it."""
    data = np.load(path, allow_pickle=False)
    out = {}
    for k in ("P", "q", "G", "h", "A", "b", "lb", "ub"):
        try:
            out[k] = data[k]
        except ValueError:  # an object array: absent
            out[k] = None
    return out


def qp_residuals(P, q, lb, ub, x, z_box) -> tuple[float, float, float]:
    """(primal residual, dual residual, duality gap) by qpsolvers' ``Solution`` methods."""
    import qpsolvers

    problem = qpsolvers.Problem(P, q, None, None, None, None, lb, ub)
    sol = qpsolvers.Solution(problem)
    sol.found, sol.x, sol.z_box = True, x, z_box
    sol.z, sol.y = np.empty(0), np.empty(0)
    return (float(sol.primal_residual()), float(sol.dual_residual()),
            float(sol.duality_gap()))


def result_rows(problems: list[ExportedProblem], solvers: list[str], settings: list[str],
                progress=None) -> list[dict]:
    """Every back-end at every settings on every problem, as qpbenchmark result rows.

    Each step is solved by :func:`~lcpbench.model.step_solver.solve_step` (the
    judged status and the same clock as in the sweep: ``runtime`` is the wall
    time of the call, building the back-end's form included, after one untimed
    solve per back-end and settings); ``x`` is u/ℓ
    and ``z_box`` the signed bound multiplier in units of EI/ℓ² (positive at
    the upper bound, as qpsolvers signs it).
    """
    from ..model.step_solver import solve_step

    if problems:  # first calls (imports, JIT, caches) are not charged to a problem
        for b in solvers:
            for s in settings:
                solve_step(problems[0].step, b, s)
    rows = []
    for p in problems:
        L, F = p.step.length_scale, p.step.force_scale
        for b in solvers:
            for s in settings:
                t0 = time.perf_counter()
                sol = solve_step(p.step, b, s)
                runtime = time.perf_counter() - t0
                row = {"problem": p.name, "solver": b, "settings": SETTINGS_NAMES[s],
                       "runtime": runtime, "found": bool(sol.solved),
                       "primal_residual": math.inf, "dual_residual": math.inf,
                       "duality_gap": math.inf}
                if sol.solved:
                    x = sol.u / L
                    z = (sol.forces_upper - sol.forces_lower) / F
                    row["primal_residual"], row["dual_residual"], row["duality_gap"] = (
                        qp_residuals(p.P, p.q, p.lb, p.ub, x, z))
                rows.append(row)
                if progress is not None:
                    progress(len(rows), p, b, s)
    return rows


def write_results(rows: list[dict], path: str | os.PathLike) -> None:
    """qpbenchmark's results CSV: its columns, sorted by problem, solver, settings."""
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=RESULT_COLUMNS)
        w.writeheader()
        for r in sorted(rows, key=lambda r: (r["problem"], r["solver"], r["settings"])):
            w.writerow({k: (repr(float(r[k])) if isinstance(r[k], float) else r[k])
                        for k in RESULT_COLUMNS})


#: the file ``lcpbench report --format qpbenchmark`` writes
SWEEP_RESULTS = "qpbenchmark_results.csv"
#: the cold driver schemes: their runs keep the back-end's name as the solver
_COLD = ("globalised", "hybr", "lm")


def _scaled_residuals(row: dict) -> tuple[float, float, float]:
    """(primal, dual, gap) of a whole answer from its certificate, in the step's units.

    Lengths over ℓ, forces over EI/ℓ², moments over EI/ℓ (the exported steps'
    scaling): primal = penetration of a wall or the pin off y = 0; dual = a
    pulling wall or the torque residual relative to the largest spring torque
    (stationarity of the energy); gap = the largest |gᵢRᵢ|. Infinite without an
    answer, as qpbenchmark writes a solution not found.
    """
    import json

    cert = row.get("certificate")
    if isinstance(cert, str):
        cert = json.loads(cert)
    if not cert:
        return math.inf, math.inf, math.inf
    L, EI = float(row["length"]), float(row["EI"])
    F = EI / L**2
    vals = [float(cert.get(k, math.nan)) for k in ("min_gap", "closure", "min_force",
                                                   "relative_torque_residual",
                                                   "complementarity")]
    if not all(math.isfinite(v) for v in vals):
        return math.inf, math.inf, math.inf
    min_gap, closure, min_force, rel_torque, compl = vals
    return (max(0.0, -min_gap, abs(closure)) / L, max(0.0, -min_force / F, rel_torque),
            abs(compl) / (F * L))


def run_result_rows(runs: list[dict]) -> list[dict]:
    """Stored sweep runs as qpbenchmark result rows (one per run).

    ``problem``: the scene's name (:func:`problem_name`, kind ``solve``: the
    whole contact solve, every step); ``solver``: the back-end, with the driver
    scheme in brackets when it is not the cold one (``active-set[globalised+quadratic]``);
    ``settings``: qpbenchmark's names of the profiles (the baselines'
    ``default``), with ``@tol=`` appended where a run's driver tolerance is not
    its profile's; ``runtime``: the stored wall time (s); ``found``: lcpbench's
    judge accepted it (``converged``); residuals by :func:`_scaled_residuals`.
    """
    from .grid import scene_from_key
    from .jobs import PROFILE_TOL

    out, seen = [], set()
    for r in runs:
        solver = r["backend"] if r["method"] in _COLD else f"{r['backend']}[{r['method']}]"
        profile = r["settings"] if r["settings"] in SETTINGS_NAMES else "default"
        settings = SETTINGS_NAMES[profile]
        if r["settings"] in PROFILE_TOL and float(r["tol"]) != PROFILE_TOL[r["settings"]]:
            settings += f"@tol={float(r['tol']):g}"
        row = {"problem": problem_name(scene_from_key(r["scene"]), "solve"),
               "solver": solver, "settings": settings, "runtime": float(r["wall_time"]),
               "found": bool(r["converged"])}
        key = (row["problem"], solver, settings)
        if key in seen:
            raise ProblemError(f"two runs are one qpbenchmark row {key}: report a store of "
                               "one driver tolerance per profile")
        seen.add(key)
        row["primal_residual"], row["dual_residual"], row["duality_gap"] = (
            _scaled_residuals(r))
        out.append(row)
    return out


def read_results(path: str | os.PathLike) -> list[dict]:
    """The rows of a qpbenchmark results CSV, typed as qpbenchmark types them."""
    with open(path, newline="") as fh:
        reader = csv.DictReader(fh)
        if tuple(reader.fieldnames or ()) != RESULT_COLUMNS:
            raise ProblemError(f"{path}: columns {reader.fieldnames}, expected "
                               f"{list(RESULT_COLUMNS)}")
        out = []
        for r in reader:
            if r["found"] not in ("True", "False"):
                raise ProblemError(f"{path}: 'found' must be True or False, got {r['found']!r}")
            out.append({"problem": r["problem"], "solver": r["solver"],
                        "settings": r["settings"], "runtime": float(r["runtime"]),
                        "found": r["found"] == "True",
                        **{k: float(r[k]) for k in RESULT_COLUMNS[5:]}})
        return out
