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
from ..problems.scenes import ActuatorScene, Chain, node_stiffness, reachable, wall_share
from ..solvers.base import Status
from ..thresholds import FINAL_FLIPS, NEWTON_SWITCH
from .chain import alpha_from_heights, node_positions
from .elastic import compliances

# (step_lemke and z_keys re-exported: the step's default solver lives in friction_lemke)
from .friction_lemke import StepLemke, step_kernels, step_lemke, z_keys  # noqa: F401
from .friction_walls import gaps_at, near_walls, tangential_slip, wall_frames, walls_at_x

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
#: a state whose chain moves along x by more than RUNAWAY · ℓ has no equilibrium
RUNAWAY = 10.0
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


def rotation_mode(chain: Chain, x: np.ndarray) -> np.ndarray | None:
    """r, the free heights' increments of a rigid rotation about node 1 by 1 rad
    (r_i = x_i − x_1), when the right end is free (None: both ends held in y)."""
    if chain.free_nodes[-1] < chain.links:
        return None
    return x[chain.free_nodes] - x[0]


def datum(scene: ActuatorScene) -> tuple[bool, bool]:
    """(has_tau, right_datum): τ is an unknown when no end holds x; the right end is
    the datum when only it is pinned."""
    left, right = scene.left_end == "pinned", scene.right_end == "pinned"
    return (not left and not right), (right and not left)


def contact_rows(scene: ActuatorScene, chain: Chain, rowed: np.ndarray,
                 touching: np.ndarray, g_up: np.ndarray, g_lo: np.ndarray):
    """The wall rows (free node, ∂g/∂y, μ, pair) and the friction pairs' nodes.

    The nodes ``rowed`` (near a wall: bool per free node) have a normal row; the
    others are left out of the step (their rows would make W singular, more columns
    than unknowns; the outer loop adds the row of a node that comes near, and
    converges only when none does). In a channel the row is for the nearer wall only
    (gaps ``g_up``, ``g_lo``: the two rows of a node are each other's negatives, and
    both would make W singular; the outer loop re-picks the wall at every step).
    Only the free nodes ``touching`` (at a wall, or pressed in the last step) get a
    friction pair (pair −1: none): a node away from the walls carries no friction,
    and its pair would only make the LCP degenerate.
    """
    mu_up, mu_lo = scene.wall_friction
    up, lo = np.isfinite(chain.upper) & rowed, np.isfinite(chain.lower) & rowed
    both = up & lo  # a channel node: the nearer wall only
    up, lo = np.where(both, g_up <= g_lo, up), np.where(both, g_lo < g_up, lo)
    rows = up | lo
    paired = rows & touching
    pair_of = np.full(rows.size, -1, np.int64)
    pair_of[paired] = np.arange(int(np.count_nonzero(paired)))
    nodes = np.flatnonzero(rows)  # (one wall per node: up and lo exclude each other)
    upper = up[nodes]
    return (nodes.astype(np.int64), np.where(upper, -1.0, 1.0),
            np.where(upper, mu_up, mu_lo), pair_of[nodes],
            chain.free_nodes[paired].astype(np.int64))


