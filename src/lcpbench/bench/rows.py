"""The rows a job hands the store: one shape for every kind of job.

Every row has the fields of :data:`ROW_FIELDS`; a solved one adds the arrays
``forces``, ``gaps``, ``x`` and ``y``. ``certificate`` is the contact
certificate (:class:`~lcpbench.model.result.Certificate` without its
per-joint torque residual, :data:`CERTIFICATE_FIELDS`) for every job that
produced an answer, the baseline included, and None for one that did not.
The sweep adds the scene's columns and the job's identity
(:func:`scene_columns`, :meth:`~lcpbench.bench.jobs.Job.identity`).
"""

from __future__ import annotations

import json
import math

import numpy as np

#: the fields every row has
ROW_FIELDS = ("status", "converged", "reason", "total_force", "outer_iterations",
              "inner_iterations", "wall_time", "solver_time", "setup_time", "certificate")
#: the fields of a certificate (Certificate.to_dict() without "torque_residual")
CERTIFICATE_FIELDS = ("min_gap", "min_force", "complementarity", "closure",
                      "max_torque_residual", "relative_torque_residual")
#: the scene's columns of a row
SCENE_COLUMNS = ("theta", "height", "links", "length", "EI", "weight", "channel")


def certificate_dict(cert) -> dict:
    """A certificate as a row stores it: its fields but the per-joint residual."""
    d = cert.to_dict()
    d.pop("torque_residual", None)
    return d


def solution_row(res) -> dict:
    """The row of a :class:`~lcpbench.model.result.ContactResult`."""
    return {
        "status": "solved" if res.converged else "not_converged",
        "converged": bool(res.converged),
        "reason": res.reason,
        "total_force": float(res.total_force),
        "outer_iterations": int(res.outer_iterations),
        "inner_iterations": int(res.inner_iterations),
        "wall_time": float(res.time_s),
        "solver_time": float(sum(s.solve_time for s in res.steps)),
        # setup: assembling each step, building the back-end's form, its own setup
        "setup_time": float(sum(s.assemble_time + getattr(s, "setup_time", 0.0)
                                for s in res.steps)),
        "certificate": certificate_dict(res.certificate),
        "forces": res.forces, "gaps": res.gaps, "x": res.x, "y": res.y,
    }


_BASELINE_STATUS = {"bad solution": "invalid", "no convergence": "not_converged",
                    "max evaluations": "max_iterations", "time limit": "timeout",
                    "diverged": "diverged"}


def _baseline_certificate(scene, chain, res) -> dict:
    """The baseline's answer certified as any other: by its link angles and reactions."""
    from ..model.result import certify

    alpha = np.asarray(res.alpha, float)
    forces = np.asarray(res.forces, float)
    if (alpha.shape == (chain.links,) and forces.shape == chain.free_nodes.shape
            and np.all(np.isfinite(alpha)) and np.all(np.isfinite(forces))):
        return certificate_dict(certify(chain, alpha, forces, np.zeros_like(forces)))
    return dict.fromkeys(CERTIFICATE_FIELDS, math.nan)


def baseline_row(scene, res) -> dict:
    """The row of a :class:`~lcpbench.reference.root_finding.BaselineResult`."""
    chain = scene.chain()
    gaps = chain.wall - res.y[chain.free_nodes]
    return {
        "status": "solved" if res.valid else _BASELINE_STATUS.get(
            str(res.status).split(":")[0], "not_converged"),
        "converged": bool(res.valid),
        "reason": res.message,
        "total_force": float(res.total_force) if res.valid else 0.0,
        "outer_iterations": int(res.iterations),
        "inner_iterations": int(res.jacobian_evaluations),
        "wall_time": float(res.time_s + res.setup_time_s),
        "solver_time": float(res.time_s),
        "setup_time": float(res.setup_time_s),
        "certificate": _baseline_certificate(scene, chain, res),
        "forces": res.forces, "gaps": gaps, "x": res.x, "y": res.y,
    }


def failed_row(status: str, reason: str, wall_time: float) -> dict:
    """The row of a job that produced no answer (error, timeout, crash)."""
    return {"status": status, "converged": False, "reason": reason, "total_force": 0.0,
            "outer_iterations": 0, "inner_iterations": 0, "wall_time": float(wall_time),
            "solver_time": float("nan"), "setup_time": float("nan"), "certificate": None}


#: the times of a row that a repeat measures again; each becomes the median of the repeats
TIMES = ("wall_time", "solver_time", "setup_time")


def repeated(first: dict, again, repeat: int) -> dict:
    """``first`` with its times the median of ``repeat`` measurements.

    ``again()`` computes the same row once more. Only a converged run is
    repeated (a failure costs the time limit in the metrics, whatever its
    time). The row keeps the first answer and gets ``repeats`` (how many
    solves were timed) and ``wall_time_min``/``wall_time_max`` (their
    spread); a repeat whose answer differs (total force, iterations) is
    named in ``reason``.
    """
    row = dict(first)
    rows = [first]
    if first.get("converged") and repeat > 1:
        rows += [again() for _ in range(repeat - 1)]
    for key in TIMES:
        vals = [float(r[key]) for r in rows if r.get(key) is not None]
        if vals:
            row[key] = float(np.median(vals))
    walls = [float(r["wall_time"]) for r in rows]
    row["repeats"] = len(rows)
    row["wall_time_min"], row["wall_time_max"] = min(walls), max(walls)
    differ = [i for i, r in enumerate(rows[1:], 2)
              if (r["total_force"], r["outer_iterations"], r["inner_iterations"]) !=
              (first["total_force"], first["outer_iterations"], first["inner_iterations"])]
    if differ:
        row["reason"] = (f"{first['reason']} (repeat(s) {', '.join(map(str, differ))} gave "
                         "another answer; the first is kept)")
    return row


def scene_columns(key: str) -> dict:
    """The scene's columns of a row, from its scene key."""
    d = json.loads(key)
    if "sections" in d:  # a SectionedScene: its sharpest θ, total length, mean EI and w
        from .grid import scene_from_key

        scene = scene_from_key(key)
        return {k: getattr(scene, k) for k in SCENE_COLUMNS}
    return {k: d[k] for k in SCENE_COLUMNS}
