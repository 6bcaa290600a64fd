"""lcpbench: contact modelling of slender soft actuators and a benchmark of its solvers.

>>> import lcpbench
>>> result = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0))
>>> result.total_force  # doctest: +SKIP

The names below are loaded on first use (PEP 562): ``import lcpbench`` costs
next to nothing, ``lcpbench.solve`` loads the model and the solver registry
(numpy and scipy), and only ``lcpbench.select_backend`` loads the benchmark
harness. Plotting and the native solver libraries load when a figure or a
back-end needs them.
"""

from importlib import import_module as _import_module
from importlib.metadata import PackageNotFoundError as _PackageNotFoundError
from importlib.metadata import version as _version

try:
    __version__ = _version("lcpbench")
except _PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

#: public name -> module that defines it
_EXPORTS = {
    "solve": "lcpbench.api",
    "solve_path": "lcpbench.api",
    "pull_out": "lcpbench.studies.pull_out",
    "FrictionResult": "lcpbench.model.friction_result",
    "solve_many": "lcpbench.studies.batch",
    "stable_states": "lcpbench.studies.states",
    "sensitivities": "lcpbench.model.sensitivity",
    "design": "lcpbench.studies.design",
    "ActuatorScene": "lcpbench.problems.scenes",
    "CantileverScene": "lcpbench.problems.cantilever",
    "Section": "lcpbench.problems.sections",
    "SectionedScene": "lcpbench.problems.sections",
    "anchoring_actuator": "lcpbench.problems.sections",
    "WallProfile": "lcpbench.problems.walls",
    "load_profile_csv": "lcpbench.problems.walls",
    "Certificate": "lcpbench.model.result",
    "ContactResult": "lcpbench.model.result",
    "LcpbenchError": "lcpbench.errors",
    "ProblemError": "lcpbench.errors",
    "SolverNotFound": "lcpbench.errors",
    "Selection": "lcpbench.solvers.selection",
    "select_backend": "lcpbench.bench.select",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'lcpbench' has no attribute {name!r}")
    value = getattr(_import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))
