"""The rule of the result judge's exact steps, compiled: block principal pivoting's test and
exchange (Júdice–Pires, then Murty's least index) and the term sizes its round-off is
measured against. The judge's steps in node heights (:func:`lcpbench.model.judge_kernel._pivot`)
and in increments (:mod:`lcpbench.model.judge_exact_kernel`) both take them from here.

A node's state is FREE, UP or LO (:mod:`lcpbench.model.judge_checks`). Every function is
``@njit(cache=True)``; ``NUMBA_DISABLE_JIT=1`` runs them as plain Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..thresholds import EPS, ROUNDOFF_ULPS, STALL
from .judge_checks import FREE, LO, UP


@njit(cache=True)
def term_sizes(bands, linear, x, n, out):
    """(|H| |x| + |c|)_i on the bands into ``out``: the size of the terms of each R_i
    (for round-off bounds)."""
    for i in range(n):
        s = abs(bands[0, i]) * abs(x[i])
        if i - 1 >= 0:
            s += abs(bands[1, i - 1]) * abs(x[i - 1])
        if i + 1 < n:
            s += abs(bands[1, i]) * abs(x[i + 1])
        if i - 2 >= 0:
            s += abs(bands[2, i - 2]) * abs(x[i - 2])
        if i + 2 < n:
            s += abs(bands[2, i]) * abs(x[i + 2])
        out[i] = s + abs(linear[i])


#: no per-node height sizes: every height rounds at the chain's length L (in heights)
NO_SIZES = np.empty(0)


@njit(cache=True)
def pivot_slack(roundoff, pull, size):
    """The pull (N) by which a wall must pull on its node before the judge releases it:
    its reaction's round-off, ``pull``, or a few ulps of the term size S_i of R = K g + z,
    whichever is largest (a sign within it is undecided, not a reason to pivot)."""
    return max(max(roundoff, pull), ROUNDOFF_ULPS * EPS * size)


@njit(cache=True)
def pivot_test(state, change, u, net, scale, sizes, hi, lo, diag, L, height_size, pull,
               roundoff):
    """One round's test of the judge's block principal pivoting, in heights or in
    increments (:mod:`lcpbench.model.judge_exact_kernel`), over the nodes of ``hi``.

    ``net``: the gradient on entry, the net reaction R' = −gradient on return; per node
    ``roundoff`` = the round-off of R' (a few ulps of its terms, ``scale``). A wall that
    pulls by more than the slack max(round-off, ``pull``, a few ulps of the term size
    S_i, ``sizes``) releases its node (``change`` 1: the upper wall, 2: the lower); a
    free node more than its reach through a wall joins it (3: the upper, 4: the lower),
    the reach max(a few ulps of |u| + the size its height rounds at, ``pull`` / H_ii
    (``diag``)): the size is ``height_size`` per node, or (empty) the length ``L``.
    Returns (how many change, the first that does, the largest round-off, max S_i)."""
    count, first = 0, -1
    worst, S = 0.0, 0.0
    per_node = height_size.size > 0
    for i in range(hi.size):
        net[i] = -net[i]
        roundoff[i] = ROUNDOFF_ULPS * EPS * scale[i]
        size = sizes[i]
        worst = max(worst, roundoff[i])
        S = max(S, size)
        slack = pivot_slack(roundoff[i], pull, size)
        rounds_at = height_size[i] if per_node else L
        reach = max(ROUNDOFF_ULPS * EPS * (abs(u[i]) + rounds_at), pull / diag[i])
        c = 0
        if state[i] == UP:
            if net[i] < -slack:
                c = 1
        elif state[i] == LO:
            if net[i] > slack:
                c = 2
        elif u[i] > hi[i] + reach:
            c = 3
        elif u[i] < lo[i] - reach:
            c = 4
        change[i] = c
        if c:
            count += 1
            if first < 0:
                first = i
    return count, first, worst, S


@njit(cache=True)
def pivot_exchange(state, change, n, count, first, best, stall):
    """Júdice–Pires: every node :func:`pivot_test` names changes sides while their
    number falls; after STALL rounds without progress only the first (Murty's least
    index, finite for the P-matrix of a positive definite step). Returns (best, stall)."""
    if count < best:
        best, stall = count, 0
    else:
        stall += 1
    for i in range(n):
        if change[i] == 0 or (stall >= STALL and i != first):
            continue
        state[i] = FREE if change[i] <= 2 else (UP if change[i] == 3 else LO)
    return best, stall


@njit(cache=True)
def pivot_settled(state, roundoff, rounds, worst, S):
    """A settled judge step's (rounds, largest round-off, max S_i), its reactions'
    round-off kept on the wall nodes only (0 on the free ones)."""
    for i in range(state.size):
        if state[i] == FREE:
            roundoff[i] = 0.0
    return rounds, worst, S
