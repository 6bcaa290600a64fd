"""The one acceptance rule: when lcpbench calls a back-end's answer SOLVED.

A back-end reports its own status; lcpbench then recomputes the residuals
from the primal unknowns alone (:func:`lcpbench.solvers.base.lcp_residuals`
for an LCP, the contact step's own residuals in :mod:`lcpbench.model`) and
keeps SOLVED only when the scaled natural residual ``||min(z, w)||_inf`` is
at most :func:`accept_tol`. Both runners (LCPs in :mod:`.runner`, contact
steps in :mod:`lcpbench.model.step_solver`) apply :func:`verdict` to every
back-end's answer, so there is one rule for what lcpbench calls SOLVED. A
back-end's own status mapping (Lemke's self-check, the Siconos bridge's
reading of Siconos' ``info``) is that back-end's word, which the verdict can
only demote, never promote.
"""

from __future__ import annotations

import numpy as np

from ..thresholds import FLOOR_ULPS  # the round-off floor, in ulps of the residual's terms
from .base import Settings, Status

EPS = np.finfo(float).eps
#: A solution is accepted as SOLVED when its scaled natural residual is at most
#: ACCEPT_FACTOR × the requested tolerance ("default" requests DEFAULT_TOL), or
#: the round-off floor, whichever is larger.
ACCEPT_FACTOR = 10.0
DEFAULT_TOL = 1e-6


def requested(settings: Settings) -> float:
    """The accuracy asked of each step: the settings' ``eps``, else DEFAULT_TOL."""
    return settings.eps if settings.eps is not None else DEFAULT_TOL


def accept_tol(settings: Settings, size: float = 0.0) -> float:
    """Largest natural residual accepted as SOLVED; ``size`` is S above."""
    return max(ACCEPT_FACTOR * requested(settings), FLOOR_ULPS * EPS * size)


def verdict(status: Status, natural: float, bound: float) -> tuple[Status, str]:
    """The status lcpbench reports for a back-end's ``status`` and residual.

    A SOLVED whose natural residual exceeds ``bound`` (or is NaN) becomes
    INACCURATE with a message saying so; any other status is kept. The
    judge only ever demotes: it never promotes a back-end's failure.
    """
    if status is Status.SOLVED and not natural <= bound:
        return Status.INACCURATE, (f"lcpbench's natural residual {natural:.2e} exceeds "
                                   f"{bound:.1e}")
    return status, ""
