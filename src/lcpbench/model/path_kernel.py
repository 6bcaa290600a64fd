"""The loading path's height steps in one kernel call (:mod:`lcpbench.model.ramp`).

:func:`lcpbench.model.ramp.follow_load` solves a scene at the load fractions s = d,
2d, …, 1 of its bend angles, each step started from the last one's answer. Where the
solve kernel takes the chain (the default back-end, the globalised or Newton scheme, a
chain of the kernel's layout, neither large nor heavy), a run of those steps in the node
heights is :func:`walk_heights`: one call of :func:`~.compiled_kernel.solve_chain` per
step, the rest shape of step j the j-th row of the path's rest shapes (the scene's
``rest_shapes``: nothing else of the chain depends on s), each step warm-started from
the last one's answer as a continuation's start is (its angles; its last contact step's
heights and active sets, bits 0–2 of the kernel's flags:
:func:`lcpbench.model.kernel_call.call_kernel`). The run stops after a step whose answer
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
def walk_heights(rest_alpha, a, jl, jr, k, rest_joint, link_load, nodal_load, fs, lo, hi, L,
                 F, cu, cl, tol, max_outer, begin, start_alpha, warm_u, warm_up, warm_lo,
                 warm_flags, max_iter, request, newton, limit):
    """(steps, outputs): the height steps of the loading path from step ``begin`` on
    (``rest_alpha[j]``, ``rest_joint[j]``: the rest shape at the path's j-th fraction; the
    other arguments :func:`~.compiled_kernel.solve_chain`'s, the start those of step
    ``begin``), each started from the last one's answer, while they converge and the
    last answer has no link within ``limit`` of the vertical (:func:`near_vertical`; a
    negative ``limit``: never). ``steps``: how many converged, from ``begin``; ``outputs``:
    solve_chain's of the last of them (where none did, of the first, not converged)."""
    got = solve_chain(rest_alpha[begin], a, jl, jr, k, rest_joint[begin], link_load,
                      nodal_load, fs, lo, hi, L, F, cu, cl, tol, max_outer, start_alpha,
                      warm_u, warm_up, warm_lo, warm_flags, max_iter, request, newton)
    if got[0] != CONVERGED:
        return 0, got
    steps = 1
    for j in range(begin + 1, rest_alpha.shape[0]):
        if near_vertical(got[1], limit):
            break
        sigma = got[5]
        nxt = solve_chain(rest_alpha[j], a, jl, jr, k, rest_joint[j], link_load, nodal_load,
                          fs, lo, hi, L, F, cu, cl, tol, max_outer, got[1], got[4],
                          sigma > 0.0, sigma < 0.0, WARM_ALL, max_iter, request, newton)
        if nxt[0] != CONVERGED:
            break
        got = nxt
        steps += 1
    return steps, got
