"""One kernel call per continuation line: predict, solve and judge every scene of it.

:func:`solve_line` is :func:`lcpbench.studies.batch_compiled.solve_line` in one
compiled call, for a line of actuator scenes of one plane (the same chain but for θ
and h; flat walls, rigid or elastic, one wall or a channel, no heavy load), or of several
planes that
share the chain's layout (each scene predicted from its own plane, and where its plane
has no answer to predict it from, from the nearest answer of its kin). For each scene,
in order:

1. the start, as :class:`lcpbench.studies.continuation.Solved` chooses it (its
   rules 1-4 and the ``adaptive`` choice of degree: the same compiled
   :func:`~lcpbench.model.predictor_kernel.predict_start`);
   where those rules find no answer (none of its plane on its line in θ or at its
   θ), rule 5: the nearest accepted answer of its kin (``kin``, ``where``: the
   scenes the same but for θ, h and the walls' stiffness, with their coordinates;
   :func:`lcpbench.studies.batch._kin`), as it is, its last step's contact set the
   warm set; each scene is solved on its own walls (its own row of ``cu``, ``cl``):
   only the start is shared;
2. the wall-free search of :func:`lcpbench.model.wall_free.solve_without_contact`
   (its tests, :func:`~lcpbench.model.wall_free_kernel.arc_kind`, which it calls too;
   the first free step is the compiled step with no walls,
   :func:`~lcpbench.model.compiled_kernel.contact_step`);
3. the solve kernel's entry :func:`~lcpbench.model.compiled_kernel.solve_chain`;
4. the judge kernel's entry :func:`~lcpbench.model.judge_kernel.judge_answer` on the
   answer, and its verdict from the judge's numbers alone
   (:func:`lcpbench.model.batch_verdict.accepted`, the checks of
   :func:`lcpbench.model.judge.failed_checks`);
5. a warm start the judge does not accept is solved again cold (in a spare row), as
   :func:`~lcpbench.studies.continuation.warm_or_cold` does.

Nothing is decided here that the single solve decides differently: where the
solve kernel stops (a bail code) the call returns that scene's index and the caller
solves the whole line by the per-scene path. The outputs are written into arrays the
caller allocates, a row per attempt; the step records go to one buffer for the line.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .batch_verdict import accepted
from .chain_kernel import free_heights
from .compiled_kernel import CONVERGED, LINE_SEARCH, MAX_OUTER, NO_FIT, solve_chain
from .judge_kernel import SETTLED, STATS, judge_answer
from .predictor_kernel import predict_start
from .wall_free_kernel import (
    ARC,
    CONTACT,
    FAR,
    FIRST_STEP,
    FREE,
    STOPPED,
    arc_kind,
    first_step_kind,
    wall_overlap,
)
from .wall_kernel import split_by_wall

__all__ = ["ARC", "CONTACT", "CONVERGED", "FREE", "LINE_SEARCH", "MAX_OUTER", "NO_FIT", "SETTLED",
           "STATS", "STOPPED_FREE", "append_records", "solve_line", "store_solve",
           "store_verdict"]
#: o_code of an attempt the wall-free search stopped on (its first step without walls,
#: or the search's solve kernel): no bail code of a contact solve
STOPPED_FREE = STOPPED


@njit(cache=True)
def _wall_free_kind(ra, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                    max_iter, request):
    """What an attempt is: ARC (the arc is the answer), FREE (the search without walls)
    or CONTACT (the contact solve), as :func:`~.wall_free_kernel.arc_kind` says and,
    where it leaves it to the first step without walls,
    :func:`~.wall_free_kernel.first_step_kind`; STOPPED_FREE where that step stopped
    (the caller's path)."""
    kind = arc_kind(ra, a, np.arange(fs - 1, fs - 1 + lo.size), link_load, lo, hi, L, F)
    if kind == FAR:
        return CONTACT
    if kind == FIRST_STEP:
        return first_step_kind(ra, a, jl, jr, k, rest, fs, nodal_load, lo, hi, L, F,
                               max_iter, request)
    return kind


@njit(cache=True)
def append_records(recs, used, rec, count):
    """Append the ``count`` step records ``rec`` to the flat buffer ``recs`` (grown by
    doubling): (buffer, its new length)."""
    if used + count > recs.shape[1]:
        bigger = np.empty((4, 2 * (used + count)))
        bigger[:, :used] = recs[:, :used]
        recs = bigger
    recs[:, used:used + count] = rec[:, :count]
    return recs, used + count


@njit(cache=True)
def store_solve(row, got, code, recs, used, o_rup, o_rlo, o_u, o_sig, o_res):
    """A solve kernel's output ``got`` (:func:`~.compiled_kernel.solve_chain`'s or the
    profile kernel's: the same layout) into ``row`` of the outputs, its step records
    appended to ``recs``, its residuals kept where ``code`` says it converged: (α, R,
    the step count, recs, used)."""
    alpha, R, count = got[1], got[9], got[7]
    o_rup[row], o_rlo[row], o_u[row], o_sig[row] = got[2], got[3], got[4], got[5]
    recs, used = append_records(recs, used, got[6], count)
    if code == CONVERGED:
        o_res[row] = got[8]
    return alpha, R, count, recs, used


@njit(cache=True)
def store_verdict(row, judged, tol, j_code, j_stats, j_fu, j_fl, j_tres):
    """The judge kernel's output ``judged`` (code, stats, R⁺, R⁻, torque residuals) into
    ``row``: whether the answer is accepted (:func:`~.batch_verdict.accepted`)."""
    jc, st, fu, fl, tres = judged
    j_code[row] = jc
    j_stats[row] = st
    j_fu[row], j_fl[row], j_tres[row] = fu, fl, tres
    return accepted(jc == SETTLED, st, tol)


@njit(cache=True)
def _attempt(row, start, w_u, w_up, w_lo, flags, ra, a, jl, jr, k, rest, link_load,
             nodal_load, fs, lo, hi, L, F, cu, cl, wall, channel, tol, max_outer, max_iter,
             request, free_lo, free_hi, o_code, o_kind, o_alpha, o_R, o_rup, o_rlo, o_u, o_sig, o_res,
             o_off, o_count, j_code, j_stats, j_fu, j_fl, j_tres, conv, recs, used):
    """One solve of a scene into ``row`` of the outputs, its step records appended to
    ``recs``: (done, recs, used); not done: the solve kernel stopped, ``o_code[row]`` its
    bail code on the contact solve, or STOPPED_FREE on the wall-free search. ``cu``, ``cl``:
    the walls' compliances (empty: rigid walls); ``channel``: a lower wall too, each
    node's net reaction the nearer wall's (as the single solve's driver output splits it,
    :func:`lcpbench.model.profile.split_reactions`)."""
    n = lo.size
    kind = _wall_free_kind(ra, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                           max_iter, request)
    if kind < 0:
        o_code[row] = STOPPED_FREE
        return False, recs, used
    o_off[row] = used
    if kind == ARC:
        code, alpha, count = CONVERGED, ra.copy(), 0
        R = np.zeros(n)
    else:
        code = -1
        if kind == FREE:  # the equilibrium without walls (its start's shape, no warm set)
            zb = np.zeros(n, np.bool_)
            got = solve_chain(ra, a, jl, jr, k, rest, link_load, nodal_load, fs, free_lo,
                              free_hi, L, F, cu[:0], cl[:0], tol, max_outer, start,
                              np.zeros(n), zb, zb, 0, max_iter, request, False)
            if got[0] >= 10:
                o_code[row] = STOPPED_FREE
                return False, recs, used
            u = np.empty(n)
            free_heights(u, got[1], a, fs)
            if got[0] == CONVERGED and wall_overlap(u, lo, hi) < 0:
                code = CONVERGED
            else:
                kind = CONTACT
        if kind == CONTACT:
            got = solve_chain(ra, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F,
                              cu, cl, tol, max_outer, start, w_u, w_up, w_lo, flags, max_iter,
                              request, False)
            if got[0] >= 10:
                o_code[row] = got[0]  # the bail code (kernel_call.BAIL_REASONS)
                return False, recs, used
            code = got[0]
        alpha, R, count, recs, used = store_solve(row, got, code, recs, used, o_rup, o_rlo,
                                                  o_u, o_sig, o_res)
    o_code[row], o_kind[row], o_count[row] = code, kind, count
    o_alpha[row] = alpha
    o_R[row] = R
    ok = False
    if code == CONVERGED:  # the judge, on the answer and the real walls
        up, down = R.copy(), np.zeros(n)
        if channel and kind != ARC:
            split_by_wall(R, o_u[row], hi, lo, True, up, down)
        judged = judge_answer(
            alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, L, F, cu, cl, wall,
            channel, up, down, tol, recs[2, used - count:used].copy())
        ok = store_verdict(row, judged, tol, j_code, j_stats, j_fu, j_fl, j_tres)
    conv[row] = ok
    return True, recs, used


@njit(cache=True)
def solve_line(rest_alpha, a, jl, jr, k, rest, link_load, nodal_load, fs, lo, hi, cu, cl, L, F,
               wall, channel,
               theta, height, plane, kin, where, tol, max_outer, max_iter, request, most, adaptive,
               o_code, o_kind, o_alpha, o_R, o_rup, o_rlo, o_u, o_sig, o_res, o_off, o_count,
               j_code, j_stats, j_fu, j_fl, j_tres, conv, kept, failed, base):
    """Every scene of the line in order; returns ``(code, records)``: code −1 all done,
    s >= 0 the solve kernel stopped on scene s, −2 more warm starts failed than the
    outputs have rows for. The outputs have a row per attempt: row s the first
    attempt of scene s, rows from m on the cold retries of failed warm starts.
    ``kept[s]``: the row of the answer kept; ``failed[s]``: the row of a failed warm
    start (−1: none); ``base[s]``: the answer that started it (−1: cold);
    ``records``: the step records (face solves, step length, max|Δα|, energy) of
    every attempt, from column ``o_off[row]``, ``o_count[row]`` of them. ``cu``, ``cl``:
    each scene's walls' compliances 1/k per free node (0: rigid; no columns where no
    wall yields). ``plane``: each scene's plane (an index, 0 to the number of planes − 1):
    a scene is predicted from the answers of its own plane only, so several planes in
    one call give the answers of a call per plane. ``kin``, ``where``: each scene's kin
    (−1: none) and coordinates, for a scene none of its plane's answers predicts
    (:func:`~.predictor_kernel.predict_start`'s rule 5; ``kin`` all −1: a call per plane's answers). Where the
    solve kernel stops on a scene alone in its plane (no other scene's start depends on it), ``kept[s]`` is −1,
    ``o_code[s]`` says where it stopped (:func:`_attempt`), and the call goes on: the
    caller solves that scene by itself."""
    m, n = lo.shape
    members = np.zeros(np.max(plane) + 1 if m else 0, np.int64)
    for s in range(m):
        members[plane[s]] += 1
    spare = o_code.size
    free_lo, free_hi = np.full(n, -np.inf), np.full(n, np.inf)
    ok = np.zeros(m, np.bool_)  # accepted answers, what Solved.add records
    touch = np.zeros(m, np.bool_)
    alphas = np.empty(rest_alpha.shape)
    zf, zb = np.zeros(n), np.zeros(n, np.bool_)
    recs, used, retry = np.empty((4, 2 * m + 8)), 0, m
    outs = (o_code, o_kind, o_alpha, o_R, o_rup, o_rlo, o_u, o_sig, o_res, o_off, o_count,
            j_code, j_stats, j_fu, j_fl, j_tres, conv)
    for s in range(m):
        start, b = predict_start(s, theta, height, plane, kin, where, ok, touch, alphas, most,
                                 adaptive)
        base[s], failed[s] = b, -1
        w_u, w_up, w_lo, flags = zf, zb, zb, 0
        if b >= 0 and o_kind[kept[b]] != ARC:  # the base's last contact step
            sig = o_sig[kept[b]]
            w_u, w_up, w_lo, flags = o_u[kept[b]], sig > 0, sig < 0, 7
        args = (rest_alpha[s], a, jl, jr, k[s], rest[s], link_load[s], nodal_load, fs, lo[s],
                hi[s], L, F, cu[s], cl[s], wall[s], channel, tol, max_outer, max_iter, request,
                free_lo, free_hi)
        done, recs, used = _attempt(s, start, w_u, w_up, w_lo, flags, *args, *outs, recs,
                                    used)
        if not done:
            if members[plane[s]] > 1:
                return s, recs
            kept[s] = -1  # alone in its plane: solved by the caller (ok[s] stays False)
            continue
        kept[s] = s
        if b >= 0 and not conv[s]:  # the warm start failed: cold, in a spare row
            if retry >= spare:
                return -2, recs
            done, recs, used = _attempt(retry, start[:0], zf, zb, zb, 0, *args, *outs, recs,
                                        used)
            if not done:
                return s, recs
            kept[s], failed[s] = retry, s
            retry += 1
        row = kept[s]
        ok[s] = conv[row]
        alphas[s] = o_alpha[row]
        if ok[s]:
            for i in range(n):
                if j_fu[row, i] > 0 or j_fl[row, i] > 0:  # (continuation.touches)
                    touch[s] = True
                    break
    return -1, recs
