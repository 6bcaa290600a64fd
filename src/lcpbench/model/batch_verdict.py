"""The result judge's rule on its numbers, compiled: which checks fail (for the batch
kernel, the one-wall route of a single solve, :func:`lcpbench.api.solve`, and
:func:`lcpbench.model.judge.failed_checks`, which call it from Python).

:func:`failed` says which checks of :mod:`lcpbench.model.judge` fail, as bits in the
order of its reasons, given the numbers the judge kernel's entries
(:mod:`lcpbench.model.judge_kernel`) return; :func:`accepted` is that none does. The
rule is written here once: :func:`lcpbench.model.judge.failed_checks` writes the reason of each bit set.
A NaN in a number passes checks 3-6 (as it did when the rule was written twice; the
total and per-node bounds and the stability count fail on a NaN). Check 2 (the last step SOLVED) is the caller's:
every contact step of the compiled solve is "solved" (the solve kernel stops on any
other). Judge side only: nothing here comes from the solve kernel.
"""

from __future__ import annotations

from numba import njit

from ..thresholds import TORQUE_FLOOR, TORQUE_PER_RAD

# indices into judge_checks.STATS
TAU, EPS_R, COMP, COMP_ALLOWED, MIN_GAP, CLOSURE = 0, 2, 3, 4, 5, 8
REL_TORQUE, FLOOR_R, R_MIN, TOTAL, NODE, NODE_ALLOWED, PEN, CLOSURE_ALLOWED = (
    10, 11, 12, 13, 14, 15, 19, 20)
UNSTABLE = 21
#: the bits of :func:`failed`, in the order of model.judge.failed_checks' reasons
(FAILS_COMPLEMENTARITY, FAILS_PENETRATION, FAILS_CLOSURE, FAILS_TORQUE, FAILS_SIGN,
 FAILS_STABILITY, FAILS_UNSETTLED, FAILS_TOTAL, FAILS_NODE) = (1, 2, 4, 8, 16, 32, 64, 128, 256)


@njit(cache=True)
def failed(settled, stats, tol):
    """The checks 3-8 of model.judge that fail on the judge kernel's ``stats`` (a judge
    step that ``settled``, driver tolerance ``tol``), as FAILS_* bits (0: none)."""
    mask = 0
    if stats[COMP] > stats[COMP_ALLOWED]:
        mask |= FAILS_COMPLEMENTARITY
    if stats[MIN_GAP] < -stats[PEN]:
        mask |= FAILS_PENETRATION
    if stats[CLOSURE] > stats[CLOSURE_ALLOWED]:
        mask |= FAILS_CLOSURE
    if stats[REL_TORQUE] > max(TORQUE_PER_RAD * tol, TORQUE_FLOOR):
        mask |= FAILS_TORQUE
    if stats[R_MIN] < -max(stats[EPS_R], stats[FLOOR_R]):
        mask |= FAILS_SIGN
    if not stats[UNSTABLE] <= 0:
        mask |= FAILS_STABILITY
    if not settled:
        mask |= FAILS_UNSETTLED
    elif not stats[TOTAL] <= stats[TAU]:
        mask |= FAILS_TOTAL
    elif not stats[NODE] <= stats[NODE_ALLOWED]:
        mask |= FAILS_NODE
    return mask


@njit(cache=True)
def accepted(settled, stats, tol):
    """No check of model.judge fails (the last step solved): :func:`failed` is 0."""
    return failed(settled, stats, tol) == 0
