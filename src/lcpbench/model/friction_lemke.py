"""The default solver of the frictional step (issue 39, docs/friction.md): Lemke with the
step's pivot tolerance and covering vectors, warm-started by block principal pivoting
from the last answer's support or, where that does not hold, from the frictionless
contacts with the pressed nodes sticking or every pair sliding (compiled:
:func:`lcpbench.model.friction_step.first_support_from`,
:func:`lcpbench.solvers.pivoting_kernel.support_pivots`). Any answer is taken only where
lcpbench's natural residual meets Lemke's own bound.
"""

from __future__ import annotations

import time

import numpy as np

from ..numba_cache import kept
from ..solvers.base import LCPSolution, Status, lcp_residuals
from ..solvers.lemke import RESIDUAL_TOL, lemke
from ..thresholds import (
    POLISH_EDGE_NODES,
    POLISH_EDGE_SETS,
    POLISH_FLIPS,
    POLISH_LIKELY_LEVEL,
    POLISH_MOST_FAILING,
    POLISH_STICK_COMPLIANCE,
    POLISH_SWEEPS,
)

#: Lemke's pivot tolerance on the frictional LCP (solvers.lemke's default: 1e-12). Its
#: W is singular where many nodes have rows (the chain is inextensible: a node's x
#: follows from the heights), and entries that are 0 but for round-off (1e-12 of the
#: column) must not be pivots
PIVOT_TOL = 1e-9
#: the seed of the random covering vectors :class:`StepLemke` tries last
COVERING_SEED = 39
#: Lemke's pivot budget on the frictional step, in pivots per unknown (solvers.lemke's
#: default is 50): a solved step takes at most ~1.3 n at N = 140 (issue 39's speed
#: benchmark), and a degenerate one that cycles is cut short and tried with another
#: covering vector
PIVOT_BUDGET = 4


#: Lemke's tie tolerance in its last try on a step where every covering stopped short
#: (solvers.lemke.TIE_RTOL, 1e-9, is the default): on elastic steps (cond(B) ≈ 2.6e8) the
#: ratio test at 1e-9 keeps z0's row as tied where it is not and stops with a basic w at
#: −1.5e-3; at 1e-12 the step is solved. Not the default: on the 100 paths of
#: benchmarks/friction_agreement.py it made 11 more states fail than it saved
STRICT_TIES = 1e-12
#: the most supports the warm start (:meth:`StepLemke.last_support`) tries before Lemke
WARM_CHANGES = 20
#: where the last answer's support does not hold, :class:`StepLemke` tries the guesses of
#: :func:`lcpbench.model.friction_step.first_support_from` (stick, then slide) with this many
#: supports each, then again with WARM_CHANGES: a wrong guess costs little, and the right
#: one takes a few (the channel's first step of benchmarks/friction_speed.py: stick, 2)
WARM_GUESS_CHANGES = 5
#: a path's first step (no last answer): the frictionless contacts' active set
#: (:func:`lcpbench.solvers.pivoting_kernel.symmetric_active_set`) may make this many
#: solves per wall row (each adds or drops one row; 22 for the 87 rows of
#: benchmarks/friction_speed.py's channel)
WARM_NORMAL_CHANGES = 2
#: the warm start's candidate is feasible where no z or w is below −this · max(1, |q|, |z|)
WARM_FEAS_RTOL = 1e-9
#: the warm start's M_SS is singular where a pivot is at most this share of its largest entry
WARM_PIVOT_RTOL = 1e-13
#: where it is, the candidate is M_SS's least-squares solution, singular values below this
#: share of the largest cut (a run of sticking nodes: T per node is indeterminate)
WARM_RCOND = 1e-12

_KERNELS: list = []  # the compiled step (model/friction_step.py), once loaded
_PIVOTING: list = []  # the warm start's pivots (solvers/pivoting_kernel.py), once loaded
_POLISH: list = []  # the primal polish (model/friction_polish.py), once loaded
#: :func:`polish_step`'s verdicts (``sol.extra["polish"]``), by the kernel's code
POLISH_VERDICTS = ("kept", "no primal form (the step has no parts)", "singular", "a sign fails",
                   "primal residual not lower", "LCP residual above the bound", "not SOLVED")


