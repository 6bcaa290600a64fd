"""The wall-free tests, compiled once: is a scene's answer the unconstrained arc, the
equilibrium without walls, or a contact solve?

:func:`arc_kind` is what :func:`lcpbench.model.wall_free.solve_without_contact`
decides before its search, and what each scene of the batch kernel's lines decides
(:mod:`.batch_kernel`); both call it. Its one open case, :data:`FIRST_STEP`, is
settled by the chain's first step without walls (:func:`first_step_kind`, which both
call too).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..solvers.dual_kernel import BAIL_NOT_PD  # the free step has no minimiser
from ..thresholds import SAG_BOUND  # the arc will not sag off a wall it crosses by more
from .compiled_kernel import contact_step

#: what the tests say a scene is: a contact solve, the equilibrium without walls (its
#: search), the unconstrained arc itself; FIRST_STEP: the first step without walls
#: decides between FREE (it clears every wall) and CONTACT; FAR: a contact solve, found
#: from the middle node alone (:func:`arc_far_past_wall`)
CONTACT, FREE, ARC, FIRST_STEP, FAR = 0, 1, 2, 3, 4
#: what :func:`first_step_kind` says where the solve kernel's step stopped (a bail other
#: than "no minimiser"): the caller's path decides
STOPPED = -1


@njit(cache=True)
def wall_overlap(u, lo, hi):
    """How far free-node heights ``u`` cross the walls ``hi`` (upper) and ``lo``
    (lower): max(max(u − hi), max(lo − u)), mm; < 0: strictly between them; NaN where u
    has a NaN."""
    up, dn = -np.inf, -np.inf
    for i in range(u.size):
        if np.isnan(u[i]):
            return np.nan
        up = max(up, u[i] - hi[i])
        dn = max(dn, lo[i] - u[i])
    return max(up, dn)


@njit(cache=True)
def beam_sag(link_load, L, F):
    """5 w ℓ⁴ / (384 EI) for the chain's total load Σ|μ_i| (EI = F ℓ², ``F`` the force
    scale EI/ℓ², ``L`` = ℓ the chain's length), mm."""
    total = 0.0
    for i in range(link_load.size):
        total += abs(link_load[i])
    return 5.0 / 384.0 * total * L / F


@njit(cache=True)
def arc_far_past_wall(alpha, a, nodes, hi, sag, L):
    """A cheap sufficient test that the wall-free search finds nothing: the arc α's
    middle free node (``nodes``: the free nodes' indices) alone crosses its upper wall
    ``hi`` by more than the bound of the search (SAG_BOUND · ``sag``; ``sag`` 0 with no
    load), with a margin far above round-off. False says nothing."""
    if nodes.size == 0:
        return False
    mid = nodes.size // 2
    wall = hi[mid]
    if not np.isfinite(wall):
        return False
    y = 0.0
    for i in range(nodes[mid]):
        y += np.sin(alpha[i])
    y *= a
    return y - wall > SAG_BOUND * sag + 1e-9 * (L + abs(wall))


@njit(cache=True)
def arc_kind(alpha, a, nodes, link_load, lo, hi, L, F):
    """What the scene of the arc α (link length ``a``, free ``nodes``, loads
    ``link_load``, walls ``lo``, ``hi`` at the free nodes, length ``L``, force scale
    ``F``) is before any step: FAR where :func:`arc_far_past_wall` says so; CONTACT
    where the arc touches or crosses a wall and no load could sag it off (none, or it
    crosses by more than SAG_BOUND times :func:`beam_sag`); ARC where it clears every
    wall with no load; FREE where it clears them with a load (the search without
    walls); FIRST_STEP where it touches or crosses a wall by less than the sag bound (a
    heavy chain can sag off a wall its arc crosses)."""
    sag = beam_sag(link_load, L, F)
    loaded = False  # a link carries a load (whatever its sag: it may underflow)
    for i in range(link_load.size):
        loaded = loaded or link_load[i] != 0.0
    if arc_far_past_wall(alpha, a, nodes, hi, sag, L):
        return FAR  # a contact solve, as the test below finds, from one node
    y = np.empty(alpha.size + 1)  # the heights, running sums (model.chain.heights)
    y[0] = 0.0
    for i in range(alpha.size):
        y[i + 1] = y[i] + a * np.sin(alpha[i])
    u = np.empty(nodes.size)
    for j in range(nodes.size):
        u[j] = y[nodes[j]]
    over = wall_overlap(u, lo, hi)
    if over >= 0:
        if not loaded or over > SAG_BOUND * sag:
            return CONTACT
        return FIRST_STEP
    return FREE if loaded else ARC


@njit(cache=True)
def first_step_kind(ra, a, jl, jr, k, rest, fs, nodal_load, lo, hi, L, F, max_iter, request):
    """What :func:`arc_kind`'s FIRST_STEP is: FREE where the chain's first step without
    walls at its arc ``ra`` (the solve kernel's contact step with no bounds: the banded
    solve of K u = −z, refined) clears the walls ``lo``, ``hi``; CONTACT where it does
    not, or has no minimiser (K not positive definite); STOPPED where the step stopped
    otherwise. The arguments are the solve kernel's (:func:`.compiled_kernel.contact_step`;
    ``max_iter`` face solves, the step residuals' ``request``)."""
    n = lo.size
    z = np.zeros(n)
    b = np.zeros(n, np.bool_)
    got = contact_step(ra, a, jl, jr, k, rest, fs, n, nodal_load, np.full(n, -np.inf),
                       np.full(n, np.inf), L, F, z[:0], z[:0], z, b, b, 0, max_iter, request)
    if got[0] == BAIL_NOT_PD:
        return CONTACT
    if got[0] != 0:
        return STOPPED
    return FREE if wall_overlap(got[1], lo, hi) < 0 else CONTACT
