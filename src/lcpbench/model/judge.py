"""The result judge: when lcpbench calls a contact result converged.

:mod:`lcpbench.solvers.judge` decides whether one contact step is SOLVED. This
module decides whether a whole answer — the final link angles α and the wall
reactions R (eq. 30) — is the equilibrium of the scene to the accuracy asked
for. Every back-end's answer goes through the same checks, computed by
lcpbench from the primal unknowns; a back-end's own word (its status, its
multipliers) is never enough.

The accuracy asked for is the report's success rule (docs/bench.md): a
relative error of the total reaction F = ΣR of at most

    τ = force_tol(tol) = min(1e-3, 100 · tol),

measured in the force unit F₀ = max(|F|, EI/ℓ²), so that a scene without
contact (F = 0) is judged too. Lengths are measured in the section length ℓ.

``converged`` requires all of the following; an answer that misses one is
``converged=False`` with a reason naming the check. Nothing is relabelled.

1. **driver**: the outer iteration stopped by its criterion max|Δα| < tol.
2. **last step**: the contact step whose reactions are reported was SOLVED by
   lcpbench's residuals (not INACCURATE). Earlier steps may be inexact: they
   only move the iterate, which the line search and the checks below judge;
   their count is kept in the judgement (``inexact_steps``).
3. **sign**: min R ≥ −ε_R, no wall pulls (ε_R = NODE_SHARE · τ · F₀, or the
   round-off of R = K g + z, 256 ε S with S the size of its terms, if larger).
4. **complementarity**: at every node, min(R_i/F₀, g_i/ℓ) ≤ NODE_SHARE · τ:
   a node that carries a reaction touches its wall.
5. **penetration**: min g ≥ −min(1e-6, NODE_SHARE · τ) · ℓ on the exact
   geometry; at an elastic wall also the indentation that the reactions'
   tolerance ε_R leaves open, ε_R/k (a soft wall's compliant gap g + R/k is
   a difference of two large lengths, known only as well as R).

At an elastic wall (:mod:`lcpbench.model.elastic`) g is the compliant gap
g + R/k in checks 4 and 5 (a node indents the wall by exactly R/k), and the
judge step holds a node in contact by the wall's spring instead of on it.
6. **closure, torque**: the exact-geometry certificate
   (:func:`lcpbench.model.result.certify`): the right pin on y = 0 to 1e-6 ℓ,
   the joint torques in balance to max(10 tol, 1e-6) of the spring torques.
7. **force error bound**: lcpbench takes one more contact step itself at the
   final α (the *judge step*), solved exactly by block principal pivoting
   from the answer's contact set, independent of every back-end. If the
   answer's forces are F_k and the judge step's F_{k+1}, and the outer
   iteration contracts by ρ per step, F_k − F* ≈ (F_k − F_{k+1}) / (1 − ρ).
   With ρ estimated from the last two step sizes (at least ½, at most 0.99),

       force_error_bound = |F_k − F_{k+1}| / ((1 − ρ) F₀) + round-off,

   and the same per node (max_i |R_i − R'_i|), which must be at most τ for
   the total and, per node, the largest of NODE_FACTOR·τ, NODE_GROSS (5 % of
   F₀: node forces converge more slowly than their sum) and NODE_FACTOR times
   the round-off of a reaction, 256 ε S. This
   is an a-posteriori estimate under linear contraction, not a proof: it is
   what turns "α stopped moving" into "F is within τ".

8. **stability**: the equilibrium is a local minimum of the exact energy on its
   contact set: the Hessian of the Lagrangian has no negative curvature on the
   tangent space of the nodes held by a wall (reaction above ε_R; the others are
   left free, which can only refuse more) and of the right pin's closure
   (:mod:`lcpbench.model.stability_kernel`, an O(N) inertia count). A saddle,
   which passes every first-order check above, is refused here.

With a wall profile y = h(x) (:mod:`lcpbench.model.profile`) the checks are
those of the exact profile problem: gaps h(x_k) − y_k at the nodes' x,
torques with the normal reactions μ (h', −1) (their horizontal parts taken
by the fixed left pin), and a judge step with the answer's reactions as its
lagged multipliers.

The contact set reported with a result counts nodes whose reaction exceeds
ε_R (so no 5e-10 N "contacts"). Every threshold is in :data:`THRESHOLDS` and
docs/solvers.md.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.linalg import LinAlgError  # scipy.linalg's LinAlgError is this class

from ..linalg import banded_matvec, solveh_banded, sub_bands
from ..problems.scenes import Chain
from ..thresholds import (  # the rule's numbers, read by the judge kernel too
    EPS,
    FLOOR_ULPS,
    FORCE_TOL_CAP,
    FORCE_TOL_PER_RAD,
    GEOMETRY_TOL,
    NODE_FACTOR,
    NODE_GROSS,
    NODE_SHARE,
    PIVOT_ROUNDS,
    RHO_MAX,
    RHO_MIN,
    ROUNDOFF_ULPS,
    STALL,
    STEP_NOISE,
)
from . import large_n
from .chain import heights
from .elastic import compliances
from .judge_large import primal_step
from .profile import has_profile, node_x, profile_step, slope_load, walls_at
from .step import ContactStep, assemble_step

#: in increments (large N) the single pivots are capped at 2 × this many, not 2 per node:
#: each round is an O(N) face solve, and a judge that cannot settle says so
LARGE_ROUNDS = 100
#: friction (issue 39): a node slides when its slip |s| > max(SLIP_FACTOR · tol · a,
#: SLIP_FLOOR · ℓ) (a = ℓ/N; the floor: ten times Lemke's accepted residual on the
#: dimensionless step, what a SOLVED step leaves on a slip)
SLIP_FACTOR, SLIP_FLOOR = 10.0, 1e-7

THRESHOLDS = {
    "force_tol": "min(1e-3, 100·tol), relative to F₀ = max(|F|, EI/ℓ²)",
    "last step": "SOLVED by lcpbench's residuals",
    "sign": "min R >= -max(NODE_SHARE·τ·F₀, FLOOR_ULPS·ε·S)",
    "complementarity": "max_i min(R_i/F₀, g_i/ℓ) <= NODE_SHARE·τ",
    "penetration": "min g >= -min(GEOMETRY_TOL, NODE_SHARE·τ)·ℓ",
    "closure": "|y_right| <= GEOMETRY_TOL·ℓ",
    "torque": "relative torque residual <= max(10·tol, 1e-6)",
    "force_error_bound": "<= τ for F; per node <= max(NODE_FACTOR·τ, NODE_GROSS, "
                         "NODE_FACTOR·FLOOR_ULPS·ε·S/F₀)",
    "contact": "R_i > NODE_SHARE·τ·F₀",
    "stability": "no negative curvature of the energy on the contact set (R_i > ε_R held)",
    "cone": "friction: |T_i| <= μ N_i + NODE_SHARE·τ·F₀ (F₀ also >= |pull|)",
    "slip": "friction: |s_i| > ε_s = max(SLIP_FACTOR·tol·a, SLIP_FLOOR·ℓ): μ N_i − |T_i| "
            "and T_i·sign(s_i) <= NODE_SHARE·τ·F₀; inside the cone by more: |s_i| <= ε_s",
    "x balance": "friction, no end holding x: |ΣT + pull| <= NODE_SHARE·τ·F₀",
}


def force_tol(tol: float) -> float:
    """τ: the relative force error a result at driver tolerance ``tol`` (rad) may have,
    min(1e-3, 100·tol). 1e-3 is the paper's agreement criterion (Fig. 26); 100·tol
    is what an exact step solver reaches at driver tolerance tol."""
    return min(FORCE_TOL_CAP, FORCE_TOL_PER_RAD * float(tol))


@dataclass
class JudgeStep:
    """The judge's own contact step at the final α, solved exactly.

    ``forces_upper``/``forces_lower``: its reactions R' (N); ``rounds``: block
    principal pivoting rounds; ``dalpha``: max|α̂' − α| it would move the chain.
    """

    forces_upper: np.ndarray
    forces_lower: np.ndarray
    rounds: int
    dalpha: float
    roundoff: np.ndarray  # per node on a wall, the round-off of its reaction R' (N)
    worst_roundoff: float  # the largest over every node (N)
    noise: np.ndarray  # per node, the round-off of an answer's R = K g + z (N)
    term_size: float  # S = max_i (|H| |u| + |c|)_i (N): the terms of R = K g + z


@dataclass
class Judgement:
    """The verdict on one answer, with the numbers behind it.

    ``force_error_bound`` is relative to ``force_unit`` F₀ (NaN when the judge
    did not get that far); ``failed`` names the checks that failed.
    """

    converged: bool
    reason: str
    force_tol: float
    force_unit: float
    force_error_bound: float = float("nan")
    node_error_bound: float = float("nan")
    contraction: float = float("nan")
    contact_threshold: float = 0.0
    judge_total_force: float = float("nan")
    judge_rounds: int = 0
    inexact_steps: int = 0
    #: negative-curvature directions of the energy on the contact set (the second-order
    #: check, :mod:`lcpbench.model.stability_kernel`): 0 a stable equilibrium; None
    #: not checked (a joint layout the check does not take)
    unstable_directions: int | None = None
    failed: list[str] = field(default_factory=list)
    # the answer's reactions with round-off set to zero (None: not judged that far)
    forces_upper: np.ndarray | None = field(default=None, repr=False)
    forces_lower: np.ndarray | None = field(default=None, repr=False)
    certificate: Any = field(default=None, repr=False)  # the Certificate it judged

    def to_dict(self) -> dict:
        d = asdict(self)
        for key in ("forces_upper", "forces_lower", "certificate"):
            d.pop(key)
        return d


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
    largest round-off of any node, S = max_i (|H||u| + |c|)_i)`` or None if it
    did not settle.
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
                    float(np.max(size, initial=0.0)))
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
            float(np.max(size, initial=0.0)))


def _wall_size(step: ContactStep) -> np.ndarray:
    """|wall height| per node (0 where there is none): what a node's height rounds at."""
    lo, hi = step.lower + step.origin, step.upper + step.origin
    return np.maximum(np.where(np.isfinite(hi), np.abs(hi), 0.0),
                      np.where(np.isfinite(lo), np.abs(lo), 0.0))