def pivoting_kernels():
    """Block principal pivoting from a support (:mod:`lcpbench.solvers.pivoting_kernel`),
    loaded once through :func:`lcpbench.numba_cache.kernel_module`."""
    return kept(_PIVOTING, "lcpbench.solvers.pivoting_kernel", "support_pivots")


def step_kernels():
    """The frictional step's compiled functions (:mod:`lcpbench.model.friction_step`),
    loaded once through :func:`lcpbench.numba_cache.kernel_module` (numba's cache
    under the hash of every kernel file)."""
    return kept(_KERNELS, "lcpbench.model.friction_step", "delassus_form")


def polish_kernels():
    """The frictional step's primal polish (:mod:`lcpbench.model.friction_polish`),
    loaded once through :func:`lcpbench.numba_cache.kernel_module`."""
    return kept(_POLISH, "lcpbench.model.friction_polish", "polish")


def polish_args(fs, z: np.ndarray) -> tuple[tuple, tuple]:
    """The polish kernels' arguments for the answer ``z`` of the frictional step ``fs``
    (:func:`lcpbench.model.friction_polish.polish_on`, ``polish_sets``): the step's
    parts (``head``) and the answer's (``answer``: z, the moves, the forces N and T, the
    scales and the polish's settings)."""
    P = fs.parts
    N, T, dy, tau = fs.forces(z)
    head = (P["bands"], P["f"], P["tan"], float(P["k_tau"]), int(P["first"]),
            bool(P["right_datum"]), P["gap"], P["slip"], P["compliance"],
            fs.normal_node, fs.normal_xy, fs.friction_node, fs.tangent_xy, fs.mu, fs.pair,
            P["rot"], float(P["rot_k"]))
    answer = (z, dy, float(tau), N, T, float(fs.force), float(fs.length),
              float(fs.length) / P["tan"].size, POLISH_STICK_COMPLIANCE, POLISH_SWEEPS)
    return head, answer


def polish_step(fs, sol: LCPSolution, flips: int = POLISH_FLIPS,
                refused: dict | None = None) -> LCPSolution:
    """A SOLVED answer of the step ``fs`` polished on its index set in the step's primal
    form (:func:`lcpbench.model.friction_polish.polish`, compiled, O(N); docs/friction.md,
    "The polish"). The polished answer replaces ``sol`` only where every sign of the index
    set holds (after ``flips`` flips of the failing nodes, then :func:`edge_polish`;
    neither where more than POLISH_MOST_FAILING signs fail at the answer's own set), its
    primal residual is below the answer's, and lcpbench's natural residual of the LCP
    still meets RESIDUAL_TOL; otherwise ``sol`` is returned as it is, its status
    unchanged (its LCP residual decides it; the state's judge decides the state). A
    status is never raised (an answer that is not SOLVED is not polished). The verdict
    is ``extra["polish"]`` (:data:`POLISH_VERDICTS`), the signs that failed at each set
    the flips solved ``extra["polish_failing"]``, the unpolished z
    ``extra["unpolished"]`` where it was replaced; an answer polished already is
    returned as it is. ``refused``: a memo the polishes of one state share (the driver's,
    :func:`lcpbench.model.friction_driver.solve_state`): an answer whose own set and its
    failing nodes are those of the last polish, refused, is refused after its own set
    (:func:`searched_polish`; ``extra["polish_repeat"]``)."""
    if "polish" in sol.extra:
        return sol
    if not sol.solved or fs.parts is None or not np.all(np.isfinite(sol.z)):
        sol.extra["polish"] = POLISH_VERDICTS[6 if fs.parts is not None or not sol.solved
                                              else 1]
        return sol
    t0 = time.perf_counter()
    w = fs.M @ sol.z + fs.q
    k = polish_kernels()
    head, answer = polish_args(fs, sol.z)  # (a free end's rotation borders the band)
    contact, state = k.index_set(sol.z, w, fs.normal_node.size, fs.friction_node.size,
                                 fs.pair, fs.mu)
    out, failing, repeat, name = searched_polish(k, head, answer, w, fs, flips, contact,
                                                 state, refused)
    code, z, r0, r1 = out[:4]
    failing = tuple(failing)
    if refused is not None:  # the refusal this polish ends on, or none
        refused["last"] = name if code == k.SIGNS else None
    extra = dict(sol.extra, polish_residuals=(r0, r1), polish_failing=failing)
    if code != 1 and repeat:
        extra["polish_repeat"] = True
    if code == 0:
        res = lcp_residuals(fs.M, fs.q, z)
        if not res["natural"] <= RESIDUAL_TOL:
            code = 5
    extra["polish"] = POLISH_VERDICTS[code]
    extra["polish_time"] = time.perf_counter() - t0
    if code != 0:
        sol.extra = extra
        return sol
    extra.update(residuals=res, unpolished=sol.z,
                 unpolished_residuals=sol.extra.get("residuals"))
    return LCPSolution(z, fs.M @ z + fs.q, sol.status, sol.iterations,
                       sol.solve_time + extra["polish_time"], sol.setup_time, sol.message,
                       extra)