def frictional_step(scene: ActuatorScene, chain: Chain, state: FrictionState,
                    x_prev: np.ndarray, pressed: np.ndarray | None = None,
                    rowed: np.ndarray | None = None, left_pull: float = 0.0,
                    y_prev: np.ndarray | None = None, tau_stiffening: float = 1.0,
                    newton: bool = False, at: tuple | None = None) -> FrictionStep:
    """The frictional contact step of ``scene`` at ``state``, slips from ``x_prev``:
    normal rows for the nodes within ROW_BAND·a of a wall or ``rowed`` before,
    friction pairs for those within NEAR·a or ``pressed`` (bool per free node: a
    normal force in the last step). ``left_pull``: a force along x (N) on the left
    end (a mirrored scene's pull, :mod:`lcpbench.model.friction_mirror`); the left end
    is the datum, so it loads τ only and has no curvature. ``y_prev``: the previous
    state's node heights (the slip along a sloped wall, :func:`tangential_slip`);
    ``tau_stiffening``: k_τ's multiple (:data:`TAU_REACH`); ``at``: the node positions
    of ``state`` and :func:`walls_at_x` there (x, y, walls), where known already."""
    has_tau, right_datum = datum(scene)
    first, n = int(chain.free_nodes[0]), int(chain.free_nodes.size)
    k = step_kernels()
    f64 = np.ascontiguousarray
    # the chain's part: the banded step (model.step.assemble_step, compiled), the pull
    # (the chain's arrays as the kernel takes them: made once per chain, not per step)
    left, right, stiffness, rest, load = chain.derived("friction: step arrays", lambda: (
        f64(chain.joint_links[:, 0], dtype=np.int64), f64(chain.joint_links[:, 1], dtype=np.int64),
        f64(chain.joint_stiffness, dtype=float), f64(chain.rest_joint, dtype=float),
        f64(chain.nodal_load, dtype=float)))
    bands, f, D, origin = k.step_arrays(
        f64(state.alpha, dtype=float), float(chain.link_length), left, right, stiffness,
        rest, first + 1, n, load, float(scene.pull), right_datum, newton)
    x, y, walls = (*state.positions(chain), None) if at is None else at
    r = rotation_mode(chain, x)
    rot, rot_k = np.empty(0), 0.0
    if r is not None:  # a free end: the rotation about the pin held by ROT_STIFFNESS
        rot, rot_k = r, ROT_STIFFNESS * scene.EI / chain.length / float(r @ r) ** 2
    k_tau = TAU_STIFFNESS * tau_stiffening * chain.force_scale / chain.length
    if has_tau:  # τ: one more unknown, moving every node's x, held by k_τ
        D = np.hstack([D, np.ones((D.shape[0], 1))])
        f = np.append(f, float(scene.pull) + left_pull)
    if walls is None:  # (the profile evaluated once per step)
        walls = walls_at_x(chain, x)
    s_up, s_lo = walls[2], walls[3]
    g_up, g_lo = gaps_at(chain, x, y, walls)
    closest = np.minimum(g_up, g_lo)  # (near_walls, from the gaps at hand)
    near = closest <= ROW_BAND * chain.link_length
    touching = closest <= NEAR * chain.link_length
    if pressed is not None:
        touching |= pressed
    if rowed is not None:
        near |= rowed
    touching &= near
    rows, signs, mus, pairs, pair_nodes = contact_rows(scene, chain, near, touching,
                                                       g_up, g_lo)
    # a wall y = h(x): N along its normal, T along its tangent, at the nodes' x (lagged)
    slope = np.where(signs < 0, s_up[rows], s_lo[rows])
    normal_xy = wall_frames(signs, slope)
    gap = np.where(signs < 0, g_up[rows], g_lo[rows]) * np.abs(normal_xy[:, 1])
    pslope = np.zeros(pair_nodes.size)
    pslope[pairs[pairs >= 0]] = slope[pairs >= 0]
    pc = np.sqrt(1.0 + pslope * pslope)
    tangent_xy = np.column_stack([1.0 / pc, pslope / pc])
    slip = tangential_slip(x, y, x_prev, y_prev, pair_nodes, pslope)
    W, g_f, s_f, X, ok = k.delassus_form(bands, rot, rot_k, k_tau, f, rows, normal_xy, gap,
                                         np.ascontiguousarray(D), pair_nodes, tangent_xy,
                                         slip, first)
    if not ok:
        raise np.linalg.LinAlgError("the step's matrix is not positive definite")
    # an elastic wall's row: 0 <= N ⟂ g + N/k >= 0, its compliance 1/k (mm/N) on W_nn's
    # diagonal (docs/friction.md, elastic walls); 0 for a rigid wall: W unchanged
    c_up, c_lo = chain.derived("friction: compliances", lambda: compliances(chain))
    compliance = np.where(signs < 0, c_up[rows], c_lo[rows])
    W[np.arange(rows.size), np.arange(rows.size)] += compliance
    L, F = chain.length, chain.force_scale
    M, q = k.frictional_lcp(W * (F / L), g_f / L, s_f / L, mus, pairs)
    parts = dict(bands=bands, f=f, tan=np.tan(state.alpha), rot=rot, rot_k=rot_k, k_tau=k_tau,
                 gap=gap, slip=slip, compliance=compliance, first=first,
                 right_datum=right_datum)
    return FrictionStep(M, q, W, g_f, s_f, X, rows, signs, pair_nodes, pairs, mus, has_tau,
                        origin, L, F, near, normal_xy, tangent_xy, parts)


