"""Back-ends for the contact step and for LCPs, behind one interface.

- :mod:`.registry` — every back-end with its capabilities, availability
  decided without importing native libraries, plug-ins through the
  ``lcpbench.solvers`` entry points;
- :mod:`.runner` — run any back-end on an LCP (:func:`solve_lcp`) or a contact
  step (:func:`solve_step`), nondimensionalised by default, judged by
  lcpbench's own residuals;
- one module per back-end: :mod:`.banded` (active set on the banded factor),
  :mod:`.lemke`, :mod:`.pgs`, :mod:`.qp_osqp`, :mod:`.qp_clarabel`,
  :mod:`.qp_proxsuite`, :mod:`.qp_qpsolvers`, :mod:`.qp_cvxpy`,
  :mod:`.siconos_bridge`.
"""

from __future__ import annotations

from .base import PROFILES, BoxQP, LCPSolution, QPResult, Settings, Status, StepSolution
from .registry import Backend, available_backends, backends, get_backend, get_settings
from .runner import make_step_solver, solve_lcp, solve_step, step_residuals

__all__ = [
    "PROFILES", "Backend", "BoxQP", "LCPSolution", "QPResult", "Settings", "Status",
    "StepSolution", "available_backends", "backends", "get_backend", "get_settings",
    "make_step_solver", "solve_lcp", "solve_step", "step_residuals",
]
