"""Heavy chains: SQP steps in the link angles instead of the heights.

A chain with load parameter wℓ³/EI ≥ :data:`~lcpbench.model.angle_step.HEAVY`
sags until links pass the vertical, where the contact step's linearisation in
the node heights (eq. 21) is singular and the globalised driver crawls (200
outer iterations) or its steps turn inaccurate. :func:`run_heavy` finds the
equilibrium by :func:`~lcpbench.model.angle_step.solve_in_angles` (quadratic
near the answer); the wall reactions are the SQP's multipliers. Each SQP step
is recorded as an outer iteration (its max|Δα| as the step size), and
lcpbench's judge decides "converged" from its own exact step and
certificate, exactly as for any other solve. Where the SQP does not converge
the caller runs its usual path.
"""

from __future__ import annotations

import numpy as np

from ..problems.scenes import Chain
from .angle_step import solve_in_angles
from .outer import DriverOutput, DriverStart, StepRecord

#: the SQP stops when a full step moved α by less than this (rad); quadratic
#: convergence makes the last step cheap
ANGLE_TOL = 1e-9
#: from this load parameter wℓ³/EI the height steps get FIRST_TRY outer iterations
#: before the SQP finishes the solve
MODERATE = 10.0
FIRST_TRY = 30
#: the SQP's step limit (issue 19: heavy chains within 30 outer iterations)
ANGLE_STEPS = 30


def no_contact(out: DriverOutput) -> bool:
    """Whether no wall carries a reaction in ``out``."""
    return not (np.any(out.forces_upper) or np.any(out.forces_lower))


def run_heavy(chain: Chain, start: DriverStart | None, tol: float,
              max_outer: int, *, why: str = "a heavy chain") -> DriverOutput | None:
    """The driver's output for a heavy chain, or None when the angle steps did not
    converge within ``max_outer`` (and :data:`ANGLE_STEPS`). The SQP starts from
    ``start``'s angles and multipliers where it has them. ``why`` the SQP ran, for
    the output's reason (also a step of the loading path with a link near the
    vertical, :mod:`lcpbench.model.ramp`)."""
    if max_outer <= 0:
        return None
    begin = None if start is None else np.asarray(start.alpha, float)
    outcome = solve_in_angles(chain, tol=min(ANGLE_TOL, tol),
                              max_iter=min(ANGLE_STEPS, max_outer), start=begin,
                              multipliers=None if start is None else start.multipliers)
    if not outcome.converged:
        return None
    records = [StepRecord(0, "solved", 0.0, 0.0, 1.0, s, e)
               for s, e in zip(outcome.step_sizes, outcome.energies, strict=True)]
    up, lo = outcome.forces_upper, outcome.forces_lower
    free = not (np.any(up) or np.any(lo))
    reason = (f"no contact: the equilibrium clears every wall (found by SQP steps in the "
              f"link angles: {why})" if free
              else f"converged (SQP steps in the link angles: {why})")
    return DriverOutput(outcome.alpha, up, lo, True, reason, records,
                        closure_multiplier=outcome.closure)
