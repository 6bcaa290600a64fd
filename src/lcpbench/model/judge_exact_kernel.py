"""The result judge's exact contact step in increments, compiled (check 7 of
:mod:`lcpbench.model.judge`): :func:`increments_step`, which the one judge kernel
(its entry :func:`lcpbench.model.judge_kernel.judge_in_increments`) takes in place of its
step in node heights from ``LARGE_N`` links or on a chain marked ``increments``.

One contact step in increments d = u − u₀ (:class:`lcpbench.model.large_n.IncrementStep`,
assembled by :func:`lcpbench.model.large_kernel.assemble_into`), solved exactly from a
contact set, independent of every back-end:

- rigid walls: the primal active set (Nocedal & Wright, Alg. 16.3; :func:`primal_step`);
- elastic walls: block principal pivoting (the judge kernel's rule,
  :func:`~.judge_pivot.pivot_test` and :func:`~.judge_pivot.pivot_exchange`), the
  springs k (u − h) of the nodes on a yielding wall rotated into the factor as rows
  √k eᵢ (nothing grows with k).

Every face solve is on one twisted factor of the step's rows
(:func:`lcpbench.linalg.twisted_kernel.face_solve`), refactored between the first and
the last node that changed since the last face (:func:`face_solve`, the restart of
:class:`lcpbench.linalg.twisted.TwistedFactor`): a pivot costs the rows it changes.

Why the primal active set with rigid walls: block principal pivoting does not settle
there. The answer's contacts are pairs of neighbouring nodes, and at the final α a pair
has moved by one node. Releasing the outer node of a pair frees the chain's slope there,
the span between the contacts passes through the wall (3,640 nodes at N = 10⁵) and the
exchanges that follow cycle until the round cap. One change at a time from the answer's
contact set, every iterate is feasible, a wall that pulls by more than the slack
releases its node (the most negative, scaled by its slack), and a move towards the face
minimiser stops at the first wall it meets, which joins the set.

A node's state is FREE, UP or LO (:mod:`lcpbench.model.judge_checks`). Every function
is ``@njit(cache=True)``; ``NUMBA_DISABLE_JIT=1`` runs them as plain Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.face_kernel import face_solve as top_face_solve
from ..linalg.twisted_kernel import face_solve as twisted_face_solve
from ..linalg.twisted_kernel import twist
from ..thresholds import EPS, LARGE_ROUNDS, PIVOT_ROUNDS, ROUNDOFF_ULPS
from .chain_kernel import predict_alpha  # eq. (21), the kinematics' (not the step's)
from .judge_checks import FREE, LO, UP
from .judge_pivot import (
    pivot_exchange,
    pivot_settled,
    pivot_slack,
    pivot_test,
    term_sizes,
)
from .large_kernel import assemble_into, descend, gradient, gradient_scale


@njit(cache=True)
def _sizes(step, u, grad, scale, sizes):
    """``grad`` = the step's gradient at u, ``scale`` = the size of its terms, and per
    node S_i = max((|H| |u| + |c|)_i, its gradient's terms): the terms of R = K g + z."""
    coef, k, phi_origin, rest, load, origin, rows, rrows, bands, linear, m = step
    gradient(coef, k, phi_origin, rest, load, origin, u, grad, m)
    gradient_scale(coef, k, phi_origin, rest, load, origin, u, scale, m)
    term_sizes(bands, linear, u, u.size, sizes)
    for i in range(u.size):
        sizes[i] = max(sizes[i], scale[i])


@njit(cache=True)
def new_face(n):
    """A twisted factor's state for :func:`face_solve`: its arrays, the last face (its
    fixed nodes and springs' √k) and ``ctl`` = (the last twist, whether there is one)."""
    factor = (np.empty((3, n)), np.empty(n, np.bool_), np.empty((n, 4)), np.empty((3, n)),
              np.empty(n, np.bool_), np.empty((n, 4)), np.zeros(3), np.empty(n), np.empty(n))
    return factor, np.zeros(n, np.bool_), np.zeros(n), np.zeros(2, np.int64)


@njit(cache=True)
def face_solve(rows, rrows, face, fixed, root, rhs, x):
    """x with (H + diag(root²))_face x = rhs, the ``fixed`` nodes held (identity rows),
    ``root`` the springs' √k per node (0: none), on the twisted factor ``face``
    (:func:`new_face`) refactored from the face of its last call between the first and
    the last node that changed (:meth:`lcpbench.linalg.twisted.TwistedFactor._twist`).
    Below five nodes, no twist: the QR from the top, without springs. False on a zero
    pivot."""
    factor, last_fixed, last_root, ctl = face
    R, filled, snap, B, bfilled, bsnap, tri, inv_r, inv_b = factor
    n = rhs.size
    if n < 5:
        for i in range(n):
            if root[i] > 0.0:
                return False
        return top_face_solve(rows, fixed, R, filled, snap, inv_r, 0, rhs, x)
    j0, k0, m = 0, 0, n // 2
    if ctl[1]:
        first, last = n, -1
        for i in range(n):
            if fixed[i] != last_fixed[i] or root[i] != last_root[i]:
                first, last = min(first, i), i
        j0, k0, m = twist(first, last, ctl[0], n)
    ctl[1] = 0  # invalid until the factorisation succeeds
    if not twisted_face_solve(rows, rrows, fixed, fixed[::-1].copy(), root, root[::-1].copy(),
                              R, filled, snap, B, bfilled, bsnap, tri, inv_r, inv_b, j0, k0,
                              m, rhs, x):
        return False
    last_fixed[:] = fixed
    last_root[:] = root
    ctl[0], ctl[1] = m, 1
    return True


@njit(cache=True)
def free_count(fixed):
    """How many nodes are not ``fixed`` (a loop: numba's array reductions would load
    numba.np.arraymath, and with it scipy.linalg, at the judge kernel's first call)."""
    count = 0
    for i in range(fixed.size):
        if not fixed[i]:
            count += 1
    return count


@njit(cache=True)
def _free_nodes(fixed):
    """The indices of the nodes not ``fixed``, ascending."""
    free = np.empty(free_count(fixed), np.int64)
    p = 0
    for i in range(fixed.size):
        if not fixed[i]:
            free[p] = i
            p += 1
    return free


@njit(cache=True)
def _descend(step, face, fixed, grad, u, x, no_springs):
    """u[free] −= H[free, free]⁻¹ grad[free] (``grad`` is overwritten): where at most half
    the nodes are free, by their independent blocks
    (:func:`~lcpbench.model.large_kernel.descend`), else on the whole restarted factor
    (:meth:`lcpbench.model.large_n.IncrementStep.solve_on`'s choice). False on a zero
    pivot."""
    n = u.size
    free = _free_nodes(fixed)
    if 2 * free.size <= n:
        return descend(step[6], free, grad, u)
    for i in range(n):
        if fixed[i]:
            grad[i] = 0.0
    if not face_solve(step[6], step[7], face, fixed, no_springs, grad, x):
        return False
    for i in free:
        u[i] -= x[i]
    return True


@njit(cache=True)
def _face_minimiser(step, face, lo, hi, state, u, grad, x, no_springs):
    """u = the step's minimiser with the nodes of ``state`` UP / LO held on their walls,
    refined once with the factored gradient. False on a zero pivot."""
    coef, k, phi_origin, rest, load, origin, rows, rrows, bands, linear, m = step
    n = u.size
    fixed = state != FREE
    for i in range(n):
        u[i] = hi[i] if state[i] == UP else (lo[i] if state[i] == LO else origin[i])
    if free_count(fixed):
        for _ in range(2):
            gradient(coef, k, phi_origin, rest, load, origin, u, grad, m)
            if not _descend(step, face, fixed, grad, u, x, no_springs):
                return False
    return True


@njit(cache=True)
def primal_step(step, lo, hi, height_size, pull, state, cap, u, net, roundoff, sizes):
    """The rigid walls' step by the primal active set from the contact set ``state``
    (settled there on return): rounds (0: not settled within ``cap`` face solves), the
    largest round-off, max S_i; u, the net reaction and the round-off per node in
    ``u``, ``net``, ``roundoff``. Slack and reach as :func:`~.judge_pivot.pivot_test`."""
    n = u.size
    grad, scale, v, x = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    change, face, no_springs = np.empty(n, np.int64), new_face(n), np.zeros(n)
    diag = step[8][0]
    if not _face_minimiser(step, face, lo, hi, state, u, grad, x, no_springs):
        return 0, 0.0, 0.0
    for _ in range(cap):  # a feasible start: nodes through a wall join it
        _sizes(step, u, net, scale, sizes)
        pivot_test(state, change, u, net, scale, sizes, hi, lo, diag, 0.0, height_size, pull,
                   roundoff)
        joins = 0
        for i in range(n):
            if change[i] >= 3:
                state[i] = UP if change[i] == 3 else LO
                joins += 1
        if joins == 0:
            break
        if not _face_minimiser(step, face, lo, hi, state, u, grad, x, no_springs):
            return 0, 0.0, 0.0
    else:
        return 0, 0.0, 0.0
    at_minimiser = True
    for rounds in range(1, cap + 1):
        if at_minimiser:  # the wall that pulls most, by its slack, releases its node
            _sizes(step, u, net, scale, sizes)
            worst, S = pivot_test(state, change, u, net, scale, sizes, hi, lo, diag, 0.0,
                                  height_size, pull, roundoff)[2:]
            # net / slack < −1 (upper) or > 1 (lower): it pulls; the first node of the
            # most on each wall, the upper wall's on a tie
            most_up, most_lo, i_up, i_lo = np.inf, np.inf, -1, -1
            for i in range(n):
                if state[i] != FREE:
                    slack = pivot_slack(roundoff[i], pull, sizes[i])
                    if state[i] == UP and net[i] / slack < most_up:
                        most_up, i_up = net[i] / slack, i
                    elif state[i] == LO and -net[i] / slack < most_lo:
                        most_lo, i_lo = -net[i] / slack, i
            if min(most_up, most_lo) >= -1.0:
                return pivot_settled(state, roundoff, rounds, worst, S)
            state[i_up if most_up <= most_lo else i_lo] = FREE
        if not _face_minimiser(step, face, lo, hi, state, v, grad, x, no_springs):
            return 0, 0.0, 0.0
        # the first wall on the way from u to v (the first node of each wall, the upper
        # wall's on a tie)
        t_up, t_lo, j_up, j_lo = np.inf, np.inf, -1, -1
        for i in range(n):
            d = v[i] - u[i]
            if state[i] == FREE and d > 0.0 and np.isfinite(hi[i]) and (hi[i] - u[i]) / d < t_up:
                t_up, j_up = (hi[i] - u[i]) / d, i
            elif state[i] == FREE and d < 0.0 and np.isfinite(lo[i]) and \
                    (lo[i] - u[i]) / d < t_lo:
                t_lo, j_lo = (lo[i] - u[i]) / d, i
        t = min(t_up, t_lo)
        if t < 1.0:  # stop there: its node joins the wall
            for i in range(n):
                u[i] += max(t, 0.0) * (v[i] - u[i])
            j, onto = (j_up, UP) if t_up <= t_lo else (j_lo, LO)
            state[j] = onto
            u[j] = hi[j] if onto == UP else lo[j]
            at_minimiser = False
        else:
            u[:] = v
            at_minimiser = True
    return 0, 0.0, 0.0


@njit(cache=True)
def pivot_step(step, lo, hi, k_up, k_lo, height_size, pull, state, cap, u, net, roundoff,
               sizes):
    """The elastic walls' step by block principal pivoting from the contact set
    ``state`` (settled there on return); returns and fills as :func:`primal_step`. A
    node on a rigid wall is held on it; on an elastic wall it stays free, held by the
    wall's spring k (u − h), as rows √k eᵢ of the twisted factor."""
    coef, k, phi_origin, rest, load, origin, rows, rrows, bands, linear, m = step
    n = u.size
    grad, scale, x = np.empty(n), np.empty(n), np.empty(n)
    change, face = np.empty(n, np.int64), new_face(n)
    spring, root, wall = np.zeros(n), np.zeros(n), np.zeros(n)
    fixed = np.empty(n, np.bool_)
    best, stall = n + 1, 0
    for rounds in range(1, cap + 1):
        springs = False
        for i in range(n):
            kk = k_up[i] if state[i] == UP else (k_lo[i] if state[i] == LO else 0.0)
            spring[i] = kk if kk > 0.0 else 0.0
            root[i] = np.sqrt(spring[i])
            wall[i] = hi[i] if state[i] == UP else (lo[i] if state[i] == LO else 0.0)
            fixed[i] = state[i] != FREE and not kk > 0.0
            u[i] = wall[i] if fixed[i] else origin[i]
            springs = springs or spring[i] > 0.0
        for _ in range(2 if free_count(fixed) else 0):  # solve, then refine (factored gradient)
            gradient(coef, k, phi_origin, rest, load, origin, u, grad, m)
            if not springs:
                if not _descend(step, face, fixed, grad, u, x, root):
                    return 0, 0.0, 0.0
                continue
            for i in range(n):
                grad[i] = 0.0 if fixed[i] else grad[i] + spring[i] * (u[i] - wall[i])
            if not face_solve(rows, rrows, face, fixed, root, grad, x):
                return 0, 0.0, 0.0
            for i in range(n):
                if not fixed[i]:
                    u[i] -= x[i]
        _sizes(step, u, net, scale, sizes)
        count, first, worst, S = pivot_test(state, change, u, net, scale, sizes, hi, lo,
                                            bands[0], 0.0, height_size, pull, roundoff)
        if count == 0:
            return pivot_settled(state, roundoff, rounds, worst, S)
        best, stall = pivot_exchange(state, change, n, count, first, best, stall)
    return 0, 0.0, 0.0


@njit(cache=True)
def increments_step(alpha, a, k, rest, load, lower, upper, cu, cl, fs, pull, forces_upper,
                    forces_lower, from_forces, from_state, state, u, net, roundoff, noise,
                    alpha_next):
    """The judge's exact contact step at α in increments d = u − u₀ (assembled by
    :func:`~lcpbench.model.large_kernel.assemble_into`, the walls ``lower``/``upper`` and the
    nodal ``load`` at α as given: a profile's at the nodes' x, with its slope load), for
    :func:`lcpbench.model.judge_kernel.judge_in_increments`.

    It starts from the nodes whose gap costs less than ``pull`` (N) of force to close (or
    is within the round-off of its height), and, ``from_forces`` (a wall profile: the
    answer sits on the walls at the x of its last step), the nodes whose reaction
    ``forces_upper``/``forces_lower`` exceeds ``pull``; ``from_state``: from the contact
    set in ``state`` instead (the second judge step starts from the first's), nodes on a
    wall of this step only. A node on both walls starts on the nearer. Rigid walls: the
    primal active set (:func:`primal_step`); walls with a compliance 1/k > 0 (``cu``,
    ``cl``; empty: none yields): block principal pivoting (:func:`pivot_step`).

    Returns ``(rounds, largest round-off, S, max|α̂ − α|)``, rounds 0 where it did not
    settle; fills the settled ``state``, the node heights u = u₀ + d, the net reactions,
    their round-off (wall nodes only), the ``noise`` of an answer's R = K g + z per node
    (a few ulps of its gradient's terms at u₀) and α̂ (``alpha_next``, eq. 21)."""
    nl = alpha.size
    n = nl - 1
    inv_a_cos, alpha0, sin_alpha = np.empty(nl), np.empty(nl), np.empty(nl)
    coef, rows, rrows = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
    heights, phi_origin, linear, lo, hi = (np.empty(n), np.empty(n), np.empty(n),
                                           np.empty(n), np.empty(n))
    bands, m, zero, sizes = np.empty((3, n)), np.empty(n), np.zeros(n), np.empty(n)
    assemble_into(alpha, a, k, np.sqrt(k), rest, load, lower, upper, inv_a_cos, coef, heights,
                  alpha0, phi_origin, bands, linear, lo, hi, rows, rrows, sin_alpha, m)
    step = (coef, k, phi_origin, rest, load, zero, rows, rrows, bands, linear, m)
    gradient_scale(coef, k, phi_origin, rest, load, zero, zero, noise, m)
    wall_size = np.empty(n)  # |wall| about u₀: what a node's increment rounds at
    for i in range(n):
        noise[i] = ROUNDOFF_ULPS * EPS * noise[i]
        wall_size[i] = max(abs(hi[i]) if np.isfinite(hi[i]) else 0.0,
                           abs(lo[i]) if np.isfinite(lo[i]) else 0.0)
        touch = max(pull / bands[0, i], ROUNDOFF_ULPS * EPS * (abs(heights[i]) + wall_size[i]))
        if from_state:
            on_up = state[i] == UP and np.isfinite(hi[i])
            on_lo = state[i] == LO and np.isfinite(lo[i])
        else:
            on_up, on_lo = hi[i] <= touch, -lo[i] <= touch
            if from_forces:
                on_up = on_up or (forces_upper[i] > pull and np.isfinite(hi[i]))
                on_lo = on_lo or (forces_lower[i] > pull and np.isfinite(lo[i]))
        up = on_up and (not on_lo or hi[i] <= -lo[i])  # the nearer wall
        state[i] = UP if up else (LO if on_lo else FREE)
    soft = False  # a wall that yields: its springs k = 1/c where it has a node
    k_up, k_lo = np.zeros(n), np.zeros(n)
    for i in range(cu.size):
        soft = soft or cu[i] > 0.0 or cl[i] > 0.0
        k_up[i] = 1.0 / cu[i] if cu[i] > 0.0 and np.isfinite(hi[i]) else 0.0
        k_lo[i] = 1.0 / cl[i] if cl[i] > 0.0 and np.isfinite(lo[i]) else 0.0
    cap = PIVOT_ROUNDS + 2 * LARGE_ROUNDS
    if soft:
        rounds, worst, S = pivot_step(step, lo, hi, k_up, k_lo, wall_size, pull, state, cap,
                                      u, net, roundoff, sizes)
    else:
        rounds, worst, S = primal_step(step, lo, hi, wall_size, pull, state, cap, u, net,
                                       roundoff, sizes)
    if rounds == 0:
        return 0, 0.0, 0.0, 0.0
    dalpha = predict_alpha(u, n, zero, alpha0, inv_a_cos, fs, alpha, alpha_next)
    for i in range(n):
        u[i] += heights[i]
    return rounds, worst, S, dalpha