def searched_polish(k, head, answer, w, fs, flips, contact, state, refused):
    """The search of the polish of the answer (``answer``: :func:`polish_args`; w = M z +
    q) from its own set (``contact``, ``state``): ((verdict, z, r0, r1), the signs that
    failed at each set the flips solved, whether it stopped at a repeat, the name of the
    refusal it may end on (:func:`refusal`, or None)). In order, each only where the
    one before found no set whose signs hold:

    1. the own set (``k.polish_on`` without flips); where more than
       POLISH_MOST_FAILING signs fail there, or ``flips`` is 0, nothing more;
    2. where its signs fail at the nodes, flipped the same way, of the last polish of the
       state, refused (``refused["last"]``, a memo the state's polishes share), nothing
       more: the search would start where the last one started, from an answer of the
       same outer loop (a guess, not a proof: the answer is returned as it was, as any
       refusal, and the state's judge decides it);
    3. where a failing node is a sticking pair of a level or nearly level run
       (:func:`level_run_fails`: joined to a sticking neighbour by a link with |tan α|
       <= POLISH_LIKELY_LEVEL, where T per node is indeterminate or all but), the
       edge search's picks (:func:`edge_picks`, every one, not only the
       POLISH_EDGE_SETS of the fewest changes) made of likely states only
       (:func:`likely_states`: such a pair sliding at its cone against its run's T, or
       sticking), in their order, at most POLISH_EDGE_SETS;
    4. the flips (``k.polish_on``: the own set's first flip, before step 3, then
       ``flips`` − 1 more);
    5. :func:`edge_polish`: the POLISH_EDGE_SETS picks of the fewest changes, in their
       order (where step 3 ran, those of them it did not try).

    Step 3 runs after the first flip (most polishes the flips keep, they keep there: 33
    of 59 on benchmarks/friction_agreement.py's Lemke paths). Without it the sets,
    verdicts and answers are those of one ``polish_on`` with ``flips`` flips and then
    the edge search (a flip onto the own set or the first flip's solves that set again
    where the one call stopped: the same verdict, each a function of its set)."""
    own = k.polish_on(*head, *answer, 0, contact, state)
    failing = [int(f) for f in own[8]]
    if own[0] != k.SIGNS or not flips or own[8][0] > POLISH_MOST_FAILING:
        return own[:4], failing, False, None
    name = refusal(contact, state, own[4], own[5])
    last = None if refused is None else refused.get("last")
    if last is not None and all(np.array_equal(a, b) for a, b in zip(name, last)):
        return own[:4], failing, True, name
    once = k.polish_on(*head, *answer, 0, own[4], own[5])  # the first flip
    failing += [int(f) for f in once[8]]
    if once[0] != k.SIGNS:
        return once[:4], failing, False, name
    seen_c, seen_s = np.concatenate((own[6], once[6])), np.concatenate((own[7], once[7]))
    nodes, picks, likely = edge_picks(k, answer, w, fs, contact, state, own[4], own[5])
    if likely.any() and level_run_fails(k, head, state, own[5]):
        out = k.polish_sets(*head, *answer, contact, state, nodes,
                            picks[likely][:POLISH_EDGE_SETS], POLISH_EDGE_SETS, seen_c, seen_s)
        if out[0] == k.KEPT:
            return out, failing, False, name
        picks = picks[:POLISH_EDGE_SETS][~likely[:POLISH_EDGE_SETS]]  # (the rest, in order)
    else:
        picks = picks[:POLISH_EDGE_SETS]
    more = once
    if flips > 1 and once[8][0] <= POLISH_MOST_FAILING:
        more = k.polish_on(*head, *answer, flips - 2, once[4], once[5])
        failing += [int(f) for f in more[8]]
        if more[0] != k.SIGNS:
            return more[:4], failing, False, name
        seen_c, seen_s = np.concatenate((seen_c, more[6])), np.concatenate((seen_s, more[7]))
    out = edge_polish(k, head, answer, contact, state, nodes, picks, POLISH_EDGE_SETS,
                      seen_c, seen_s)
    return (out if out[0] == k.KEPT else more[:4]), failing, False, name