def judge_step(chain: Chain, alpha: np.ndarray, *, pull: float = 0.0,
               forces: tuple[np.ndarray, np.ndarray] | None = None) -> JudgeStep | None:
    """One more contact step at ``alpha``, solved by the judge (None if it cannot).

    It starts from the answer's contact set: the nodes whose gap costs less
    than ``pull`` of force to close. With a wall profile the step is the
    profile step (:func:`lcpbench.model.profile.profile_step`) with the
    answer's reactions ``forces`` (upper, lower) as its lagged multipliers.
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
    if has_profile(chain) and forces is not None:
        # the answer sits on the walls at the x of its last step, h'·Δx from the exact
        # wall: its nodes that carry force start on the wall too (else dozens of rounds)
        up |= (forces[0] > pull) & np.isfinite(step.upper)
        lo |= (forces[1] > pull) & np.isfinite(step.lower)
    up &= ~lo | (step.upper - step.origin <= step.origin - step.lower)  # the nearer wall
    lo &= ~up
    found = _pivot_step(step, up, lo, pull)
    if found is None:
        return None
    u, net, rounds, roundoff, worst, term_size = found
    upper, lower = split_reactions(chain, net, u - step.origin + absolute)
    dalpha = float(np.max(np.abs(step.predict_alpha(u) - alpha), initial=0.0))
    return JudgeStep(upper, lower, rounds, dalpha, roundoff, worst, noise, term_size)


def contraction_estimate(step_sizes: list[float], judge_dalpha: float) -> float:
    """ρ from the last step sizes: the larger of the last two ratios, in [½, 0.99].

    Step sizes at the round-off of an angle (below STEP_NOISE rad) are left out:
    the ratio of two rounding errors says nothing about the contraction.
    """
    sizes = [s for s in [*step_sizes, judge_dalpha] if np.isfinite(s) and s > STEP_NOISE]
    ratios = [b / a for a, b in zip(sizes[:-1], sizes[1:]) if a > 0][-2:]
    rho = max(ratios, default=RHO_MIN)
    return float(min(max(rho, RHO_MIN), RHO_MAX))


def judge(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
          forces_lower: np.ndarray, *, tol: float, driver_converged: bool,
          driver_reason: str, step_statuses: list[str], step_sizes: list[float],
          certificate) -> Judgement:
    """Judge an answer: link angles ``alpha`` and reactions R (N) on the free nodes.

    ``step_statuses`` are lcpbench's verdicts of the contact steps taken,
    ``step_sizes`` their max|Δα|; ``certificate`` the exact-geometry
    :class:`~lcpbench.model.result.Certificate` of the answer, or a callable
    ``(upper, lower) -> Certificate`` that the judge calls on the reactions it
    reports (round-off set to zero); the one it used is ``judgement.certificate``.
    """
    tau = force_tol(tol)
    F_up, F_lo = float(np.sum(forces_upper)), float(np.sum(forces_lower))
    F0 = max(abs(F_up), abs(F_lo), chain.force_scale)
    eps_R = NODE_SHARE * tau * F0
    verdict = Judgement(False, driver_reason, tau, F0, contact_threshold=eps_R)
    if not driver_converged:
        verdict.failed.append("driver")
        verdict.certificate = (certificate(forces_upper, forces_lower) if callable(certificate)
                               else certificate)
        return verdict
    L = chain.length
    chain = walls_at(chain, alpha)  # a wall profile: its rows at the nodes' x (exact gaps)
    js = judge_step(chain, alpha, pull=eps_R, forces=(forces_upper, forces_lower))
    if js is not None:  # values within round-off are zero, not reactions
        forces_upper = np.where(np.abs(forces_upper) <= js.noise, 0.0, forces_upper)
        forces_lower = np.where(np.abs(forces_lower) <= js.noise, 0.0, forces_lower)
        verdict.forces_upper, verdict.forces_lower = forces_upper, forces_lower
    if callable(certificate):
        certificate = certificate(forces_upper, forces_lower)
    verdict.certificate = certificate
    verdict.inexact_steps = sum(s != "solved" for s in step_statuses)
    u = heights(chain, alpha)
    c_up, c_lo = compliances(chain)  # elastic walls: the compliant gap g + R/k
    g_up = chain.upper - u + c_up * np.maximum(forces_upper, 0.0)
    g_lo = u - chain.lower + c_lo * np.maximum(forces_lower, 0.0)
    with np.errstate(invalid="ignore"):
        comp = max(float(np.max(np.minimum(forces_upper / F0, g_up / L), initial=0.0)),
                   float(np.max(np.minimum(forces_lower / F0, g_lo / L), initial=0.0)))
    comp_allowed = max(NODE_SHARE * tau, FLOOR_ULPS * EPS * js.term_size / F0
                       if js is not None else 0.0)
    floor_R = FLOOR_ULPS * EPS * js.term_size if js is not None else 0.0
    R_min = float(min(np.min(forces_upper, initial=0.0), np.min(forces_lower, initial=0.0)))
    bound = None
    if js is not None:
        rho = contraction_estimate(step_sizes, js.dalpha)
        kappa = 1.0 / (1.0 - rho)
        # the judge's own round-off: its wall reactions', and the residual left on the
        # free nodes, which the chain carries to the walls
        floor = (float(np.sum(js.roundoff)) + js.worst_roundoff) / F0
        d_up = forces_upper - js.forces_upper
        d_lo = forces_lower - js.forces_lower
        total = kappa * max(abs(float(np.sum(d_up))), abs(float(np.sum(d_lo)))) / F0 + floor
        node = kappa * float(np.max(np.abs(np.concatenate([d_up, d_lo])), initial=0.0)) / F0
        # per node, certified down to the round-off of R = K g + z only
        node_allowed = max(NODE_FACTOR * tau, NODE_GROSS, NODE_FACTOR * floor_R / F0)
        verdict.force_error_bound, verdict.node_error_bound = total, node
        verdict.contraction = rho
        verdict.judge_total_force = float(np.sum(js.forces_upper))
        verdict.judge_rounds = js.rounds
        bound = (total, node, node_allowed)
    verdict.unstable_directions = unstable_directions(chain, alpha, forces_upper,
                                                      forces_lower, eps_R)
    fails = failed_checks(certificate, step_statuses, tol=tol, tau=tau, comp=comp,
                          comp_allowed=comp_allowed,
                          pen=penetration_allowed(tau, L, eps_R, c_up, c_lo),
                          closure_allowed=GEOMETRY_TOL * L, R_min=R_min,
                          allowed_R=max(eps_R, floor_R), bound=bound,
                          judge_total_force=verdict.judge_total_force,
                          unstable=verdict.unstable_directions or 0)
    return settle_verdict(verdict, fails, driver_reason)


def unstable_directions(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
                        forces_lower: np.ndarray, threshold: float) -> int | None:
    """The second-order check of an answer (:mod:`lcpbench.model.stability_kernel`):
    how many directions lower the energy on its contact set (0: stable), None where
    it does not apply (joints that are not neighbours)."""
    kern, args = stability_args(chain, alpha, forces_upper, forces_lower)
    code, unstable, _ = kern.unstable_directions(*args, float(threshold),
                                                 bool(chain.free_nodes[-1] < chain.links))
    return int(unstable) if code == kern.CHECKED else None


def stability_args(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
                   forces_lower: np.ndarray) -> tuple:
    """The stability kernel's module and the arguments of its ``unstable_directions``
    up to the threshold: the chain's arrays, the reactions, the walls' springs (inf:
    rigid) and their slopes and curvatures at the nodes' x (0: flat)."""
    from ..numba_cache import kernel_module  # numba at the first numpy judgement

    kern = kernel_module("lcpbench.model.stability_kernel", "unstable_directions")
    n = len(forces_upper)
    rigid, flat = np.full(n, np.inf), np.zeros(n)
    walls = []
    for stiffness, profile in ((chain.upper_stiffness, chain.upper_profile),
                               (chain.lower_stiffness, chain.lower_profile)):
        x = node_x(chain, alpha) if profile is not None else None
        walls.append((rigid if stiffness is None else np.asarray(stiffness, float),
                      flat if x is None else np.asarray(profile.slope(x), float),
                      flat if x is None else np.asarray(profile.curvature(x), float)))
    (ku, su, cu), (kl, sl, cl) = walls
    f64 = np.ascontiguousarray
    return kern, (f64(alpha, dtype=float), float(chain.link_length),
                  f64(chain.joint_links[:, 0]), f64(chain.joint_links[:, 1]),
                  f64(chain.joint_stiffness, dtype=float), f64(chain.rest_joint, dtype=float),
                  f64(chain.link_load, dtype=float), int(chain.free_nodes[0]),
                  f64(forces_upper, dtype=float), f64(forces_lower, dtype=float), f64(ku),
                  f64(kl), f64(su), f64(sl), f64(cu), f64(cl))


