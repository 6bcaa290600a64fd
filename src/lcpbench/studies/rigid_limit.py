"""Elastic walls as k grows: how fast the force reaches the rigid wall's (issue 17).

For one discretised chain (fixed N) the elastic step is the rigid step's QP with
the penalty Σ ½ k_i δ_i², so the answer moves from the rigid one by O(1/k)
once the walls are much stiffer than the chain is locally. The chain's local
stiffness against a node's displacement is about EI/a³, and a node's wall
spring k·a, so the regime starts near k ≈ EI/a⁴ (N/mm per mm), which grows
like N⁴. Below it the wall is softer than a link and the contact zone's edges
are boundary layers of the continuous beam on a Winkler foundation (width
(4EI/k)^{1/4}), and the force converges more slowly. :func:`rigid_limit`
measures both: the force against k, its error against the rigid wall's, and
the log-log slope between successive k.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..api import solve


@dataclass
class RigidLimit:
    """Forces against the Winkler stiffness k for one scene (fixed N)."""

    scene: Any  # an ActuatorScene or CantileverScene
    rigid_force: float
    stiffness: list[float] = field(default_factory=list)  # N/mm per mm
    total_force: list[float] = field(default_factory=list)  # N
    relative_error: list[float] = field(default_factory=list)  # |F(k) − F_rigid| / F_rigid
    max_indentation: list[float] = field(default_factory=list)  # mm
    max_pressure: list[float] = field(default_factory=list)  # N/mm
    converged: list[bool] = field(default_factory=list)

    @property
    def crossover(self) -> float:
        """EI/a⁴ (N/mm per mm): where a node's wall spring k·a matches EI/a³."""
        s = self.scene
        a = s.length / int(s.links)
        return s.EI / a**4

    def slopes(self) -> np.ndarray:
        """d log(error) / d log(k) between successive stiffnesses."""
        k, e = np.log(self.stiffness), np.log(self.relative_error)
        return np.diff(e) / np.diff(k)


def rigid_limit(scene, stiffness, *, tol: float = 1e-9, solver: str = "auto") -> RigidLimit:
    """Solve ``scene`` with rigid walls and with each Winkler ``stiffness``."""
    rigid = solve(replace(scene, wall_stiffness=math.inf), solver, tol, max_outer=400)
    out = RigidLimit(scene, rigid.total_force)
    for k in stiffness:
        res = solve(replace(scene, wall_stiffness=float(k)), solver, tol, max_outer=400)
        out.stiffness.append(float(k))
        out.total_force.append(res.total_force)
        out.relative_error.append(abs(res.total_force - rigid.total_force)
                                  / abs(rigid.total_force))
        out.max_indentation.append(res.max_indentation)
        out.max_pressure.append(res.max_pressure)
        out.converged.append(bool(res.converged and rigid.converged))
    return out
