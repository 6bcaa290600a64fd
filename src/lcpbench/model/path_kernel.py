"""The loading path's height steps in one kernel call (:mod:`lcpbench.model.ramp`).

:func:`lcpbench.model.ramp.follow_load` solves a scene at the load fractions s = d,
2d, …, 1 of its bend angles, each step started from the last one's answer. Where the
solve kernel takes the chain (the default back-end, the globalised or Newton scheme, a
chain of the kernel's layout, neither large nor heavy), a run of those steps in the node
heights is :func:`walk_heights`: one call of :func:`~.compiled_kernel.solve_chain` per
step, the rest shape of step j the j-th row of the path's rest shapes (the scene's
``rest_shapes``: nothing else of the chain depends on s), each step started from the
secant through the last two answers (:func:`predicted`) and warm-started from the last
one's contact step as a continuation's start is (its heights and active sets, bits 0–2
of the kernel's flags: :func:`lcpbench.model.kernel_call.call_kernel`), the steps before
the path's last solved to the path's looser tolerance. The run stops after a step whose answer
has a link near the vertical (where the path takes SQP steps in the link angles) and
before a step that does not converge; the Python loop of ``follow_load`` takes over
there, with the same rules for every back-end. Loaded through
:func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .compiled_kernel import CONVERGED, solve_chain  # once (numba_cache)

#: the kernel's warm-start flags of a converged step: heights, upper and lower sets given
WARM_ALL = 7


@njit(cache=True)
def near_vertical(alpha, limit):
    """Whether a link of ``alpha`` (rad) has |cos α_i| ≤ ``limit``."""
    for i in range(alpha.size):
        if abs(np.cos(alpha[i])) <= limit:
            return True
    return False


@njit(cache=True)
def predicted(last, before):
    """The start of the next step of the path: the secant through the last two answers
    ``before``, ``last`` (rad; equal steps in s: 2 last − before), or ``last`` where
    ``before`` is empty (the first step of a run, or after a step solved another way)."""
    if before.size != last.size:
        return last
    return 2.0 * last - before


@njit(cache=True)
def walk_heights(rest_alpha, a, jl, jr, k, rest_joint, link_load, nodal_load, fs, lo, hi, L,
                 F, cu, cl, tol, path_tol, max_outer, begin, start_alpha, before, warm_u,
                 warm_up, warm_lo, warm_flags, max_iter, request, newton, limit, predict):
    """(steps, outputs, before): the height steps of the loading path from step ``begin`` on
    (``rest_alpha[j]``, ``rest_joint[j]``: the rest shape at the path's j-th fraction; the
    other arguments :func:`~.compiled_kernel.solve_chain`'s, the start those of step
    ``begin``), each started from the secant through the last two answers
    (:func:`predicted`; ``before``: the answer before ``start_alpha``, empty where there
    is none; ``predict`` False: from the last answer itself) with the last one's heights
    and active sets, while they converge and the
    last answer has no link within ``limit`` of the vertical (:func:`near_vertical`; a
    negative ``limit``: never). The steps before the path's last are solved to
    ``path_tol``, the last to ``tol``. ``steps``: how many converged, from ``begin``;
    ``outputs``: solve_chain's of the last of them (where none did, of the first, not
    converged); ``before``: the answer before that last one (empty where none, or
    without ``predict``)."""
    last = rest_alpha.shape[0] - 1
    got = solve_chain(rest_alpha[begin], a, jl, jr, k, rest_joint[begin], link_load,
                      nodal_load, fs, lo, hi, L, F, cu, cl, tol if begin == last else path_tol,
                      max_outer, predicted(start_alpha, before), warm_u, warm_up, warm_lo,
                      warm_flags, max_iter, request, newton)
    if got[0] != CONVERGED:
        return 0, got, np.empty(0)
    steps, previous = 1, start_alpha if predict else np.empty(0)
    for j in range(begin + 1, last + 1):
        if near_vertical(got[1], limit):
            break
        sigma = got[5]
        nxt = solve_chain(rest_alpha[j], a, jl, jr, k, rest_joint[j], link_load, nodal_load,
                          fs, lo, hi, L, F, cu, cl, tol if j == last else path_tol, max_outer,
                          predicted(got[1], previous), got[4], sigma > 0.0, sigma < 0.0,
                          WARM_ALL, max_iter, request, newton)
        if nxt[0] != CONVERGED:
            break
        if predict:
            previous = got[1]
        got = nxt
        steps += 1
    return steps, got, previous