def penetration_allowed(tau: float, L: float, eps_R: float, c_up: np.ndarray,
                        c_lo: np.ndarray) -> float:
    """Check 5's allowance (mm): min(GEOMETRY_TOL, NODE_SHARE τ) ℓ, plus ε_R times the
    largest compliance 1/k of an elastic wall (0 for rigid walls)."""
    c = max(float(np.max(c_up, initial=0.0)), float(np.max(c_lo, initial=0.0)))
    return min(GEOMETRY_TOL, NODE_SHARE * tau) * L + eps_R * c


def failed_checks(cert, step_statuses: list[str], *, tol: float, tau: float, comp: float,
                  comp_allowed: float, pen: float, closure_allowed: float, R_min: float,
                  allowed_R: float, bound: tuple[float, float, float] | None,
                  judge_total_force: float, unstable: float = 0) -> list[str]:
    """The checks of :func:`judge` that fail, each as "check: why", in one order.

    Shared by the numpy judge and the compiled one (:mod:`lcpbench.model.judge_compiled`),
    which compute the same numbers: ``bound`` is (total, per-node, per-node allowed) of
    the force error bound, None when the judge step did not settle.
    """
    fails: list[str] = []
    if step_statuses and step_statuses[-1] != "solved":
        fails.append(f"last step: the contact step whose reactions are reported was "
                     f"{step_statuses[-1]} by lcpbench's residuals")
    if comp > comp_allowed:
        fails.append(f"complementarity: a node carries a reaction {comp:.1e} F₀ while "
                     f"{comp:.1e} ℓ from its wall (allowed {comp_allowed:.1e})")
    if cert.min_gap < -pen:
        fails.append(f"penetration: {-cert.min_gap:.1e} mm through a wall "
                     f"(allowed {pen:.1e} mm)")
    if cert.closure > closure_allowed:
        fails.append(f"closure: the right pin is {cert.closure:.1e} mm off y = 0")
    if cert.relative_torque_residual > max(10 * tol, 1e-6):
        fails.append(f"torque: relative torque residual {cert.relative_torque_residual:.1e}")
    if R_min < -allowed_R:
        fails.append(f"sign: a wall pulls with {R_min:.2e} N (allowed down to "
                     f"{-allowed_R:.1e} N)")
    if not unstable <= 0:  # (a NaN fails, as in batch_verdict.accepted)
        many = not unstable <= 1
        fails.append(f"stability: the answer is an unstable equilibrium (a saddle): "
                     f"{unstable:g} direction{'s' if many else ''} on its contact set "
                     f"lower{'' if many else 's'} the energy")
    if bound is None:
        fails.append("force error bound: the judge step did not settle")
    elif not bound[0] <= tau:
        fails.append(f"force error bound: the total force may be {bound[0]:.1e} F₀ off "
                     f"(allowed {tau:.1e}; one more exact step moves it to "
                     f"{judge_total_force:.6g} N)")
    elif not bound[1] <= bound[2]:
        fails.append(f"force error bound: a node's force may be {bound[1]:.1e} F₀ off "
                     f"(allowed {bound[2]:.1e})")
    return fails


def settle_verdict(verdict: Judgement, fails: list[str], driver_reason: str) -> Judgement:
    """The verdict with its failed checks: converged only if none failed."""
    verdict.failed = [f.split(":")[0] for f in fails]
    if fails:
        verdict.reason = "not accepted by lcpbench's judge: " + "; ".join(fails)
        return verdict
    verdict.converged = True
    verdict.reason = driver_reason
    return verdict