def gross_slip(fs: FrictionStep, N: np.ndarray, T: np.ndarray, pull: float) -> float:
    """Whether a step of a chain that no end holds in x slides as a whole: every pair
    at its cone (|T| = μN) and the pull beyond what they hold, |P| > Σ μN (so ΣT + P ≠ 0
    whatever the directions of T); returned as the excess |P| − Σ μN (N), 0.0 when not.
    On flat walls the next step is the same one moved along x, so there is no
    equilibrium (docs/friction.md). Every pair at its cone with |P| <= Σ μN is not that:
    the tangential forces then oppose each other in part (a chain turning or rolling in
    a channel), and the step is an iterate on the way to an equilibrium that friction
    can hold. Against a wall of any profile, P is P + Σ N n_x and Σ μN is Σ μN t_x."""
    limit = np.zeros(T.size)
    paired = fs.pair >= 0
    np.add.at(limit, fs.pair[paired], (fs.mu * N)[paired])
    # against sloped walls the normal reactions' x parts load the chain along x too, and
    # friction holds along x only its tangent's x part of μN
    load = pull + float(fs.normal_xy[:, 0] @ N)
    capacity = float(limit @ fs.tangent_xy[:, 0])
    scale = max(abs(load), capacity, 1e-300)
    at_cone = np.all(np.abs(T) >= limit - 1e-9 * scale)
    excess = abs(load) - capacity
    return float(excess) if at_cone and excess > 1e-9 * scale else 0.0


def damped(chain: Chain, origin: np.ndarray, dy: np.ndarray, alpha: np.ndarray):
    """(α, share): the step's heights origin + share·δy, share = 1 unless that turns a
    link by more than MAX_TURN or past the vertical, then halved until it does not (an
    iterate, not the answer: a state converges on full steps only). (None, 0) when no
    share of 2⁻³⁰ helps."""
    share = 1.0
    for _ in range(30):
        new = alpha_from_heights(chain, origin + share * dy, alpha)
        if new is not None and np.max(np.abs(new - alpha)) <= MAX_TURN:
            return new, share
        share *= 0.5
    return None, 0.0


