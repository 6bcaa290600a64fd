"""The result judge's exact contact step in increments (check 7 of
:mod:`lcpbench.model.judge`, from ``LARGE_N`` links or on a chain marked ``increments``).

The judge kernel (:mod:`lcpbench.model.judge_kernel`) takes its exact steps in node
heights, on the Cholesky of H, whose round-off grows as N⁴. Where the solve is in
increments on the tridiagonal factor (:mod:`lcpbench.model.large_n`), so is the
judge's step, here: :func:`judge_step` assembles one contact step at given link angles
α and solves it exactly from a contact set (the answer's, or the previous judge
step's), independent of every back-end, in one compiled call
(:mod:`lcpbench.model.judge_exact_kernel`: rigid walls by the primal active set,
elastic walls by the judge kernel's block principal pivoting, their springs in the
twisted factor's face solves). The judge takes it twice: at the answer's α, then at
α₁, where the first step moves the chain (the force error bound,
:mod:`lcpbench.model.judge_bound`). It is the judge's own code, independent of the
solver's dual walk (:mod:`lcpbench.solvers.banded`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..problems.scenes import Chain
from ..thresholds import EPS, PIVOT_ROUNDS, ROUNDOFF_ULPS
from . import large_n
from .elastic import wall_springs
from .profile import slope_load, split_reactions, walls_at

#: the single pivots are capped at PIVOT_ROUNDS + 2 × this many, not 2 per node: each
#: round is an O(N) face solve, and a judge that cannot settle says so
LARGE_ROUNDS = 100


@dataclass
class JudgeStep:
    """The judge's own contact step at the final α, solved exactly.

    ``forces_upper``/``forces_lower``: its reactions R' (N); ``rounds``: its pivoting
    rounds (the primal active set's with rigid walls, block principal pivoting's with
    elastic ones); ``dalpha``: max|α̂' − α| it would move the chain
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


def _kernel():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.model.judge_exact_kernel")


def _pivot_step(step, up: np.ndarray, lo: np.ndarray, pull: float):
    """The step's exact solution from contact sets up/lo (compiled:
    :mod:`lcpbench.model.judge_exact_kernel`).

    Returns ``(u, net reaction, rounds, round-off of each wall reaction, the
    largest round-off of any node, S = max_i (|H||u| + |c|)_i, (up, lo) the settled
    contact set)`` or None if it did not settle.
    Nodes in ``up`` sit on the upper wall, in ``lo`` on the lower; the others
    are solved for. A wall that pulls by more than ``pull`` (N) releases its node; a
    node more than pull / H_ii (mm) through a wall (the height error that costs ``pull``
    of force) joins its set (on an elastic wall the node is not held on the wall but by
    its spring, and released when the spring pulls), or more than the round-off of its
    height where that is larger, so that rounding cannot make it cycle (a height error
    δ costs ~16 EI δ / a³ of force: 1e-13 mm is 2 N at N = 1e5). Rigid walls: the
    primal active set, one change at a time; elastic walls: block principal pivoting
    (Júdice–Pires, then Murty's least index). The step's Hessian is positive definite,
    so the LCP has one solution; the round cap only guards against cycling.
    """
    n = step.size
    kern = _kernel()  # (its node states: judge_checks', loaded with it, not at import)
    state = np.where(up, kern.UP, np.where(lo, kern.LO, kern.FREE)).astype(np.int64)
    u, net, roundoff, sizes = (np.empty(n) for _ in range(4))
    cap = PIVOT_ROUNDS + 2 * LARGE_ROUNDS
    if step.elastic:
        k_up, k_lo = (np.ascontiguousarray(k, dtype=float) for k in wall_springs(step))
        rounds, worst, S = kern.pivot_step(*kernel_step(step), k_up, k_lo, _wall_size(step),
                                           float(pull), state, cap, u, net, roundoff, sizes)
    else:
        rounds, worst, S = kern.primal_step(*kernel_step(step), _wall_size(step), float(pull),
                                            state, cap, u, net, roundoff, sizes)
    if rounds == 0:
        return None
    return (u, net, int(rounds), roundoff, float(worst), float(S),
            (state == kern.UP, state == kern.LO))


def kernel_step(step) -> tuple:
    """``(arrays, lower, upper)``: a step in increments as the judge's kernel takes it
    (:mod:`lcpbench.model.judge_exact_kernel`; ``arrays`` the factored gradient's
    arguments, the rows of A and their mirror, the bands, the linear term and a work
    row; the walls about u₀)."""
    f64 = np.ascontiguousarray
    arrays = tuple(f64(x, dtype=float) for x in (
        step.coef, step.stiffness, step.phi_origin, step.rest_joint, step.nodal_load,
        step.origin, step.factor.rows, step.factor.rrows, step.bands, step.linear))
    return arrays + (np.empty(step.size),), f64(step.lower, dtype=float), f64(step.upper,
                                                                             dtype=float)


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
