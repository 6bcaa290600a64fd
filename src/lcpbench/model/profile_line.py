"""A scene of a plane against a wall of any profile, solved and judged in one kernel call.

:func:`profile_attempt` is one attempt of :func:`lcpbench.studies.batch_compiled.solve_line`'s
scene-by-scene loop for a scene against one wall of any profile (no channel) whose
unconstrained arc lies far past the wall (:func:`lcpbench.model.wall_free.arc_far`: the
wall-free search has nothing to look for), in one call, by the functions of the single
solve:

1. the start's lagged reactions, the net reactions of the answer whose last step
   warm-starts it (:func:`lcpbench.model.wall_kernel.split_by_wall`, as
   :func:`lcpbench.model.kernel_call.call_profile_kernel` sets them);
2. the profile kernel's solve (:func:`lcpbench.model.compiled_kernel.solve_profile_chain`);
3. the judge kernel's entry :func:`~lcpbench.model.judge_kernel.judge_walls` on the
   answer, and its verdict from the judge's numbers alone
   (:func:`lcpbench.model.batch_verdict.accepted`).

The start itself is the caller's (:class:`lcpbench.studies.continuation.Solved`, the
compiled predictor :func:`lcpbench.model.predictor_kernel.predict_start`: the same bits
as the scene-by-scene loop's). Its outputs go to a row of the
flat-wall line kernel's arrays (:func:`lcpbench.model.batch_kernel.solve_line`), read
by the same code (:mod:`lcpbench.studies.batch_result`). Where the profile kernel stops
(a bail code) the caller solves the line scene by scene.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .batch_kernel import (
    ARC,
    CONTACT,
    CONVERGED,
    FREE,
    SETTLED,
    STATS,
    STOPPED_FREE,
    store_solve,
    store_verdict,
)
from .compiled_kernel import solve_profile_chain
from .judge_kernel import judge_walls
from .wall_kernel import split_by_wall

__all__ = ["ARC", "CONTACT", "CONVERGED", "FREE", "SETTLED", "STATS", "STOPPED_FREE",
           "profile_attempt"]


@njit(cache=True)
def profile_attempt(row, start, net, u0, ra, a, jl, jr, k, rest, link_load, nodal_load, fs,
                    lo, hi, L, F, ku, cu_, kl, cl_, wall, tol, max_outer, max_iter, request,
                    o_code, o_kind, o_alpha, o_R, o_rup, o_rlo, o_u, o_sig, o_res, o_off,
                    o_count, j_code, j_stats, j_fu, j_fl, j_tres, conv, recs, used):
    """One solve of a scene into ``row`` of the outputs (``start``: α to start from,
    empty: cold; ``net``, ``u0``: the net reactions and node heights of the answer whose
    last step warm-starts it), its step records appended to ``recs``: (done, recs,
    used); not done: the profile kernel stopped, ``o_code[row]`` its bail code. The
    scene's arrays as the profile kernel takes them (the solve kernel's first nine, the
    wall's rows, ℓ, EI/ℓ², the walls' tables), ``wall`` its wall height (the judge's,
    :func:`lcpbench.model.judge.chain_args`); the outputs: a row per attempt, as
    :func:`lcpbench.model.batch_kernel.solve_line`'s."""
    n = lo.size
    mu_up, mu_lo = np.zeros(n), np.zeros(n)
    if start.size and net.size == n and np.all(np.isfinite(net)):
        split_by_wall(net, u0, hi, lo, False, mu_up, mu_lo)
    no_springs = np.zeros(0)
    got = solve_profile_chain(ra, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                              ku, cu_, kl, cl_, False, tol, max_outer, start, mu_up, mu_lo,
                              max_iter, request)
    code = got[0]
    if code >= 10:
        o_code[row] = code  # the bail code (kernel_call.BAIL_REASONS)
        return False, recs, used
    o_off[row] = used
    alpha, R, count, recs, used = store_solve(row, got, code, recs, used, o_rup, o_rlo, o_u,
                                              o_sig, o_res)
    o_code[row], o_kind[row], o_count[row] = code, CONTACT, count
    o_alpha[row] = alpha
    o_R[row] = R
    ok = False
    if code == CONVERGED:  # the judge, on the answer and the exact walls (one wall: R)
        judged = judge_walls(
            alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F, no_springs,
            no_springs, wall, False, ku, cu_, kl, cl_, R.copy(), np.zeros(n), tol,
            recs[2, used - count:used].copy())
        ok = store_verdict(row, judged, tol, j_code, j_stats, j_fu, j_fl, j_tres)
    conv[row] = ok
    return True, recs, used
