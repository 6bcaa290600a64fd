"""The result judge's exact contact step, numpy (the reference; check 7 of
:mod:`lcpbench.model.judge`).

:func:`judge_step` takes one contact step at given link angles α, solved exactly
by block principal pivoting from a contact set (the answer's, or the previous
judge step's), independent of every back-end; at large N in increments on the
tridiagonal factor (rigid walls by the primal active set of
:mod:`lcpbench.model.judge_large`). The judge takes it twice: at the answer's α,
then at α₁, where the first step moves the chain (the force error bound,
:mod:`lcpbench.model.judge_bound`). The judge kernel
(:mod:`lcpbench.model.judge_kernel`) takes the same steps compiled for the
layouts it takes; this module is the path for every other chain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.linalg import LinAlgError  # scipy.linalg's LinAlgError is this class

from ..linalg import banded_matvec, solveh_banded, sub_bands
from ..problems.scenes import Chain
from ..thresholds import EPS, PIVOT_ROUNDS, ROUNDOFF_ULPS, STALL
from . import large_n
from .judge_large import primal_step
from .profile import has_profile, profile_step, slope_load, walls_at
from .step import ContactStep, assemble_step

#: in increments (large N) the single pivots are capped at 2 × this many, not 2 per node:
#: each round is an O(N) face solve, and a judge that cannot settle says so
LARGE_ROUNDS = 100


@dataclass
class JudgeStep:
    """The judge's own contact step at the final α, solved exactly.

    ``forces_upper``/``forces_lower``: its reactions R' (N); ``rounds``: block
    principal pivoting rounds; ``dalpha``: max|α̂' − α| it would move the chain
    (to ``alpha_next``); ``contacts``: its settled contact set.
    """

    forces_upper: np.ndarray
    forces_lower: np.ndarray
    rounds: int
    dalpha: float
    roundoff: np.ndarray  # per node on a wall, the round-off of its reaction R' (N)
    worst_roundoff: float  # the largest over every node (N)
    noise: np.ndarray  # per node, the round-off of an answer's R = K g + z (N)
    term_size: float  # S = max_i (|H| |u| + |c|)_i (N): the terms of R = K g + z
    alpha_next: np.ndarray  # α̂', where the step moves the chain (eq. 21)
    contacts: tuple  # (upper, lower): the nodes it holds on (or by) each wall



def split_reactions(chain: Chain, net: np.ndarray, u: np.ndarray):
    """Upper and lower wall reactions from the net reaction ``net`` (N, + pushes down).

    One wall: all of it is the upper wall's (a negative value is that wall
    pulling). A channel: each node's reaction belongs to the wall it is nearer
    to, with its sign kept, so a pulling wall stays visible.
    """
    net = np.asarray(net, dtype=float)
    if not chain.channel:
        return net.copy(), np.zeros_like(net)
    with np.errstate(invalid="ignore"):  # inf - inf where a node reaches no wall
        mid = 0.5 * (chain.upper + chain.lower)
    near_upper = np.where(np.isfinite(mid), u >= mid, np.isfinite(chain.upper))
    return np.where(near_upper, net, 0.0), np.where(near_upper, 0.0, -net)


def _springs(step: ContactStep) -> tuple[np.ndarray, np.ndarray]:
    """The elastic walls' k_i (N/mm) per free node, 0 where a wall is rigid or absent."""
    out = []
    for k, wall in ((step.upper_stiffness, step.upper), (step.lower_stiffness, step.lower)):
        k = np.full(step.size, np.inf) if k is None else np.asarray(k, float)
        out.append(np.where(np.isfinite(k) & np.isfinite(wall), k, 0.0))
    return out[0], out[1]


