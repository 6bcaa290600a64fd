"""Back-ends for LCPs and bound-constrained QPs, behind one interface.

Solvers know LCP and box-QP data only, nothing of actuators (the contact
step is handed to them by :mod:`lcpbench.model.step_solver`).

- :mod:`.registry` — every back-end with its capabilities, availability
  decided without importing native libraries, plug-ins through the
  ``lcpbench.solvers`` entry points;
- :mod:`.judge` — the one acceptance rule, on lcpbench's own residuals;
- :mod:`.runner` — run any back-end on an LCP (:func:`solve_lcp`);
- :mod:`.selection` — the :class:`Selection` of a back-end that
  ``lcpbench.solve(scene, solver=selection)`` accepts;
- one module per back-end: :mod:`.banded` (active set on the banded factor),
  :mod:`.lemke`, :mod:`.pgs`, :mod:`.qp_osqp`, :mod:`.qp_clarabel`,
  :mod:`.qp_proxsuite`, :mod:`.qp_qpsolvers`, :mod:`.qp_cvxpy`,
  :mod:`.siconos_bridge`.
"""

from __future__ import annotations

from .base import PROFILES, BoxQP, LCPSolution, QPResult, Settings, Status, StepSolution
from .registry import Backend, available_backends, backends, get_backend, get_settings
from .runner import solve_lcp

__all__ = [
    "PROFILES", "Backend", "BoxQP", "LCPSolution", "QPResult", "Settings", "Status",
    "StepSolution", "available_backends", "backends", "get_backend", "get_settings",
    "solve_lcp",
]
