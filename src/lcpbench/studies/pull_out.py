"""Pull-out: the largest axial pull an actuator holds by wall friction (issue 39, item 5).

A chain that no end holds along x (``left_end="slider"``, the pull on the right slider)
holds a pull P while friction can balance it: Σ T + P = 0 with |T_i| <= μ_i N_i. The
capacity C(P) = Σ μ_i N_i(P) falls as the pull straightens the chain, and the pull-out
force P* is the root of g(P) = C(P) − P: at P* every contact node slides (gross slip).

:func:`pull_out` follows the pull as a loading path (each state solved from the last,
:mod:`lcpbench.model.friction_path`), stepping towards P* by the secant of g through the
states held so far, from below, each state's outer loop started on the line through
the last two held states (:func:`predicted`): a step past P* (gross slip: no
equilibrium) is not kept, and the next one goes at most half way to it (with the start
held only, the pull 0.999 of the way to its capacity is taken as such a gross slip
without being solved: :data:`ASSUME_SLIP`); a state that fails for another reason (a
step Lemke cannot solve) says nothing of P*, and the next step goes half as far. Every
attempt starts its steps from the last held state's support (:meth:`StepLemke.rewind`),
not from a gross slip's: the first step after a held state can have two answers, one
sliding everywhere. A gross slip read off fewer than ``GROSS_STEPS`` outer steps is
retried once from the last held state itself (its end state, not the predicted start),
with Lemke's pivots where its support does not hold a step (not the frictionless-contact
guesses), and if it slips so again it is still no bound on P* (it says nothing of P*,
as a failure); after such a slide the step after the next held state goes at most
``SHAKY_SHARE`` of the way to it, and no step goes past the root of the quadratic of g
through the last three held states where g bends down. The nodes that pass from stick
to slip between two held
states are its events. P* is the secant's root once it is within ``rtol`` of the
last pull held (g(P) ≈ 0 there: the state is at gross slip), or of the root before
it while within :data:`SECANT_REACH` of the last pull held (within ~1e-7 of P* Lemke
is inexact on the degenerate step, docs/friction.md, so the states stop short of
it), or once the last pull held and a gross slip are within ``rtol`` of each other.
An extrapolation from states far below P* is never called converged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ProblemError
from ..model.friction_driver import GROSS_STEPS, FrictionState, StepLemke
from ..model.friction_path import PATH_SCENES, advance, place, with_pull
from ..model.friction_result import FrictionResult
from ..problems.checks import check_number
from ..problems.scenes import ActuatorScene
from ..problems.sections import SectionedScene

#: a step goes this share of the way to the secant's root (from below)
APPROACH = 0.999
#: two successive secant roots that agree to rtol give P* only within this share of
#: P* from the last pull held (the error of a secant root is second order in the
#: distance it reaches; an extrapolation from far below P* is never called converged)
SECANT_REACH = 1e-5
#: with the start held only, the secant's root is the start's capacity C(P₀) (slope −1:
#: C unchanged); C falls as the pull straightens the chain, so P* < C(P₀) and the state
#: APPROACH of the way there is a gross slip (flat wall, channel and stenosis of
#: benchmarks/friction_speed.py: P* is 0.92–0.94 C(P₀)). It is taken as one without
#: being solved (the steps go at most half way to it, as to a gross slip seen) until a
#: secant root passes it (a capacity that does not fall); never as a bracket of P*
ASSUME_SLIP = True
#: after a gross slip read off fewer than GROSS_STEPS outer steps (retried too), the
#: step that follows the next held state goes at most this share of the way to it (once:
#: it is no bound on P*, the first step after a held state can slide everywhere where the
#: state holds), and from then on no step goes past the root of the quadratic of g
#: through the last three held states where g bends down. Where the capacity falls
#: steeply near P* (the anchoring actuator at μ 0.5) the secant's root overshoots again
#: and again, each overshoot costing two solves (docs/friction.md, "Pull-out")
SHAKY_SHARE = 0.7


@dataclass
class PullOut:
    """The pull-out force of a scene and the path that found it (N, mm).

    ``force``: P*; ``capacity``: Σ μ_i N_i at the last state held; ``normal_forces``,
    ``tangential_forces``: per free node there; ``normal_force_total``: ΣN over every
    wall there; ``path``: the states held, in order; ``events``: (node, pull) where a
    node passed from stick to slip (the first held pull at which it slides);
    ``solves``: frictional states solved (held or not).
    """

    force: float
    capacity: float
    normal_forces: np.ndarray
    tangential_forces: np.ndarray
    normal_force_total: float
    converged: bool
    reason: str
    solves: int
    path: list[FrictionResult] = field(default_factory=list)
    events: list[tuple[int, float]] = field(default_factory=list)

    def __repr__(self) -> str:
        total = 1e3 * self.normal_force_total
        return (f"PullOut(force={1e3 * self.force:.6g} mN, ΣN={total:.6g} mN, "
                f"solves={self.solves}, converged={self.converged})")


def capacity(res: FrictionResult) -> float:
    """C = Σ μ_i N_i over every wall (N); against a wall y = h(x) (a profile) the pull
    that gross slip along +x balances, Σ N_i (μ_i t_x,i − n_x,i) = Σ N_i (μ_i ∓ h'_i) /
    √(1 + h'_i²) (− at the upper wall, + at the lower; h' at the nodes' x): the normal
    reactions' x parts take a share of the pull too (docs/friction.md)."""
    mu_up, mu_lo = res.scene.wall_friction
    walls = getattr(res.scene, "profiles", (None, None))
    xf = res.x[1:1 + res.forces.size]

    def share(N, mu, profile, side):
        if profile is None:
            return mu * float(np.sum(N))
        h1 = profile.slope(xf)
        return float(np.sum(N * (mu + side * h1) / np.sqrt(1.0 + h1 * h1)))

    lower = 0.0 if res.forces_lower is None else share(res.forces_lower, mu_lo, walls[1], 1.0)
    return share(res.forces, mu_up, walls[0], -1.0) + lower


def _check(scene) -> ActuatorScene | SectionedScene:
    if not isinstance(scene, PATH_SCENES):
        raise ProblemError(f"pull_out takes an ActuatorScene or a SectionedScene, got "
                           f"{type(scene).__name__}")
    if scene.left_end == "pinned" or scene.right_end != "slider":
        raise ProblemError("pull_out needs left_end='slider' and right_end='slider' (a "
                           "pinned end holds any pull; the pull acts on the right end), got "
                           f"left_end={scene.left_end!r}, right_end={scene.right_end!r}")
    if not any(m > 0 for m in scene.wall_friction):
        raise ProblemError("pull_out needs friction > 0 on a wall")
    return scene


def pull_out(scene, *, tol: float = 1e-10, rtol: float = 1e-6, max_solves: int = 20,
             max_outer: int = 30) -> PullOut:
    """The largest axial pull the scene holds (N): see the module's note.

    Parameters
    ----------
    scene : ActuatorScene or SectionedScene
        Sliders at both ends and friction; its ``pull`` (>= 0) is the path's start.
    tol : the outer loop's threshold on max|Δα| (rad) per state.
    rtol : P* is returned once the secant's root is within ``rtol`` (relative) of the
        last pull held or of the previous root.
    max_solves : the budget of frictional states.
    max_outer : the outer steps of each state (they take at most 7 on the scenes of
        ``benchmarks/friction_speed.py``; within ~1e-7 of P* a state on the degenerate
        step does not converge and would spend them all).

    Returns
    -------
    PullOut
        ``converged`` False (with a reason) when the budget runs out first or the
        start does not hold.
    """
    from ..api import solve

    _check(scene)
    rtol = check_number("rtol", rtol, low=1e-12, high=0.1)
    max_solves = int(check_number("max_solves", max_solves, low=2, high=1000, integer=True))
    if scene.pull < 0:
        raise ProblemError(f"pull_out starts from pull >= 0, got {scene.pull!r}")
    current, x_prev, why, y_prev = place(scene, tol=tol, max_outer=max_outer, solve=solve)
    if why:
        return PullOut(np.nan, np.nan, np.zeros(0), np.zeros(0), np.nan, False, why, 0)
    path, held, events, solves, ends = [], [], [], 0, []
    lcp = StepLemke()  # one for the path: the covering that solves a step carries over
    kept = lcp.warm_start()  # ... from the last held state: every attempt starts there
    P, fail, trouble, before = float(scene.pull), None, "", np.inf
    assumed, slip = not ASSUME_SLIP, None  # the gross slip taken, not solved (ASSUME_SLIP)
    shaky = None  # the lowest pull above the last held one that slid on a first step
    bent = False  # a first-step slide seen: no step past the quadratic's root of g
    while solves < max_solves:
        res, end = _attempt(scene, P, predicted(ends, P, current), x_prev, y_prev, lcp, kept,
                            tol=tol, max_outer=max_outer)
        solves += 1
        if path and _unproven(res) and solves < max_solves:  # once more: from the last
            # held state itself (its end, not the predicted start), Lemke after its support
            res, end = _attempt(scene, P, current, x_prev, y_prev, lcp, kept, tol=tol,
                                max_outer=max_outer, guesses=False)
            solves += 1
        if res.converged:
            if path:
                slid = path[-1].stick & ~res.stick
                events += [(int(j), P) for j in np.flatnonzero(slid)]
            path.append(res)
            held.append((P, capacity(res) - P))
            current, x_prev, y_prev = end, res.x.copy(), res.y.copy()
            ends.append((P, end))
            kept = lcp.warm_start()
            if shaky is not None and P >= shaky:  # it held: that slide was not a bound
                shaky = None
            if len(path) == 1 and capacity(res) <= 0.0:  # no node presses a wall
                return _answer(P, path, events, solves, True, "no wall contact at the "
                               "start: friction holds no pull beyond the start's")
        elif not path:
            return PullOut(np.nan, np.nan, np.zeros(0), np.zeros(0), np.nan, False,
                           f"the start (pull {P:g} N) does not hold: {res.reason}", solves)
        elif res.reason.startswith("gross slip") and not _unproven(res):
            fail = P if fail is None else min(fail, P)  # no equilibrium: P* < P
        elif res.reason.startswith("gross slip"):  # read off fewer steps: not a proof
            shaky, bent = (P if shaky is None else min(shaky, P)), True
            trouble = (f"; the state at pull {P:g} N ended in gross slip after "
                       f"{res.outer_iterations} outer step(s), not taken as a bound on P*")
        else:  # a state that failed for another reason says nothing of P*
            trouble = f"; the state at pull {P:g} N did not converge ({res.reason})"
        root, last = _secant_root(held), held[-1][0]
        near = abs(root - last) <= SECANT_REACH * abs(root)
        if len(held) >= 2 and (abs(root - last) <= rtol * abs(root) or (
                near and res.converged and abs(root - before) <= rtol * abs(root))):
            return _answer(root, path, events, solves, True, "secant root within rtol")
        if fail is not None and fail - last <= rtol * fail:  # P* in [last, fail]
            return _answer(min(max(root, last), fail), path, events, solves, True,
                           "bracketed within rtol: the last pull held and a gross slip")
        before = root
        step = APPROACH * (root - last)
        if bent and len(held) >= 3:  # g bends down: its quadratic's root, if nearer
            step = min(step, APPROACH * (_quadratic_root(held, root) - last))
        if slip is not None and root > slip:  # the capacity does not fall: no such slip
            slip = None
        if len(held) == 1 and not assumed and step > 0.0:
            assumed, slip = True, last + step
        # after a first-step slide, a secant root inside the bracket is stepped to
        # (APPROACH of the way), not half way to the gross slip
        inside = bent and fail is not None and last < root < fail and len(held) >= 2
        if (fail is not None or slip is not None) and not inside:
            step = min(step, 0.5 * ((slip if fail is None else fail) - last))
        if not res.converged and P != fail:  # go half as far as the step that failed
            step = min(step, 0.5 * (P - last))
        elif res.converged and shaky is not None:  # after a hold, at most SHAKY_SHARE of
            step = min(step, SHAKY_SHARE * (shaky - last))  # the way to a one-step slide
            shaky = None  # (once: it is no bound on P*, and a later step may pass it)
        P = last + step
    root = _secant_root(held)
    if fail is not None:  # never past a pull seen to slip: P* lies in [last held, fail]
        root = min(max(root, held[-1][0]), fail)
    return _answer(root, path, events, solves, False,
                   f"the budget of {max_solves} frictional solves ran out{trouble}"
                   + ("" if fail is None else
                      f"; P* lies between {held[-1][0]:.6g} N (held) and {fail:.6g} N "
                      f"(gross slip)"))


def _attempt(scene, P, start, x_prev, y_prev, lcp, kept, *, tol, max_outer, guesses=True):
    """The state at pull ``P`` from ``start``, its steps warm-started from the last held
    state's (``kept``, :meth:`StepLemke.warm_start`); ``guesses`` False: where that
    support does not hold a step, Lemke's pivots solve it, not the guesses."""
    lcp.rewind(kept)
    lcp.guesses = guesses
    try:
        return advance(with_pull(scene, P), {"pull": P}, start, x_prev, tol=tol,
                       max_outer=max_outer, lcp=lcp, y_prev=y_prev)
    finally:
        lcp.guesses = True


def _unproven(res) -> bool:
    """A gross slip read off fewer than GROSS_STEPS outer steps: where the step has
    several answers (one sliding everywhere), not a proof that there is no equilibrium."""
    return (not res.converged and res.reason.startswith("gross slip")
            and res.outer_iterations < GROSS_STEPS)


def predicted(ends: list, P: float, current: FrictionState) -> FrictionState:
    """Where the outer loop of the state at pull ``P`` starts: on the line through the
    last two held states' end states (α and x of node 1, against the pull), else at
    ``current``. A start only: the state is the fixed point whatever its start, its
    slips measured from the last held state."""
    if len(ends) < 2:
        return current
    (P0, s0), (P1, s1) = ends[-2:]
    t = (P - P1) / (P1 - P0)
    return FrictionState(s1.alpha + t * (s1.alpha - s0.alpha), s1.x0 + t * (s1.x0 - s0.x0))


def _secant_root(held: list[tuple[float, float]]) -> float:
    """The root of g(P) = C(P) − P on the secant through the last two held states (the
    slope −1 with one: C unchanged)."""
    P1, g1 = held[-1]
    if len(held) < 2:
        return P1 + g1
    P0, g0 = held[-2]
    slope = (g1 - g0) / (P1 - P0) if P1 != P0 else -1.0
    return P1 - g1 / slope if slope < 0 else P1 + g1


def _quadratic_root(held: list[tuple[float, float]], root: float) -> float:
    """The root above the last held pull of the quadratic of g through the last three
    held states, where it bends down (concave) and has one; else ``root`` (the
    secant's)."""
    (P0, g0), (P1, g1), (P2, g2) = held[-3:]
    if not (P0 < P1 < P2):
        return root
    d12 = (g2 - g1) / (P2 - P1)
    c = (d12 - (g1 - g0) / (P1 - P0)) / (P2 - P0)
    if not c < 0.0:
        return root
    b = d12 + c * (P2 - P1)  # g(P) = g2 + b (P − P2) + c (P − P2)², c < 0
    disc = b * b - 4.0 * c * g2
    if g2 <= 0.0 or disc < 0.0:
        return root
    return P2 + (-b - np.sqrt(disc)) / (2.0 * c)


def _answer(force, path, events, solves, converged, reason) -> PullOut:
    last = path[-1]
    lower = last.forces_lower if last.forces_lower is not None else 0.0
    return PullOut(float(force), capacity(last), last.forces + lower,
                   last.tangential_forces.copy(), last.total_force, converged, reason, solves,
                   path, events)
