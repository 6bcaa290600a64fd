"""The outer loop of a frictional state and the loading path (issue 39, docs/friction.md).

A state is solved from the last: its slips s_i = x_i − x_i^prev are measured from
the previous state's node positions. Each outer step assembles the frictional
contact step at the current α (:mod:`lcpbench.model.friction_step`), solves its LCP
(Lemke by default; any function ``(M, q) -> LCPSolution``), moves the heights by δy
(exact inverse kinematics) and the chain by τ, and re-linearises until
max|Δα| < tol and |τ| < tol·ℓ. At that fixed point the linearised gaps and slips
are the exact ones.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ProblemError
from ..problems.scenes import ActuatorScene, Chain, node_stiffness, reachable
from ..problems.templates import wall_share
from ..solvers.base import Status
from ..thresholds import FINAL_FLIPS, NEWTON_SWITCH
from .chain import node_positions

# (step_lemke and z_keys re-exported: the step's default solver lives in friction_lemke)
from .friction_lemke import StepLemke, step_kernels, step_lemke, z_keys  # noqa: F401
from .friction_walls import RUNAWAY, frictional_chain_args, outer_kernels

#: a node within NEAR · a of a wall gets a friction pair in the step (docs/friction.md)
NEAR = 1e-3
#: a node within ROW_BAND · a of a wall gets a normal row (docs/friction.md)
ROW_BAND = 1.0
#: the stiffness that holds the translation τ in a step, in EI/ℓ³: a proximal term,
#: exact at the fixed point (τ = 0 there; docs/friction.md)
TAU_STIFFNESS = 1.0
#: against a sloped wall a translation opens or closes the gaps (n_x τ), and with k_τ
#: soft one step can carry the chain far along x, beyond where its linearised gaps
#: hold: the step's LCP has a spurious answer beside the one friction holds (every node
#: off its wall, the chain carried |τ| = P/k_τ away), or steps of ~1 mm that the
#: gross-slip rule takes for sliding as a whole. A step whose |τ| exceeds TAU_REACH · a
#: there is solved again with k_τ TAU_STIFFEN times stiffer (a proximal term: the fixed
#: point does not depend on it), up to TAU_STIFFEN_MAX times (docs/friction.md)
TAU_REACH = 1.0
TAU_STIFFEN = 100.0
TAU_STIFFEN_MAX = 1e6
#: the stiffness that holds a free end's rotation about the pin in a step, in EI/ℓ per
#: rad: a proximal term as k_τ (docs/friction.md, free ends)
ROT_STIFFNESS = 1.0
#: the largest turn of a link in one outer step (rad); a longer step is shortened
MAX_TURN = 0.25
#: this many steps in a row at gross slip (:func:`gross_slip`) end a state: no equilibrium
GROSS_STEPS = 3
#: this many steps in a row that Lemke solves only INACCURATE end a state (not converged:
#: it converges on a SOLVED step only; near gross slip the step is degenerate and
#: stays so, and the outer loop would spend its budget there)
INEXACT_STEPS = 5


@dataclass
class FrictionState:
    """Where a path stands: link angles α (rad) and the x of node 1 (mm)."""

    alpha: np.ndarray
    x0: float = 0.0

    def positions(self, chain: Chain) -> tuple[np.ndarray, np.ndarray]:
        x, y = node_positions(chain, self.alpha)
        return x + self.x0, y


@dataclass
class FrictionStep:
    """One frictional contact step: the LCP, its Delassus form and how to map back.

    ``normal_node``/``normal_sign``: the free node and ∂g/∂y of each wall row;
    ``friction_node``: the node (0..N) of each friction pair; ``pair``: the pair of
    each wall row; ``mu``: the Coulomb coefficient of each wall row; ``normal_xy``,
    ``tangent_xy``: the wall's normal at each row and tangent at each pair (a wall
    y = h(x): n = (h', −1)/√(1 + h'²) at an upper wall, (−l', 1)/√(1 + l'²) at a lower
    one, t = (1, h')/√(1 + h'²); N along n, T along t). ``W``,
    ``g_f``, ``s_f``: the contact quantities (g + N/k, s) = (g_f, s_f) + W (N, T), the
    Siconos fc2d form (an elastic wall's compliance 1/k on W_nn's diagonal, 0 if rigid); ``M``, ``q``: the LCP in units of ℓ and EI/ℓ²
    (``length``, ``force``).
    """

    M: np.ndarray
    q: np.ndarray
    W: np.ndarray
    g_f: np.ndarray
    s_f: np.ndarray
    X: np.ndarray
    normal_node: np.ndarray
    normal_sign: np.ndarray
    friction_node: np.ndarray
    pair: np.ndarray
    mu: np.ndarray
    has_tau: bool
    origin: np.ndarray
    length: float
    force: float
    rowed: np.ndarray  # the free nodes with a normal row
    #: per wall row, the wall's normal n (the direction its gap grows) and per friction
    #: pair its tangent t, at the nodes' x (flat walls: (0, ∓1) and (1, 0))
    normal_xy: np.ndarray
    tangent_xy: np.ndarray
    #: the chain's part of the step as doubles (H's bands, f, tan α, gap, slip, …): what
    #: an exact oracle solves from (benchmarks/exact_friction.py)
    parts: dict | None = None

    def forces(self, z: np.ndarray):
        """(N, T, δy, τ) in N and mm of an LCP solution z (dimensionless)."""
        mn, mt = self.normal_node.size, self.friction_node.size
        zz = z.copy()
        zz[:mn + 2 * mt] *= self.force
        zz[mn + 2 * mt:] *= self.length
        N, T, d = step_kernels().recover(zz, self.X, mn, mt)
        return (N, T, d[:-1], float(d[-1])) if self.has_tau else (N, T, d, 0.0)


def check_frictional_ends(scene: ActuatorScene) -> None:
    """ProblemError for a free left end here: the step frees the right end only, and a
    path solves a free left end as its mirror image
    (:mod:`lcpbench.model.friction_mirror`, docs/friction.md, free ends)."""
    if scene.left_end == "free":
        raise ProblemError("left_end='free': the frictional step frees the right end only; "
                           "solve the scene along a path (lcpbench.solve_path mirrors it)")


def frictional_chain(scene: ActuatorScene) -> Chain:
    """The chain of a frictional state: the scene's, or with a free right end its tip's
    height unknown too (free nodes 2..N+1) and wall rows for every node within reach
    of the walls from the left pin (its arc length s >= h)."""
    chain = scene.chain()
    if scene.right_end != "free":
        return chain

    def make():
        n = chain.links
        free = np.arange(1, n + 1)
        can = reachable(free * chain.link_length, chain.length, scene.height, "clamped-free")
        upper = np.where(can, scene.height, np.inf)
        lower = np.where(can, -scene.height, -np.inf) if scene.channel else np.full(n, -np.inf)
        # the walls' springs (a row of sections has rigid walls only)
        k = node_stiffness(getattr(scene, "wall_stiffness", math.inf), can,
                           wall_share(n, chain.link_length, free))
        return replace(chain, free_nodes=free, upper=upper, lower=lower, upper_stiffness=k,
                       lower_stiffness=k if scene.channel else None)

    return chain.derived("friction: free right end", make)


def datum(scene: ActuatorScene) -> tuple[bool, bool]:
    """(has_tau, right_datum): τ is an unknown when no end holds x; the right end is
    the datum when only it is pinned."""
    left, right = scene.left_end == "pinned", scene.right_end == "pinned"
    return (not left and not right), (right and not left)


_NONE = np.zeros(0, bool)  # no mask, no previous heights


def frictional_step(scene: ActuatorScene, chain: Chain, state: FrictionState,
                    x_prev: np.ndarray, pressed: np.ndarray | None = None,
                    rowed: np.ndarray | None = None, left_pull: float = 0.0,
                    y_prev: np.ndarray | None = None, tau_stiffening: float = 1.0,
                    newton: bool = False) -> FrictionStep:
    """The frictional contact step of ``scene`` at ``state``, slips from ``x_prev``
    (:func:`lcpbench.model.friction_outer.assemble`): normal rows for the nodes within
    ROW_BAND·a of a wall or ``rowed`` before (the others' rows would make W singular;
    in a channel the nearer wall's only), friction pairs for those within NEAR·a or
    ``pressed`` (bool per free node). ``left_pull``: a force along x (N) on the left end
    (a mirrored scene's pull: it loads τ only); ``y_prev``: the previous node heights
    (the slip along a sloped wall); ``tau_stiffening``: k_τ's multiple
    (:data:`TAU_REACH`). A free right end's rotation is held by ROT_STIFFNESS."""
    has_tau, right_datum = datum(scene)
    first, n = int(chain.free_nodes[0]), int(chain.free_nodes.size)
    free_end = chain.free_nodes[-1] >= chain.links
    k_tau = TAU_STIFFNESS * tau_stiffening * chain.force_scale / chain.length
    arrays = frictional_chain_args(chain)
    mu_up, mu_lo = scene.wall_friction
    L, F = chain.length, chain.force_scale
    (code, M, q, W, g_f, s_f, X, rows, signs, pair_nodes, pairs, mus, near, normal_xy,
     tangent_xy, origin, bands, f, gap, slip, compliance, rot, rot_k) = outer_kernels().assemble(
        np.ascontiguousarray(state.alpha, dtype=float), float(state.x0),
        float(chain.link_length), *arrays[:4], first + 1, n, arrays[4], float(scene.pull),
        float(left_pull), right_datum, newton, has_tau, k_tau,
        ROT_STIFFNESS * scene.EI / chain.length if free_end else 0.0, *arrays[5:],
        float(mu_up), float(mu_lo), np.ascontiguousarray(x_prev, dtype=float),
        _NONE.astype(float) if y_prev is None else np.ascontiguousarray(y_prev, dtype=float),
        _NONE if pressed is None else pressed, _NONE if rowed is None else rowed,
        ROW_BAND, NEAR, float(F), float(L))
    if code == outer_kernels().NO_Y_PREV:
        raise ProblemError("the slip along a sloped wall needs the previous state's "
                           "node heights (y_prev)")
    if code == outer_kernels().NOT_DEFINITE:
        raise np.linalg.LinAlgError("the step's matrix is not positive definite")
    parts = dict(bands=bands, f=f, tan=np.tan(state.alpha), rot=rot, rot_k=rot_k, k_tau=k_tau,
                 gap=gap, slip=slip, compliance=compliance, first=first,
                 right_datum=right_datum)
    return FrictionStep(M, q, W, g_f, s_f, X, rows, signs, pair_nodes, pairs, mus, has_tau,
                        origin, L, F, near, normal_xy, tangent_xy, parts)


def _moved(scene: ActuatorScene, chain: Chain, fs: FrictionStep, z: np.ndarray,
           state: FrictionState, tol: float, stiff: float, solved: bool, x_right: float,
           pull: float):
    """(N, T, τ of the step, and None where no share of it keeps the links off the
    vertical, else (pressed, the new state, max|Δα|, τ taken, done, gross-slip excess)):
    :func:`lcpbench.model.friction_outer.move` of ``z`` from ``state``."""
    arrays = frictional_chain_args(chain)
    has_tau, right_datum = datum(scene)
    k = outer_kernels()
    code, N, T, tau_step, pressed, alpha, x0, dalpha, tau, done, excess = k.move(
        z, fs.X, fs.normal_node.size, fs.friction_node.size, float(fs.force),
        float(fs.length), has_tau, fs.normal_node, fs.pair, fs.mu, fs.normal_xy,
        fs.tangent_xy, fs.rowed, fs.origin, state.alpha, float(state.x0),
        float(chain.link_length), int(chain.free_nodes[0]) + 1, right_datum, float(x_right),
        MAX_TURN, float(tol), float(stiff), bool(solved), *arrays[5:11], ROW_BAND,
        float(pull))
    if code == k.VERTICAL:
        return N, T, tau_step, None
    return N, T, tau_step, (pressed, FrictionState(alpha, x0), dalpha, tau, done, excess)


def _stick_preferred(lcp, sol, out, start: FrictionState, args: tuple):
    """The step solved again by Lemke's pivots (``lcp.pivots``) where the warm start's
    answer ``sol`` (its move ``out``, :func:`_moved`) slides as a whole and runs the
    chain away: Lemke's answer and its move where it is SOLVED and does not run away
    (the step's answer that holds; docs/friction.md, "Pull-out"), else ``sol`` and
    ``out`` as they were, the solver's warm start as it was after ``sol``. ``args``:
    (scene, chain, the step, the state, tol, k_τ's multiple, x_right, pull)."""
    scene, chain, fs, state, tol, stiff, x_right, pull = args
    warm = lcp.warm_start()
    again = lcp.pivots(fs.M, fs.q, z_keys(fs))
    if again.solved:
        out2 = _moved(scene, chain, fs, again.z, state, tol, stiff, True, x_right, pull)
        moved = out2[3]
        if moved is not None and abs(moved[1].x0 - start.x0) <= RUNAWAY * chain.length:
            again.extra["start"] = "Lemke, after a warm start that slid as a whole"
            return again, out2
    lcp.rewind(warm)
    return sol, out


@dataclass
class StateAnswer:
    """The outer loop's answer for one state (before it is judged)."""

    state: FrictionState
    normal: np.ndarray  # N per wall row (N)
    tangential: np.ndarray  # T per friction pair (N)
    step: FrictionStep | None
    converged: bool
    reason: str
    iterations: int
    step_sizes: list = field(default_factory=list)
    time_s: float = 0.0
    left_pull: float = 0.0  # N along x on the left end (a mirrored scene's pull)


def solve_state(scene: ActuatorScene, start: FrictionState, x_prev: np.ndarray, *,
                tol: float, max_outer: int = 100, lcp=None,
                left_pull: float = 0.0, y_prev: np.ndarray | None = None) -> StateAnswer:
    """The outer loop of one state from ``start``, slips from ``x_prev`` (and ``y_prev``,
    the previous node heights, against a wall of any profile; docs/friction.md);
    ``lcp``: the step's solver (default a :class:`StepLemke`); ``left_pull`` as
    :func:`frictional_step`'s. A solver that defers its polish (``defers_polish``) has
    the answer that would end the state polished, not the steps before it
    (docs/friction.md, "The polish"). Each step moves the chain by
    :func:`lcpbench.model.friction_outer.move`; the state ends on a full step of a SOLVED
    answer that turns no link by ``tol``, moves the chain by less than tol·ℓ along x,
    leaves every pressed node with its friction pair and every node near a wall with its
    row."""
    check_frictional_ends(scene)
    lcp = StepLemke() if lcp is None else lcp
    newton = getattr(lcp, "newton", False)
    takes_step = getattr(lcp, "takes_step", False)
    defer = takes_step and getattr(lcp, "defers_polish", False)
    t0 = time.perf_counter()
    chain = frictional_chain(scene)
    has_tau, right_datum = datum(scene)
    x_right = start.positions(chain)[0][-1]  # a pinned right end stays where it starts
    state = FrictionState(start.alpha.copy(), start.x0)
    sizes: list[float] = []
    N = T = np.zeros(0)
    fs = held = None  # held: the step whose answer N, T are (a failed step is not theirs)
    pressed, away, it, gross, inexact, excess = None, False, 0, 0, 0, 0.0
    stiff = TAU_STIFFEN  # k_τ's multiple (:data:`TAU_REACH`)
    final = False  # every step polished (a polished answer did not end the state)
    refused: dict = {}  # the state's last refused polish (friction_lemke.polish_step)
    pull = float(scene.pull) + left_pull
    for it in range(1, max_outer + 1):
        # Newton on the springs once the last step turned no link by NEWTON_SWITCH; for
        # the rest of the state not after a Newton step that did not halve (a cycle)
        if newton and len(sizes) >= 2 and sizes[-2] < NEWTON_SWITCH \
                and sizes[-1] > 0.5 * sizes[-2]:
            newton = False
        # a step starts one stiffening softer than the last, and is solved again stiffer
        # where a sloped wall gives the spurious slide (:data:`TAU_REACH`)
        stiff, rowed = max(1.0, stiff / TAU_STIFFEN), None if fs is None else fs.rowed
        while True:
            try:
                fs = frictional_step(scene, chain, state, x_prev, pressed, rowed, left_pull,
                                     y_prev, stiff, newton and bool(sizes)
                                     and sizes[-1] < NEWTON_SWITCH)
            except np.linalg.LinAlgError as exc:  # (K singular: a link at the vertical)
                return StateAnswer(state, N, T, held, False, f"contact step {it}: {exc}", it,
                                   sizes, time.perf_counter() - t0, left_pull)
            # a solver by name (model.friction_solvers.step_runner) takes the whole step;
            # one that defers its polish answers unpolished (polished below, once)
            sol = (lcp(fs, polish=False) if defer else lcp(fs) if takes_step
                   else lcp(fs.M, fs.q))
            # an inexact step only moves the iterate (the judge reads the last one, which
            # must be SOLVED): go on from it, as the frictionless driver does
            if not (sol.solved or (sol.status is Status.INACCURATE
                                   and np.all(np.isfinite(sol.z)))):
                return StateAnswer(state, N, T, held, False, f"contact step {it}: "
                                   f"{sol.status.name} ({sol.message})", it, sizes,
                                   time.perf_counter() - t0, left_pull)
            N, T, tau, moved = _moved(scene, chain, fs, sol.z, state, tol, stiff,
                                      sol.solved, x_right, pull)
            if not (chain.profiled_walls and abs(tau) > TAU_REACH * chain.link_length
                    and stiff < TAU_STIFFEN_MAX):
                break
            stiff *= TAU_STIFFEN
        if moved is not None and moved[5] and abs(moved[1].x0 - start.x0) > \
                RUNAWAY * chain.length and "start" in sol.extra and hasattr(lcp, "pivots"):
            # a warm start's answer that slides as a whole and carries the chain away
            # (the state would end on it): the step can have two answers, and Lemke's
            # pivots may find the one that holds (docs/friction.md, "Pull-out")
            sol, (N, T, tau, moved) = _stick_preferred(
                lcp, sol, (N, T, tau, moved), start,
                (scene, chain, fs, state, tol, stiff, x_right, pull))
        held = fs
        if defer and (final or (moved is not None and moved[4])):
            # the answer that would end the state leaves through the primal polish: the
            # state is then the polished answer's move, tested again; where that move is
            # not below tol the loop goes on from it, every step polished from then on
            # (the polished step's fixed point is the state's; docs/friction.md, "The
            # polish"). Each may flip a failing index set (FINAL_FLIPS), kept as the
            # state's answer only where its move passes; one whose signs fail after its
            # flips and the edge search is returned as it was (the judge decides), and
            # the next step's answer with the same failing set is not searched again
            polished = lcp.polish(fs, sol, FINAL_FLIPS, refused)
            final = True
            if polished is not sol:
                sol = polished
                N, T, _, moved = _moved(scene, chain, fs, sol.z, state, tol, stiff,
                                        sol.solved, x_right, pull)
        if moved is None:
            return StateAnswer(state, N, T, fs, False, f"contact step {it}: a link would "
                               "pass the vertical (no chain has these heights)", it, sizes,
                               time.perf_counter() - t0, left_pull)
        pressed, state, dalpha, tau, done, ex = moved
        sizes.append(dalpha)
        if done:
            return StateAnswer(state, N, T, fs, True, "max|Δα| < tol", it, sizes,
                               time.perf_counter() - t0, left_pull)
        # on a profile the capacity changes as the chain moves: a run of steps at gross
        # slip counts only while the excess does not shrink (a chain sliding towards
        # where friction holds it is on its way to an equilibrium; docs/friction.md)
        gross = (0 if not ex else 1 if chain.profiled_walls and gross
                 and ex < excess * (1.0 - 1e-9) else gross + 1)
        excess = ex
        runaway = abs(state.x0 - start.x0) > RUNAWAY * chain.length
        away = runaway or gross >= GROSS_STEPS
        inexact = 0 if sol.solved else inexact + 1
        if not np.isfinite(dalpha) or away or inexact >= INEXACT_STEPS:
            break
    # gross slip only where GROSS_STEPS steps in a row were, or every step of a chain that
    # ran away: one that ran along x while its steps changed contact sets (an outer loop
    # cycling) has not shown that there is no equilibrium
    why = ("gross slip: every contact node slides at its cone and friction holds less than "
           "the pull (no equilibrium)" if gross >= GROSS_STEPS or (away and gross == it) else
           f"no convergence: the chain ran {RUNAWAY:g} ℓ along x in {it} contact steps "
           "without its steps sliding as a whole" if away else
           f"the step's LCP solved only INACCURATE in {inexact} contact steps in a row"
           if inexact >= INEXACT_STEPS else f"no convergence in {it} contact steps"
           + ("" if fs is None or sol.solved else f" (the last {sol.status.name})"))
    return StateAnswer(state, N, T, fs, False, why, it, sizes, time.perf_counter() - t0,
                       left_pull)