def refusal(contact, state, flip_c, flip_s):
    """What names a refused polish (:func:`searched_polish`): the answer's own set and
    the set its failing nodes flip it to (``flip_c``, ``flip_s``)."""
    return contact.copy(), state.copy(), flip_c.copy(), flip_s.copy()


def level_run_fails(k, head, state, flip_s) -> bool:
    """Whether a sticking pair whose sign fails (its state changed in ``flip_s``, the own
    set's first flip) is joined to a sticking neighbour by a link level or nearly: |tan
    α| at most POLISH_LIKELY_LEVEL. Along such a run T per node is indeterminate (level:
    the polish holds it at the answer's split) or all but, and the flips read a slide's
    direction from a polished T that can point either way. Level links were left out
    until the held pair's slip became a sign of its set (``friction_polish.signs``):
    before, on one of the active set's steps of benchmarks/friction_agreement.py (path
    52), the likely picks kept a set whose held slip the exact solution breaks; now such
    a set is refused like any whose sign fails (docs/friction.md, "What limits target
    2": state 12.1)."""
    tan, friction_node = head[2], head[11]
    sticks = state == k.STICK
    stick_at = np.zeros(tan.size + 1, np.bool_)
    stick_at[friction_node[sticks]] = True
    near = np.abs(tan) <= POLISH_LIKELY_LEVEL
    for c in np.flatnonzero(sticks & (flip_s != state)):
        i = int(friction_node[c])
        if (i >= 1 and stick_at[i - 1] and near[i - 1]) or \
                (i < tan.size and stick_at[i + 1] and near[i]):
            return True
    return False


def edge_picks(k, answer, w, fs, contact, state, flip_c, flip_s):
    """The edge search's nodes and picks: (nodes, picks, whether each pick is made of
    likely states only, :func:`likely_states` of the runs' T, :func:`run_sums`). The
    nodes: those whose sign fails at the own set's polished answer (their state changed
    in its first flip, ``flip_c``, ``flip_s``), at most :data:`POLISH_EDGE_NODES`, those
    whose LCP pairs are nearest the edge of two states first (both sides of the pair
    smallest). The picks: every state of those nodes (a row in contact or separate, a
    pair STICK, FORWARD or BACKWARD), all of them, the fewest changes first
    (:func:`edge_order`), the own set's left out (at most 3⁶ = 729; the searches try at
    most POLISH_EDGE_SETS of them: :func:`searched_polish`)."""
    z = answer[0]
    mn, mt = fs.normal_node.size, fs.friction_node.size
    lam = mn + 2 * mt
    rim = np.concatenate([np.maximum(np.abs(z[:mn]), np.abs(w[:mn])),
                          np.maximum(np.abs(z[lam:]), np.abs(w[lam:]))])
    failing = np.concatenate([flip_c != contact, flip_s != state])
    order = np.lexsort((rim, ~failing))
    nodes = np.array([int(i) for i in order if failing[i]][:POLISH_EDGE_NODES], np.int64)
    now = [int(contact[i]) if i < mn else int(state[i - mn]) for i in nodes]
    choices = [(1, 0) if i < mn else (k.STICK, k.FORWARD, k.BACKWARD) for i in nodes]
    runs = run_sums(k, fs.parts["tan"], fs.friction_node, state, answer[4])
    every = int(np.prod([len(c) for c in choices]))
    picks, likely = edge_order(choices, now, likely_states(k, nodes, now, mn, runs), every)
    return nodes, picks, likely