def _pivot_step(step: ContactStep, up: np.ndarray, lo: np.ndarray, pull: float):
    """The step's exact solution by block principal pivoting from contact sets up/lo.

    Returns ``(u, net reaction, rounds, round-off of each wall reaction, the
    largest round-off of any node, S = max_i (|H||u| + |c|)_i, (up, lo) the settled
    contact set)`` or None if it did not settle.
    Nodes in ``up`` sit on the upper wall, in ``lo`` on the lower; the others
    are solved for (a banded solve, refined once in factored form). A wall
    that pulls by more than ``pull`` (N) releases its node; a node more than
    pull / H_ii (mm) through a wall joins its set (on an elastic wall the node is
    not held on the wall but by its spring, and released when the spring pulls) (the height error that costs
    ``pull`` of force), or more than the round-off where that is larger, so
    that at large N rounding cannot make it cycle. The step's Hessian is positive definite,
    so the LCP has one solution; the round cap only guards against cycling.
    """
    up, lo = up.copy(), lo.copy()
    best, stall = step.size + 1, 0
    k_up, k_lo = _springs(step)
    # the round-off of a height: of ℓ; in increments (large N), of the node's own wall
    # distance (there a height error δ costs ~16 EI δ / a³ of force: 1e-13 mm is 2 N at
    # N = 1e5)
    height_size = step.length_scale if step.factor is None else _wall_size(step)
    cap = PIVOT_ROUNDS + 2 * (step.size if step.factor is None else LARGE_ROUNDS)
    if step.factor is not None and not step.elastic:  # increments (large N), rigid walls:
        return _large_step(step, up, lo, pull, height_size, cap)  # one change at a time
    for rounds in range(1, cap + 1):
        # a node on a rigid wall is held on it; on an elastic wall it stays free, held
        # by the wall's spring k (u − h) (model.elastic): a banded solve all the same
        soft_up, soft_lo = up & (k_up > 0), lo & (k_lo > 0)
        spring = np.where(soft_up, k_up, 0.0) + np.where(soft_lo, k_lo, 0.0)
        rest = np.where(soft_up, step.upper, np.where(soft_lo, step.lower, 0.0))
        u = step.origin.copy()
        hard_up, hard_lo = up & ~soft_up, lo & ~soft_lo
        u[hard_up] = step.upper[hard_up]
        u[hard_lo] = step.lower[hard_lo]
        free = np.flatnonzero(~(hard_up | hard_lo))
        if free.size:
            try:
                if np.any(spring[free] > 0) and step.factor is not None:  # large N: the
                    # springs as rows of the twisted factor (nothing grows with k)
                    fixed = hard_up | hard_lo
                    for _ in range(2):  # solve, then refine with the factored gradient
                        grad = step.gradient(u) + spring * (u - rest)
                        grad[fixed] = 0.0
                        u -= step.factor.face_solve(fixed, grad, spring)
                elif np.any(spring[free] > 0):  # elastic walls: banded
                    bands = sub_bands(step.bands, free)
                    bands[0] += spring[free]
                    for _ in range(2):  # solve, then refine with the factored gradient
                        grad = step.gradient(u) + spring * (u - rest)
                        u[free] -= solveh_banded(bands, grad[free], lower=True,
                                                 check_finite=False)
                else:  # on H's banded Cholesky, or its tridiagonal factor (large N)
                    for _ in range(2):  # solve, then refine with the factored gradient
                        u[free] -= step.solve_on(free, step.gradient(u)[free])
            except (LinAlgError, ValueError):
                return None
        net = -step.gradient(u)
        # R' is the factored gradient (round-off ~ ε × its terms), not K g + z; but the
        # free heights carry the solve's error, which K turns into force (a few ulps
        # of S_i): a sign within that is undecided, not a reason to pivot
        roundoff = ROUNDOFF_ULPS * EPS * step.gradient_scale(u)
        size = banded_matvec(np.abs(step.bands), np.abs(u)) + np.abs(step.linear)
        if step.factor is not None:  # increments (large N): R's terms are the gradient's
            size = np.maximum(size, step.gradient_scale(u))
        slack = np.maximum(np.maximum(roundoff, pull), ROUNDOFF_ULPS * EPS * size)
        # a height error δ costs H_ii δ of force: ``pull`` in force is pull / H_ii in height
        reach = np.maximum(ROUNDOFF_ULPS * EPS * (np.abs(u) + height_size), pull / step.bands[0])
        release_up = up & (net < -slack)
        release_lo = lo & (net > slack)
        join_up = ~up & ~lo & (u > step.upper + reach)
        join_lo = ~up & ~lo & (u < step.lower - reach)
        change = release_up | release_lo | join_up | join_lo
        count = int(np.count_nonzero(change))
        if count == 0:
            return (u, net, rounds, np.where(up | lo, roundoff, 0.0), float(np.max(roundoff)),
                    float(np.max(size, initial=0.0)), (up, lo))
        # Júdice–Pires: exchange every infeasible node while their number falls; after
        # STALL rounds without progress, only the first one (Murty's least-index rule,
        # finite for the P-matrix of a positive definite step)
        best, stall = (count, 0) if count < best else (best, stall + 1)
        if stall >= STALL:
            first = np.zeros_like(change)
            first[np.argmax(change)] = True
            release_up, release_lo = release_up & first, release_lo & first
            join_up, join_lo = join_up & first, join_lo & first
        up = (up & ~release_up) | join_up
        lo = (lo & ~release_lo) | join_lo
    return None


