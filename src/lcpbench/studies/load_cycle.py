"""A load–unload cycle: the actuator inflated against its wall and deflated again (issue 39).

The input pressure P (kPa) is ramped up through ``pressures`` and back down, at a fixed
wall height h, as one loading path (:func:`lcpbench.solve_path`: each state solved from
the last, θ from the actuator's calibration θ(P), eqs. 40–42 of the paper). With wall
friction μ > 0 the contact force depends on the way the state was reached: the nodes
that slide along the wall as the chain bends are held back by friction, in the
opposite sense on the way up and on the way down, so the loading and unloading forces
at the same pressure differ (hysteresis). With μ = 0 the path is the paper's model,
state by state, and both branches are the frictionless answer.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ProblemError
from ..problems.calibrations import get_calibration
from ..problems.checks import describe
from ..problems.scenes import ActuatorScene


@dataclass
class LoadCycle:
    """The states of a load–unload cycle, in the path's order (loading, then unloading).

    ``pressure`` (kPa) and ``theta`` (degrees) per state; ``loading``: True on the way
    up (the peak is the last loading state); ``force``: ΣN over every wall (N) on the
    path; ``frictionless``: :func:`lcpbench.solve` of the same scene with μ = 0 at the
    same θ (N); ``converged`` per state; ``path``: the
    :class:`~lcpbench.model.friction_result.FrictionResult` of each state.
    """

    pressure: np.ndarray
    theta: np.ndarray
    loading: np.ndarray
    force: np.ndarray
    frictionless: np.ndarray
    converged: np.ndarray
    path: list = field(default_factory=list)

    def branch(self, loading: bool) -> tuple[np.ndarray, np.ndarray]:
        """(pressures, forces) of one branch, pressure ascending (kPa, N)."""
        keep = self.loading == loading
        if not loading:  # the peak belongs to both branches
            keep[int(np.flatnonzero(self.loading)[-1])] = True
        order = np.argsort(self.pressure[keep], kind="stable")
        return self.pressure[keep][order], self.force[keep][order]


def load_cycle(scene: ActuatorScene, pressures, *, actuator="1", tol: float = 1e-8,
               max_outer: int = 100) -> LoadCycle:
    """Ramp the pressure up through ``pressures`` and back down at the scene's height.

    Parameters
    ----------
    scene : ActuatorScene
        The wall, friction and end conditions (its θ is replaced by θ(P)).
    pressures : sequence of float
        Increasing input pressures P (kPa); the cycle is P_1 … P_n … P_1.
    actuator : "1", "2", "3" or Calibration
        The pressure → θ calibration (default the paper's actuator 1, eq. 40).
    tol : the outer loop's threshold on max|Δα| (rad) per state.

    Returns
    -------
    LoadCycle
    """
    from ..api import solve, solve_path

    if not isinstance(scene, ActuatorScene):
        raise ProblemError(f"load_cycle takes an ActuatorScene, got {describe(scene)}")
    p = np.asarray(pressures, float).ravel()
    if p.size < 2 or not np.all(np.isfinite(p)) or np.any(np.diff(p) <= 0):
        raise ProblemError(f"pressures must be at least two increasing numbers (kPa), got "
                           f"{describe(pressures)}")
    cal = get_calibration(actuator, param="actuator")
    cycle = np.concatenate([p, p[-2::-1]])
    theta = np.array([float(cal.theta(v)) for v in cycle])
    loading = np.arange(cycle.size) < p.size
    path = solve_path(replace(scene, theta=float(theta[0])),
                      [{"theta": float(t)} for t in theta], tol=tol, max_outer=max_outer)
    plain = replace(scene, friction=0.0, left_end="pinned", right_end="pinned", pull=0.0)
    ref = {float(t): solve(replace(plain, theta=float(t)), tol=tol).total_force
           for t in theta[:p.size]}
    return LoadCycle(cycle, theta, loading, np.array([r.total_force for r in path]),
                     np.array([ref[float(t)] for t in theta]),
                     np.array([r.converged for r in path]), path)