def edge_polish(k, head, answer, contact, state, nodes, picks, most, seen_c, seen_s):
    """The edge search (``k.polish_sets``: ``polish_on`` without flips on each set, in
    one compiled call): the sets that differ from the own set (``contact``, ``state``)
    at ``nodes`` only, each row of ``picks`` their states, in order, at most ``most``,
    the sets solved before (``seen_c``, ``seen_s``: the own set and the flips') passed
    over: the first kept, as :func:`polish_step`'s (verdict, z, r0, r1), else SIGNS. The
    nodes whose sign holds keep their state: on the 100 paths of
    benchmarks/friction_agreement.py each of the 18 sets this search kept differed from
    the answer's only at failing nodes (a sticking pair made to slide, or an off one to
    stick), none at a node whose sign held; searched too, those nodes made a search that
    finds nothing cost 64 sets, not 8 (docs/friction.md, "The polish")."""
    if not nodes.size or most <= 0:
        return k.SIGNS, answer[0], np.nan, np.nan
    return k.polish_sets(*head, *answer, contact, state, nodes, picks, most, seen_c, seen_s)


def likely_states(k, nodes, now, mn, T) -> list[tuple]:
    """Per edge node (``nodes``, as :func:`edge_picks`'s; ``now`` their states, ``T``
    per pair the answer's T summed over its sticking run, :func:`run_sums`) the states its
    exact answer most likely has: a wall row either; a sticking pair its own or sliding
    against its run's T (FORWARD where T < 0: T = −μN), a sliding pair its own or
    sticking. Where the answer's T per node is ill-determined (a level or nearly straight
    run of sticking nodes) the polished T that the flips read a slide's direction from
    can point either way, and so can the answer's T per node (agreement state 12.1: a
    run's whole T on one of its two nodes, 0 on the other, which slides with it); the
    answer's T summed over the run (the LCP's) does not: the channel's kept sets of
    benchmarks/friction_speed.py slide each of their changed pairs against it, and
    12.1's its three (docs/friction.md, "What limits target 2")."""
    likely = []
    for i, s in zip(nodes, now):
        if i < mn:
            likely.append((1, 0))
        elif s == k.STICK:
            likely.append((k.STICK, k.FORWARD if T[i - mn] < 0.0 else k.BACKWARD))
        else:
            likely.append((s, k.STICK))
    return likely


def run_sums(k, tan, friction_node, state, T) -> np.ndarray:
    """Per pair the answer's T summed over its sticking run: the sticking pairs joined to
    it, neighbour by neighbour, by links with |tan α| <= POLISH_LIKELY_LEVEL (level or
    nearly: T per node along such a run is indeterminate or all but, its sum is not); a
    pair not sticking, its own T."""
    out = np.asarray(T, np.float64).copy()
    order = np.argsort(friction_node, kind="stable")
    run: list[int] = []
    for c in order:
        joined = bool(run) and state[c] == k.STICK and \
            friction_node[c] == friction_node[run[-1]] + 1 and \
            abs(tan[friction_node[run[-1]]]) <= POLISH_LIKELY_LEVEL
        if not joined:
            if len(run) > 1:
                out[run] = np.sum(np.asarray(T)[run])
            run = []
        if state[c] == k.STICK:
            run.append(int(c))
    if len(run) > 1:
        out[run] = np.sum(np.asarray(T)[run])
    return out


