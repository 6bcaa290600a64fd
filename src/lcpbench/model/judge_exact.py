"""The result judge's exact contact step in increments (check 7 of
:mod:`lcpbench.model.judge`, from ``LARGE_N`` links or on a chain marked ``increments``).

The judge kernel (:mod:`lcpbench.model.judge_kernel`) takes its exact steps in node
heights, on the Cholesky of H, whose round-off grows as N⁴. Where the solve is in
increments on the tridiagonal factor (:mod:`lcpbench.model.large_n`), so is the
judge's step, here: :func:`judge_step` takes one contact step at given link angles α,
solved exactly from a contact set (the answer's, or the previous judge step's),
independent of every back-end: with rigid walls by the primal active set
(:func:`primal_step`), with elastic walls by block principal pivoting, their springs
in the twisted factor's face solves. The judge takes it twice: at the answer's α,
then at α₁, where the first step moves the chain (the force error bound,
:mod:`lcpbench.model.judge_bound`).

The primal active set (Nocedal & Wright, Alg. 16.3) is used with rigid walls
because block principal pivoting does not settle there: the answer's contacts are
pairs of neighbouring nodes, and at the final α a pair has moved by one node.
Releasing the outer node of a pair frees the chain's slope there, the span between
the contacts passes through the wall (3,640 nodes at N = 10⁵) and the exchanges that
follow cycle until the round cap. One change at a time from the answer's contact set,
every iterate is feasible, a wall that pulls by more than the slack releases its node
(the most negative, scaled by its slack), and a move towards the face minimiser stops
at the first wall it meets, which joins the set. It is the judge's own code,
independent of the solver's dual walk (:mod:`lcpbench.solvers.banded`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.linalg import LinAlgError  # scipy.linalg's LinAlgError is this class

from ..linalg import banded_matvec
from ..problems.scenes import Chain
from ..thresholds import EPS, PIVOT_ROUNDS, ROUNDOFF_ULPS, STALL
from . import large_n
from .elastic import wall_springs
from .profile import slope_load, split_reactions, walls_at

#: the single pivots are capped at 2 × this many, not 2 per node: each round is an O(N)
#: face solve, and a judge that cannot settle says so
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


def _sizes(step, u):
    """Per node, the round-off of R' (the factored gradient's) and S_i, the size of
    the terms of R = K g + z (in increments, at least the gradient's)."""
    scale = step.gradient_scale(u)
    size = np.maximum(banded_matvec(np.abs(step.bands), np.abs(u)) + np.abs(step.linear),
                      scale)
    return ROUNDOFF_ULPS * EPS * scale, size


def _pivot_step(step, up: np.ndarray, lo: np.ndarray, pull: float):
    """The step's exact solution from contact sets up/lo.

    Returns ``(u, net reaction, rounds, round-off of each wall reaction, the
    largest round-off of any node, S = max_i (|H||u| + |c|)_i, (up, lo) the settled
    contact set)`` or None if it did not settle.
    Nodes in ``up`` sit on the upper wall, in ``lo`` on the lower; the others
    are solved for (a face solve, refined once in factored form). A wall
    that pulls by more than ``pull`` (N) releases its node; a node more than
    pull / H_ii (mm) through a wall (the height error that costs ``pull`` of force)
    joins its set (on an elastic wall the node is not held on the wall but by its
    spring, and released when the spring pulls), or more than the round-off of its
    height where that is larger, so that rounding cannot make it cycle (a height error
    δ costs ~16 EI δ / a³ of force: 1e-13 mm is 2 N at N = 1e5). Rigid walls: the
    primal active set (:func:`primal_step`), one change at a time; elastic walls:
    block principal pivoting (Júdice–Pires, then Murty's least index). The step's
    Hessian is positive definite, so the LCP has one solution; the round cap only
    guards against cycling.
    """
    up, lo = up.copy(), lo.copy()
    height_size = _wall_size(step)  # the round-off of a height: of its wall distance

    def slack_of(u):
        roundoff, size = _sizes(step, u)
        return np.maximum(np.maximum(roundoff, pull), ROUNDOFF_ULPS * EPS * size)

    def reach_of(u):
        return np.maximum(ROUNDOFF_ULPS * EPS * (np.abs(u) + height_size), pull / step.bands[0])

    cap = PIVOT_ROUNDS + 2 * LARGE_ROUNDS
    if not step.elastic:  # rigid walls: one change at a time
        found = primal_step(step, up, lo, slack_of=slack_of, reach_of=reach_of, cap=cap)
        if found is None:
            return None
        u, up, lo, rounds = found
        roundoff, size = _sizes(step, u)
        return (u, -step.gradient(u), rounds, np.where(up | lo, roundoff, 0.0),
                float(np.max(roundoff)), float(np.max(size, initial=0.0)), (up, lo))
    best, stall = step.size + 1, 0
    k_up, k_lo = wall_springs(step)
    for rounds in range(1, cap + 1):
        # a node on a rigid wall is held on it; on an elastic wall it stays free, held
        # by the wall's spring k (u − h) (model.elastic), as rows of the twisted factor
        # (nothing grows with k)
        soft_up, soft_lo = up & (k_up > 0), lo & (k_lo > 0)
        spring = np.where(soft_up, k_up, 0.0) + np.where(soft_lo, k_lo, 0.0)
        rest = np.where(soft_up, step.upper, np.where(soft_lo, step.lower, 0.0))
        u = step.origin.copy()
        hard_up, hard_lo = up & ~soft_up, lo & ~soft_lo
        u[hard_up] = step.upper[hard_up]
        u[hard_lo] = step.lower[hard_lo]
        fixed = hard_up | hard_lo
        free = np.flatnonzero(~fixed)
        if free.size:
            try:
                for _ in range(2):  # solve, then refine with the factored gradient
                    if np.any(spring[free] > 0):
                        grad = step.gradient(u) + spring * (u - rest)
                        grad[fixed] = 0.0
                        u -= step.factor.face_solve(fixed, grad, spring)
                    else:
                        u[free] -= step.solve_on(free, step.gradient(u)[free])
            except (LinAlgError, ValueError):
                return None
        net = -step.gradient(u)
        # R' is the factored gradient (round-off ~ ε × its terms), not K g + z; but the
        # free heights carry the solve's error, which K turns into force (a few ulps
        # of S_i): a sign within that is undecided, not a reason to pivot
        roundoff, size = _sizes(step, u)
        slack = np.maximum(np.maximum(roundoff, pull), ROUNDOFF_ULPS * EPS * size)
        reach = reach_of(u)
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


def primal_step(step, up: np.ndarray, lo: np.ndarray, *, slack_of, reach_of, cap: int):
    """``(u, up, lo, rounds)`` at the settled face, or None within ``cap`` face solves.

    ``slack_of(u)``: per node, the pull that releases a wall; ``reach_of(u)``: per
    node, the depth through a wall that joins it (both as the block pivoting uses).
    Rigid walls only (elastic walls take the block pivoting of :func:`_pivot_step`,
    their springs in the twisted factor).
    """
    up, lo = up.copy(), lo.copy()
    hi_w, lo_w = step.upper, step.lower
    u = _face_minimiser(step, up, lo)
    if u is None:
        return None
    # a feasible start: nodes through a wall join it (then the face's minimiser again)
    for _ in range(cap):
        reach = reach_of(u)
        join_up = ~up & ~lo & (u > hi_w + reach)
        join_lo = ~up & ~lo & (u < lo_w - reach)
        if not (join_up.any() or join_lo.any()):
            break
        up |= join_up
        lo |= join_lo
        u = _face_minimiser(step, up, lo)
        if u is None:
            return None
    else:
        return None
    at_minimiser = True
    for rounds in range(1, cap + 1):
        if at_minimiser:
            net = -step.gradient(u)
            slack = slack_of(u)
            # net = −gradient: the upper wall's reaction (it pushes down), minus the lower's
            pull_up = np.where(up, net / slack, np.inf)  # < −1: it pulls
            pull_lo = np.where(lo, -net / slack, np.inf)
            i_up, i_lo = int(np.argmin(pull_up)), int(np.argmin(pull_lo))
            if min(pull_up[i_up], pull_lo[i_lo]) >= -1.0:
                return u, up, lo, rounds
            if pull_up[i_up] <= pull_lo[i_lo]:
                up[i_up] = False
            else:
                lo[i_lo] = False
        v = _face_minimiser(step, up, lo)
        if v is None:
            return None
        d = v - u
        free = ~(up | lo)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_up = np.where(free & (d > 0) & np.isfinite(hi_w), (hi_w - u) / d, np.inf)
            t_lo = np.where(free & (d < 0) & np.isfinite(lo_w), (lo_w - u) / d, np.inf)
        j_up, j_lo = int(np.argmin(t_up)), int(np.argmin(t_lo))
        t = min(t_up[j_up], t_lo[j_lo])
        if t < 1.0:
            u = u + max(t, 0.0) * d
            if t_up[j_up] <= t_lo[j_lo]:
                up[j_up] = True
                u[j_up] = hi_w[j_up]
            else:
                lo[j_lo] = True
                u[j_lo] = lo_w[j_lo]
            at_minimiser = False
        else:
            u = v
            at_minimiser = True
    return None


def _face_minimiser(step, up, lo):
    """The step's minimiser with ``up`` / ``lo`` on their walls: a face solve, refined once
    with the factored gradient (as the block pivoting does)."""
    u = step.origin.copy()
    u[up] = step.upper[up]
    u[lo] = step.lower[lo]
    free = np.flatnonzero(~(up | lo))
    if free.size:
        try:
            for _ in range(2):
                u[free] -= step.solve_on(free, step.gradient(u)[free])
        except (np.linalg.LinAlgError, ValueError):
            return None
    return u


def _wall_size(step) -> np.ndarray:
    """|wall height| per node (0 where there is none): what a node's height rounds at."""
    lo, hi = step.lower + step.origin, step.upper + step.origin
    return np.maximum(np.where(np.isfinite(hi), np.abs(hi), 0.0),
                      np.where(np.isfinite(lo), np.abs(lo), 0.0))


def judge_step(chain: Chain, alpha: np.ndarray, *, pull: float = 0.0,
               forces: tuple[np.ndarray, np.ndarray] | None = None,
               contacts: tuple[np.ndarray, np.ndarray] | None = None) -> JudgeStep | None:
    """One more contact step at ``alpha`` in increments, solved by the judge (None if
    it cannot; the chain must be one :func:`lcpbench.model.large_n.takes`).

    It starts from the answer's contact set: the nodes whose gap costs less
    than ``pull`` of force to close. With a wall profile the step is the
    profile step in increments, with the answer's reactions ``forces`` (upper,
    lower), clipped at 0, as its lagged multipliers (their slope load).
    ``contacts`` (upper, lower): the contact set to start from instead (the judge's
    second step starts from its first's).
    """
    if chain.profiled_walls:
        n = chain.free_nodes.size
        up_lo = forces if forces is not None else (np.zeros(n), np.zeros(n))
        at = walls_at(chain, alpha)
        s = slope_load(chain, alpha, *(np.maximum(f, 0.0) for f in up_lo))
        step = large_n.increments_at(chain, alpha, walls=(at.lower, at.upper),
                                     load=chain.nodal_load + s)
        chain = at
    else:  # on the tridiagonal factor
        step = large_n.increments_at(chain, alpha)
    absolute = step.heights  # node heights at α
    floor = ROUNDOFF_ULPS * EPS * (np.abs(absolute) + _wall_size(step))
    touch = np.maximum(pull / step.bands[0], floor)
    on_upper, on_lower = step.upper - step.origin <= touch, step.origin - step.lower <= touch
    # R = K g + z of an answer is exact to a few ulps of the gradient's terms
    noise = ROUNDOFF_ULPS * EPS * step.gradient_scale(step.origin)
    up, lo = on_upper.copy(), on_lower.copy()  # a reaction off the wall is not contact
    if contacts is not None:
        up, lo = (np.asarray(c, bool) & np.isfinite(w) for c, w in zip(contacts,
                                                                        (step.upper, step.lower)))
    elif chain.profiled_walls and forces is not None:
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
