"""The judge's verdict from its own numbers, compiled (for the batch kernel and the
one-wall route of a single solve, :func:`lcpbench.api.solve`, which calls it from Python).

:func:`accepted` is whether :func:`lcpbench.model.judge.failed_checks` finds no
failed check, given the numbers the judge kernel
(:func:`lcpbench.model.judge_kernel.judge_answer`) returns, as
:func:`lcpbench.model.judge.verdict_from_stats` hands them to it; every
contact step of the compiled solve is "solved" (the solve kernel stops on any
other). The same comparisons, written so that a NaN fails as it does there.
Judge side only: nothing here comes from the solve kernel. The reasons (the
text of each failed check) are built in Python when a result is read
(:mod:`lcpbench.model.lazy_result`), by ``verdict_from_stats`` itself.
"""

from __future__ import annotations

from numba import njit

# indices into judge_kernel.STATS
TAU, EPS_R, COMP, COMP_ALLOWED, MIN_GAP, CLOSURE = 0, 2, 3, 4, 5, 8
REL_TORQUE, FLOOR_R, R_MIN, TOTAL, NODE, NODE_ALLOWED, PEN, CLOSURE_ALLOWED = (
    10, 11, 12, 13, 14, 15, 19, 20)
UNSTABLE = 21


@njit(cache=True)
def accepted(settled, stats, tol):
    """No check of model.judge.failed_checks fails (the last step solved)."""
    if stats[COMP] > stats[COMP_ALLOWED]:
        return False
    if stats[MIN_GAP] < -stats[PEN]:
        return False
    if stats[CLOSURE] > stats[CLOSURE_ALLOWED]:
        return False
    if stats[REL_TORQUE] > max(10 * tol, 1e-6):
        return False
    if stats[R_MIN] < -max(stats[EPS_R], stats[FLOOR_R]):
        return False
    if not stats[UNSTABLE] <= 0:
        return False
    if not settled:
        return False
    if not stats[TOTAL] <= stats[TAU]:
        return False
    return stats[NODE] <= stats[NODE_ALLOWED]