def _moved(chain: Chain, fs: FrictionStep, sol, state: FrictionState, tol: float,
           stiff: float, right_datum: bool, x_right: float, forces=None):
    """Where the step's answer ``sol`` moves the chain from ``state``, and whether that
    ends the state: (pressed, the new state, max|Δα|, τ, done, at); None where no share
    of the step keeps the links off the vertical (:func:`damped`); ``at``: the new
    state's node positions and walls (:func:`frictional_step`'s); ``forces``:
    ``fs.forces(sol.z)`` where known. Done: a full step of a
    SOLVED answer that turns no link by ``tol`` and moves the chain by less than
    tol·ℓ/stiff along x, every pressed node with its friction pair and every node near
    a wall with its row."""
    N, _, dy, tau = fs.forces(sol.z) if forces is None else forces
    pressed = np.zeros(chain.free_nodes.size, bool)
    pressed[fs.normal_node[N > 0]] = True
    # every pressed node had its friction pair: else the step is not the answer yet
    paired = bool(np.all(fs.pair[N > 0] >= 0))
    alpha, share = damped(chain, fs.origin, dy, state.alpha)
    if alpha is None:
        return None
    dalpha = float(np.max(np.abs(alpha - state.alpha)))
    tau *= share
    new = FrictionState(alpha, state.x0 + tau)
    if right_datum:
        new.x0 = x_right - float(np.sum(chain.link_length * np.cos(alpha)))
    # every node that is now near a wall had its row
    x, y = new.positions(chain)
    walls = walls_at_x(chain, x)
    settled = not np.any(near_walls(chain, x, y, ROW_BAND, walls) & ~fs.rowed)
    # (k_τ τ is the imbalance along x: with k_τ stiffened, τ is held to tol·ℓ/stiff)
    done = (dalpha < tol and abs(tau) * stiff < tol * chain.length and paired
            and share == 1.0 and settled and sol.solved)
    return pressed, new, dalpha, tau, done, (x, y, walls)


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
    (docs/friction.md, "The polish")."""
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
    at = None  # the state's node positions and walls (known after a step)
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
                                     and sizes[-1] < NEWTON_SWITCH, at)
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
            N, T, dy, tau = fs.forces(sol.z)
            if not (chain.profiled_walls and abs(tau) > TAU_REACH * chain.link_length
                    and stiff < TAU_STIFFEN_MAX):
                break
            stiff *= TAU_STIFFEN
        held = fs
        moved = _moved(chain, fs, sol, state, tol, stiff, right_datum, x_right,
                       (N, T, dy, tau))
        if defer and (final or (moved is not None and moved[4])):
            # the answer that would end the state leaves through the primal polish: the
            # state is then the polished answer's move, tested again; where that move is
            # not below tol the loop goes on from it, every step polished from then on
            # (the polished step's fixed point is the state's; docs/friction.md, "The
            # polish"). Each may flip a failing index set (FINAL_FLIPS), kept as the
            # state's answer only where its move passes; one whose signs fail after its
            # flips comes back INACCURATE (not an answer: it only moves the iterate)
            polished = lcp.polish(fs, sol, FINAL_FLIPS)
            final = True
            if polished is not sol:
                sol = polished
                N, T, _, _ = fs.forces(sol.z)
                moved = _moved(chain, fs, sol, state, tol, stiff, right_datum, x_right)
        if moved is None:
            return StateAnswer(state, N, T, fs, False, f"contact step {it}: a link would "
                               "pass the vertical (no chain has these heights)", it, sizes,
                               time.perf_counter() - t0, left_pull)
        pressed, state, dalpha, tau, done, at = moved
        sizes.append(dalpha)
        if done:
            return StateAnswer(state, N, T, fs, True, "max|Δα| < tol", it, sizes,
                               time.perf_counter() - t0, left_pull)
        ex = gross_slip(fs, N, T, float(scene.pull) + left_pull) if has_tau else 0.0
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


def fc2d_form(fs: FrictionStep) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The step in Siconos' fc2d form (:mod:`lcpbench.solvers.siconos_fc2d`),
    dimensionless (lengths by ℓ, forces by EI/ℓ²): wall row r is a contact with
    u = (g_r, s_p), r = (N_r, T_p), p its friction pair. Needs one row per pair
    (a step built with every rowed node ``pressed``); ProblemError otherwise."""
    mn, pairs = fs.normal_node.size, fs.pair
    if np.any(pairs < 0) or np.unique(pairs).size != mn or fs.friction_node.size != mn:
        raise ProblemError("fc2d_form needs one friction pair per wall row (build the step "
                           "with every rowed node pressed)")
    idx = np.empty(2 * mn, np.int64)
    idx[0::2] = np.arange(mn)
    idx[1::2] = mn + pairs
    W = fs.W[np.ix_(idx, idx)] * (fs.force / fs.length)
    q = np.concatenate([fs.g_f, fs.s_f])[idx] / fs.length
    return W, q, fs.mu.copy()