def _large_step(step: ContactStep, up, lo, pull: float, height_size, cap: int):
    """:func:`_pivot_step` in increments (large N), by the primal active set of
    :mod:`.judge_large`, with the same slack, reach and settle test."""

    def sizes(u):
        roundoff = ROUNDOFF_ULPS * EPS * step.gradient_scale(u)
        size = np.maximum(banded_matvec(np.abs(step.bands), np.abs(u)) + np.abs(step.linear),
                          step.gradient_scale(u))
        return roundoff, size

    def slack_of(u):
        roundoff, size = sizes(u)
        return np.maximum(np.maximum(roundoff, pull), ROUNDOFF_ULPS * EPS * size)

    def reach_of(u):
        return np.maximum(ROUNDOFF_ULPS * EPS * (np.abs(u) + height_size), pull / step.bands[0])

    found = primal_step(step, up, lo, slack_of=slack_of, reach_of=reach_of, cap=cap)
    if found is None:
        return None
    u, up, lo, rounds = found
    net = -step.gradient(u)
    roundoff, size = sizes(u)
    return (u, net, rounds, np.where(up | lo, roundoff, 0.0), float(np.max(roundoff)),
            float(np.max(size, initial=0.0)), (up, lo))


def _wall_size(step: ContactStep) -> np.ndarray:
    """|wall height| per node (0 where there is none): what a node's height rounds at."""
    lo, hi = step.lower + step.origin, step.upper + step.origin
    return np.maximum(np.where(np.isfinite(hi), np.abs(hi), 0.0),
                      np.where(np.isfinite(lo), np.abs(lo), 0.0))


def judge_step(chain: Chain, alpha: np.ndarray, *, pull: float = 0.0,
               forces: tuple[np.ndarray, np.ndarray] | None = None,
               contacts: tuple[np.ndarray, np.ndarray] | None = None) -> JudgeStep | None:
    """One more contact step at ``alpha``, solved by the judge (None if it cannot).

    It starts from the answer's contact set: the nodes whose gap costs less
    than ``pull`` of force to close. With a wall profile the step is the
    profile step (:func:`lcpbench.model.profile.profile_step`) with the
    answer's reactions ``forces`` (upper, lower) as its lagged multipliers.
    ``contacts`` (upper, lower): the contact set to start from instead (the judge's
    second step starts from its first's).
    """
    if has_profile(chain):
        n = chain.free_nodes.size
        up_lo = forces if forces is not None else (np.zeros(n), np.zeros(n))
        if large_n.applies(chain):  # the profile step in increments; its slope load from
            # the reactions clipped at 0, as profile.profile_step's (the driver's are not)
            at = walls_at(chain, alpha)
            s = slope_load(chain, alpha, *(np.maximum(f, 0.0) for f in up_lo))
            step = large_n.increments_at(chain, alpha, walls=(at.lower, at.upper),
                                         load=chain.nodal_load + s)
            chain = at
        else:
            step, chain = profile_step(chain, alpha, *up_lo)
    elif large_n.applies(chain):  # in increments, on the tridiagonal factor
        step = large_n.increments_at(chain, alpha)
    else:
        step = assemble_step(chain, alpha)
    absolute = step.origin if step.factor is None else step.heights  # node heights at α
    floor = 1e3 * EPS * chain.length
    if step.factor is not None:  # increments (large N)
        floor = ROUNDOFF_ULPS * EPS * (np.abs(absolute) + _wall_size(step))
    touch = np.maximum(pull / step.bands[0], floor)
    on_upper, on_lower = step.upper - step.origin <= touch, step.origin - step.lower <= touch
    # R = K g + z of an answer is exact to the factored gradient's round-off on a wall
    # (g = 0), to that of rounded heights, a few ulps of S_i = (|K||g| + |z|)_i, off it
    size = np.where(on_upper | on_lower | (step.factor is not None),
                    step.gradient_scale(step.origin),
                    banded_matvec(np.abs(step.bands), np.abs(step.origin))
                    + np.abs(step.linear))
    noise = ROUNDOFF_ULPS * EPS * size
    up, lo = on_upper.copy(), on_lower.copy()  # a reaction off the wall is not contact
    if contacts is not None:
        up, lo = (np.asarray(c, bool) & np.isfinite(w) for c, w in zip(contacts,
                                                                        (step.upper, step.lower)))
    elif has_profile(chain) and forces is not None:
        # the answer sits on the walls at the x of its last step, h'·Δx from the exact
        # wall: its nodes that carry force start on the wall too (else dozens of rounds)
        up |= (forces[0] > pull) & np.isfinite(step.upper)
        lo |= (forces[1] > pull) & np.isfinite(step.lower)
    up &= ~lo | (step.upper - step.origin <= step.origin - step.lower)  # the nearer wall
    lo &= ~up
    found = _pivot_step(step, up, lo, pull)
    if found is None:
        return None
    u, net, rounds, roundoff, worst, term_size, settled = found
    upper, lower = split_reactions(chain, net, u - step.origin + absolute)
    alpha_next = step.predict_alpha(u)
    dalpha = float(np.max(np.abs(alpha_next - alpha), initial=0.0))
    return JudgeStep(upper, lower, rounds, dalpha, roundoff, worst, noise, term_size,
                     alpha_next, settled)