def edge_order(choices, now, likely, most) -> tuple[np.ndarray, np.ndarray]:
    """The edge search's picks of one state per edge node (``choices``: each node's
    states) as rows, in the order tried: the ``most`` with the fewest changes from
    ``now``, at least one (``now`` itself is the own set; a node's state in ``now`` need
    not be one of its choices: an off pair whose row comes into contact, so that no pick
    is ``now``), in the order of ``itertools.product(*choices)`` within a tie; and per
    pick whether each of its states is one of its node's ``likely`` states
    (:func:`likely_states`)."""
    if not choices:
        return np.zeros((0, 0), np.int64), np.zeros(0, np.bool_)
    grids = np.meshgrid(*[np.array(c, np.int64) for c in choices], indexing="ij")
    picks = np.stack([g.ravel() for g in grids], axis=1)  # itertools.product's order
    changes = (picks != np.array(now, np.int64)).sum(axis=1)
    order = np.argsort(changes, kind="stable")
    picks = picks[order[changes[order] > 0][:most]]  # (``now`` itself, where a pick, not)
    ok = np.ones(len(picks), np.bool_)
    for j, states in enumerate(likely):
        ok &= np.isin(picks[:, j], np.array(states, np.int64))
    return picks, ok


def step_coverings(n: int) -> list[np.ndarray]:
    """The covering vectors :class:`StepLemke` tries, in order: (1 … n)/n, all ones
    (Lemke's default), (2 … 1), then three seeded random ones in [1, 2). (1 … n)/n
    first: on 20 steps of four pulled scenes at N = 140 it solved 13, all ones none
    (Lemke stops on a ray)."""
    rng = np.random.default_rng(COVERING_SEED)
    return ([np.arange(1, n + 1) / n, np.ones(n), np.linspace(2.0, 1.0, n)]
            + [1.0 + rng.random(n) for _ in range(3)])


