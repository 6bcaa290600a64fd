"""lcpbench: contact modelling of slender soft actuators and a benchmark of its solvers.

>>> import lcpbench
>>> result = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0))
>>> result.total_force  # doctest: +SKIP
"""

from .api import solve
from .bench.select import Selection, select_backend
from .errors import LcpbenchError, ProblemError, SolverNotFound
from .model.result import Certificate, ContactResult
from .problems.scenes import ActuatorScene, CantileverScene

__version__ = "0.1.0"

__all__ = [
    "ActuatorScene",
    "CantileverScene",
    "Certificate",
    "ContactResult",
    "LcpbenchError",
    "Selection",
    "ProblemError",
    "SolverNotFound",
    "select_backend",
    "solve",
]
