"""One accuracy knob: a relative force accuracy, translated into the driver's ``tol``
and the back-end's ε.

``accuracy`` a is the largest relative error of the total reaction F = ΣR (eq. 30) a
user accepts, in the force unit of lcpbench's judge, F₀ = max(|F|, EI/ℓ²)
(:mod:`lcpbench.model.judge`); ``select``'s ``force_tol`` is the same quantity.
The translation (docs/accuracy.md; measured in results/accuracy-translation.md):

- **driver tol = min(a, 1e-3) rad** (never looser than the paper's). On the paper
  grid (108 scenes, N = 140) a cold solve at tol t has a force error of at most
  0.46 t and a judge's bound of at most 0.72 t, for t from 1e-2 to 1e-9 rad.
  ``select`` probes at the same tol (:func:`driver_tol_for`).
- **back-end ε = min(a, 1e-3)**, the residual tolerance of the settings profiles
  (:data:`lcpbench.solvers.base.PROFILES`): accuracy 1e-3, 1e-6 and 1e-9 are the
  profiles ``low``, ``mid`` and ``high``.
- **held to it**: the judge accepts a bound up to min(1e-3, 100 tol), looser than a.
  A converged answer whose bound exceeds a is continued from its own angles at
  tol a / 100, where the judge's own rule guarantees a (:func:`held_to`); an answer
  still over it is returned ``converged=False``, with the reason.
"""

from __future__ import annotations

from collections.abc import Callable

from .model.result import ContactResult, Retry
from .problems.checks import check_number
from .solvers.base import PROFILES, Settings
from .thresholds import FORCE_TOL_PER_RAD

#: the range of ``accuracy`` (relative force error). Below 1e-9 the force is at the
#: round-off of the reference on the paper grid (N = 140): asked 1e-10, the measured
#: error reached 2.6e-10 (results/accuracy-translation.md)
LOWEST, HIGHEST = 1e-9, 0.1
#: the back-end ε and the driver tol never looser than the ``low`` profile's (both 1e-3)
LOOSEST = PROFILES["low"].driver_tol


def check_accuracy(accuracy) -> float:
    """``accuracy`` as a float in [1e-9, 0.1], or ProblemError naming it."""
    return float(check_number("accuracy", accuracy, low=LOWEST, high=HIGHEST,
                              unit="(relative force error)"))


def driver_tol_for(accuracy: float) -> float:
    """The driver tolerance (rad) for a relative force accuracy: min(accuracy, 1e-3)
    (measured on the paper grid: force error ≤ 0.46 tol, judge's bound ≤ 0.72 tol)."""
    return min(float(accuracy), LOOSEST)


def accuracy_settings(accuracy: float) -> Settings:
    """The settings of a relative force accuracy: back-end ε = min(accuracy, 1e-3),
    ``driver_tol`` = :func:`driver_tol_for` (accuracy) = min(accuracy, 1e-3).
    ``accuracy`` is checked."""
    a = check_accuracy(accuracy)
    return Settings(f"accuracy {a:g}", min(a, LOOSEST), driver_tol=driver_tol_for(a))


def held_to(res: ContactResult, accuracy: float,
            again: Callable[[float, ContactResult], ContactResult]) -> ContactResult:
    """``res`` where the judge's force bound meets ``accuracy``; else ``again(tol,
    res)`` (the same solve from ``res``'s angles at tol = accuracy / 100, where the
    judge's rule min(1e-3, 100 tol) guarantees it), that answer if its bound meets
    ``accuracy``, and otherwise an answer marked ``converged=False`` with the reason.
    An answer the judge refused is returned as it is."""
    if not res.converged or res.force_error_bound <= accuracy:
        return res
    tol = accuracy / FORCE_TOL_PER_RAD
    told = (f"the judge's force bound {res.force_error_bound:.1e} exceeds accuracy "
            f"{accuracy:.1e}: continued from its angles at tol {tol:.1e} rad")
    tight = again(tol, res)
    if tight.converged and tight.force_error_bound <= accuracy:
        tight.retries = (Retry("accuracy", told), *tight.retries)
        tight.time_s += res.time_s
        return tight
    res.converged = False
    res.reason = (f"force error bound {res.force_error_bound:.1e} exceeds accuracy "
                  f"{accuracy:.1e} (at tol {tol:.1e} rad: "
                  f"{tight.reason if not tight.converged else 'bound still over it'})")
    res.retries = (*res.retries, Retry("accuracy", told))
    return res


__all__ = ["HIGHEST", "LOWEST", "accuracy_settings", "check_accuracy", "driver_tol_for",
           "held_to"]