class StepLemke:
    """The default solver of the frictional step: Lemke with :data:`PIVOT_TOL` and at
    most :data:`PIVOT_BUDGET` · n pivots, and where it stops short of SOLVED (near gross
    slip the LCP is degenerate: every node at its cone) again with the other covering
    vectors (:func:`step_coverings`): other pivot paths to the same solution set. The
    step's LCP always has a solution (W is positive semidefinite: Stewart–Trinkle), so a
    ray is a numerical failure.

    One instance serves a path: it tries first the covering that solved its last step
    (the steps of a path are alike, and so is the covering that gets through), so the
    restarts are paid once, not at every step. And before any pivot, block principal
    pivoting from the support of its last answer (:meth:`last_support`; Lemke's basic z,
    named by node): the outer steps of a state, and the states of a path, mostly keep
    their stick/slip/separate pattern, so the next step's answer is one linear solve on
    that support, or a few where some nodes change state. That answer is taken only
    where lcpbench's natural residual meets Lemke's own bound (``RESIDUAL_TOL``), as any
    Lemke answer; else (a cycle, the budget :data:`WARM_CHANGES`) Lemke runs. A fresh
    instance starts with the first covering and no support: its first step is Lemke's.
    """

    #: the driver hands it the whole step (its rows' nodes name the support)
    takes_step = True
    #: the driver's steps near the answer take the springs' exact curvature (Newton:
    #: :func:`frictional_step`'s ``newton``); the peers by name get Gauss–Newton steps
    newton = True
    #: the driver asks for the step's answer unpolished (``polish=False``) and polishes,
    #: by :meth:`polish`, only the answer that would end a state (docs/friction.md, "The
    #: polish")
    defers_polish = True

    def __init__(self) -> None:
        self.first = 0
        self.support = np.empty(0, np.int64)  # the last answer's support (basic z), by z_keys
        self.warm_solves = 0  # the linear solves of the warm start (counted, for benchmarks)
        self.guesses = True  # False: no frictionless-contact guesses, Lemke after S

    def warm_start(self) -> tuple[int, np.ndarray]:
        """What it carries from one step to the next (the covering that solved last, the
        last answer's support): kept at a held state of a path, given back by
        :meth:`rewind` (a pull-out's attempt after a gross slip starts from the last held
        state's, not from the sliding answer's: docs/friction.md, "Pull-out")."""
        return self.first, self.support.copy()

    def rewind(self, warm: tuple[int, np.ndarray]) -> None:
        """Start the next step from ``warm`` (:meth:`warm_start`)."""
        self.first, self.support = warm[0], warm[1].copy()

    def last_support(self, M: np.ndarray, q: np.ndarray, keys: np.ndarray | None):
        """The LCP's answer by block principal pivoting (:func:`lcpbench.solvers.
        pivoting_kernel.support_pivots`, at most :data:`WARM_CHANGES` supports) from the
        last answer's support S (read by node from ``keys``, :func:`z_keys`), SOLVED where
        its natural residual meets RESIDUAL_TOL; None otherwise (no support, a singular
        M_SS, the budget, or a residual above the bound)."""
        if keys is None or not keys.size or not self.support.size:
            return None
        # (np.isin by a table of the names: ~10× cheaper at these sizes, the same S)
        named = np.zeros(max(int(keys.max()), int(self.support.max())) + 1, bool)
        named[self.support] = True
        S = named[keys]
        if not S.any():
            return None
        t0 = time.perf_counter()
        k = pivoting_kernels()
        z, w, S, end, solves = k.support_pivots(np.ascontiguousarray(M), q, S, WARM_CHANGES,
                                                WARM_FEAS_RTOL, WARM_PIVOT_RTOL, WARM_RCOND)
        return self.taken(M, q, keys, z, S, end, solves, t0, "the last answer's support")

    def first_guess(self, M: np.ndarray, q: np.ndarray, keys: np.ndarray | None,
                    pair: np.ndarray | None, slide: bool, changes: int, contacts: dict):
        """The answer of a step whose last answer's support does not hold (or that has
        none: a path's first) by block principal pivoting from the frictionless
        contacts, the pressed nodes sticking (``slide`` False) or every pair sliding
        against its free slip (True; :func:`lcpbench.model.friction_step.first_support_from`,
        compiled; at most ``changes`` supports of the whole LCP), SOLVED where its natural
        residual meets RESIDUAL_TOL; None otherwise (Lemke then). ``contacts``: the
        step's frictionless contacts, found at its first guess and kept there for the
        others (:func:`~lcpbench.model.friction_step.frictionless_contacts`)."""
        if keys is None:
            return None
        t0 = time.perf_counter()
        k = step_kernels()
        budget = max(WARM_CHANGES, WARM_NORMAL_CHANGES * pair.size)
        if not contacts:
            contacts["M"] = np.ascontiguousarray(M)
            contacts["pair"] = np.ascontiguousarray(pair, dtype=np.int64)
            N, end, solves = k.frictionless_contacts(contacts["M"], q, pair.size, budget,
                                                     WARM_FEAS_RTOL, WARM_PIVOT_RTOL)
            contacts.update(N=N, done=end == pivoting_kernels().DONE)
            self.warm_solves += int(solves)
        if not contacts["done"]:
            return None
        z, w, S, end, solves = k.first_support_from(
            contacts["M"], q, contacts["pair"], contacts["N"], slide, budget, changes,
            WARM_FEAS_RTOL, WARM_PIVOT_RTOL, WARM_RCOND)
        how = "every pair sliding" if slide else "the pressed nodes sticking"
        return self.taken(M, q, keys, z, S, end, solves, t0, f"the frictionless contacts, {how}")

    def taken(self, M, q, keys, z, S, end, solves, t0, start):
        """The pivoting's answer z (support S) as a SOLVED LCPSolution where it ended DONE
        and its natural residual meets RESIDUAL_TOL (the support kept for the next step);
        None otherwise."""
        self.warm_solves += int(solves)
        if end != pivoting_kernels().DONE or not np.all(np.isfinite(z)):
            return None
        res, w = lcp_residuals(M, q, z, with_w=True)
        if not res["natural"] <= RESIDUAL_TOL:
            return None
        self.support = keys[S]
        return LCPSolution(z, w, Status.SOLVED, int(solves), time.perf_counter() - t0,
                           extra={"residuals": res, "start": start})

    def __call__(self, M, q: np.ndarray | None = None, polish: bool = True):
        """Solve the step ``M`` (a :class:`FrictionStep`), or the LCP (``M``, ``q``). The
        whole step's answer leaves through the primal polish unless ``polish`` is False
        (the driver's intermediate steps)."""
        if q is None:
            sol = self.solve(M.M, M.q, z_keys(M), M.pair)
            return polish_step(M, sol) if polish else sol
        return self.solve(M, q)

    @staticmethod
    def polish(fs, sol: LCPSolution, flips: int = POLISH_FLIPS,
               refused: dict | None = None) -> LCPSolution:
        """``sol``, an answer of the step ``fs``, through the primal polish
        (:func:`polish_step`; ``flips``: its flips of a failing index set). An answer the
        polish refuses is returned as it was; the step is not solved again from the
        other starts (on the 100 paths of benchmarks/friction_agreement.py no polish of
        a state's last answer reached that re-solve — every one the flips left refused
        the edge search kept — and on the channel of benchmarks/friction_speed.py it
        never found an answer the polish keeps, at ~29 ms a state: docs/friction.md,
        "The polish"); ``refused``: the state's memo of its last refusal,
        :func:`polish_step`)."""
        return polish_step(fs, sol, flips, refused)

    def solve(self, M, q, keys=None, pair=None):
        """The LCP (``M``, ``q``): the warm start from the last support (``keys``, the
        unknowns' names, :func:`z_keys`) or the frictionless contacts (``pair``), else
        Lemke's pivots."""
        sol = self.last_support(M, q, keys)
        contacts: dict = {}  # the step's frictionless contacts, once
        for budget in (WARM_GUESS_CHANGES, WARM_CHANGES) if self.guesses else ():
            for slide in (False, True):  # (a short try of each guess first)
                if sol is None:
                    sol = self.first_guess(M, q, keys, pair, slide, budget, contacts)
        if sol is not None:
            return sol
        return self.pivots(M, q, keys)

    def pivots(self, M, q, keys=None):
        """The LCP (``M``, ``q``) by Lemke's pivots, each covering vector in turn
        (:func:`step_coverings`, the last that solved first), then again at ties of
        :data:`STRICT_TIES`; its basic z is the next warm start's support."""
        n = q.size
        coverings = step_coverings(n)
        order = [self.first] + [i for i in range(len(coverings)) if i != self.first]
        sol = None
        for i, tie in [(i, None) for i in order] + [(i, STRICT_TIES) for i in order]:
            sol = lemke(M, q, pivot_tol=PIVOT_TOL, max_pivots=PIVOT_BUDGET * max(n, 25),
                        covering=coverings[i], tie_rtol=tie)
            if sol.solved:
                self.first = i
                if keys is not None:  # the basic z (M_SS nonsingular), not only z > 0
                    basic = sol.extra.get("basic_z", np.flatnonzero(sol.z > 0.0))
                    self.support = keys[basic]
                break
        return sol


def z_keys(fs) -> np.ndarray:
    """Each unknown of the step's LCP, z = (N, β⁺, β⁻, λ), named by its node: 5 j + c,
    j the node, c 0 for the upper wall's N (∂g/∂y = −1), 1 the lower's, 2 β⁺, 3 β⁻, 4 λ
    (a wall row by node and side, a friction pair's three by their node); the same names
    from step to step, whatever rows a step has."""
    rows = 5 * np.asarray(fs.normal_node, np.int64) + (np.asarray(fs.normal_sign) > 0)
    pairs = 5 * np.asarray(fs.friction_node, np.int64)
    return np.concatenate([rows, pairs + 2, pairs + 3, pairs + 4])


def step_lemke(M: np.ndarray, q: np.ndarray):
    """One frictional step solved by a fresh :class:`StepLemke`."""
    return StepLemke()(M, q)
