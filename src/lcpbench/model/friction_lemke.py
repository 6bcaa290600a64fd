"""The default solver of the frictional step (issue 39, docs/friction.md): Lemke with the
step's pivot tolerance and covering vectors, warm-started by block principal pivoting
from the last answer's support or, where that does not hold, from the frictionless
contacts with the pressed nodes sticking or every pair sliding (compiled:
:func:`lcpbench.model.friction_step.first_support`,
:func:`lcpbench.solvers.pivoting_kernel.support_pivots`). Any answer is taken only where
lcpbench's natural residual meets Lemke's own bound.
"""

from __future__ import annotations

import itertools
import time

import numpy as np

from ..solvers.base import LCPSolution, Status, lcp_residuals
from ..solvers.lemke import RESIDUAL_TOL, lemke
from ..thresholds import (
    POLISH_EDGE_NODES,
    POLISH_EDGE_SETS,
    POLISH_FLIPS,
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
#: :func:`lcpbench.model.friction_step.first_support` (stick, then slide) with this many
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
    if not _PIVOTING:
        from ..numba_cache import held, kernel_module

        held(_PIVOTING).append(kernel_module("lcpbench.solvers.pivoting_kernel",
                                             "support_pivots"))
    return _PIVOTING[0]


def step_kernels():
    """The frictional step's compiled functions (:mod:`lcpbench.model.friction_step`),
    loaded once through :func:`lcpbench.numba_cache.kernel_module` (numba's cache
    under the hash of every kernel file)."""
    if not _KERNELS:
        from ..numba_cache import held, kernel_module

        held(_KERNELS).append(kernel_module("lcpbench.model.friction_step", "delassus_form"))
    return _KERNELS[0]


def polish_kernels():
    """The frictional step's primal polish (:mod:`lcpbench.model.friction_polish`),
    loaded once through :func:`lcpbench.numba_cache.kernel_module`."""
    if not _POLISH:
        from ..numba_cache import held, kernel_module

        held(_POLISH).append(kernel_module("lcpbench.model.friction_polish", "polish"))
    return _POLISH[0]


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


def polish_step(fs, sol: LCPSolution, flips: int = POLISH_FLIPS) -> LCPSolution:
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
    returned as it is."""
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
    out = k.polish_on(*head, *answer, flips, contact, state)  # (polish, its sets)
    code, z, r0, r1 = out[:4]
    failing = tuple(int(f) for f in out[8])
    # an answer at whose own set more signs fail than round-off explains: no search
    if code == k.SIGNS and flips and out[8][0] <= POLISH_MOST_FAILING:
        code, z, r0, r1 = edge_polish(k, head, answer, w, fs, out)
    extra = dict(sol.extra, polish_residuals=(r0, r1), polish_failing=failing)
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


def edge_polish(k, head, answer, w, fs, flipped):
    """Where the polish's flips find no index set whose signs hold (``flipped``:
    ``k.polish_on``'s answer, SIGNS, with the sets it solved, the answer's own first): every
    state of the nodes whose sign fails at the polished answer of the answer's own set
    (``k.polish_sets``: ``polish_on`` on each set, no flips, in one compiled call, the
    sets the flips solved passed over; at most :data:`POLISH_EDGE_NODES` of them,
    those whose LCP pairs are nearest the edge of two states first: both sides of the
    pair smallest), the sets with the fewest changes first, at most
    :data:`POLISH_EDGE_SETS`: the first kept, as :func:`polish_step`'s (verdict, z, r0,
    r1); else ``flipped``'s. The nodes whose sign holds keep their state: on the 100 paths
    of benchmarks/friction_agreement.py each of the 18 sets this search kept differed
    from the answer's only at failing nodes (a sticking pair made to slide, or an off
    one to stick), none at a node whose sign held; searched too, those nodes made a
    search that finds nothing cost 64 sets, not 8 (docs/friction.md, "The polish")."""
    z = answer[0]
    mn, mt = fs.normal_node.size, fs.friction_node.size
    refused, seen_c, seen_s = flipped[:4], flipped[6], flipped[7]
    contact, state = seen_c[0], seen_s[0]
    # the first flip's set (the answer's own set's failing nodes flipped), as polish_on
    # with no flips returns it
    first = (seen_c[1], seen_s[1]) if len(seen_c) > 1 else flipped[4:6]
    lam = mn + 2 * mt
    rim = np.concatenate([np.maximum(np.abs(z[:mn]), np.abs(w[:mn])),
                          np.maximum(np.abs(z[lam:]), np.abs(w[lam:]))])
    failing = np.concatenate([first[0] != contact, first[1] != state])
    order = np.lexsort((rim, ~failing))
    nodes = [int(i) for i in order if failing[i]][:POLISH_EDGE_NODES]
    if not nodes:
        return refused
    now = [bool(contact[i]) if i < mn else int(state[i - mn]) for i in nodes]
    choices = [(True, False) if i < mn else (k.STICK, k.FORWARD, k.BACKWARD) for i in nodes]
    picks = sorted(itertools.product(*choices),
                   key=lambda p: sum(a != b for a, b in zip(p, now)))[1:]
    out = k.polish_sets(*head, *answer, contact, state, np.array(nodes, np.int64),
                        np.array(picks, np.int64).reshape(len(picks), len(nodes)),
                        POLISH_EDGE_SETS, seen_c, seen_s)
    return out if out[0] == k.KEPT else refused


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
        against its free slip (True; :func:`lcpbench.model.friction_step.first_support`,
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
    def polish(fs, sol: LCPSolution, flips: int = POLISH_FLIPS) -> LCPSolution:
        """``sol``, an answer of the step ``fs``, through the primal polish
        (:func:`polish_step`; ``flips``: its flips of a failing index set). An answer the
        polish refuses is returned as it was; the step is not solved again from the
        other starts (on the 100 paths of benchmarks/friction_agreement.py no polish of
        a state's last answer reached that re-solve — every one the flips left refused
        the edge search kept — and on the channel of benchmarks/friction_speed.py it
        never found an answer the polish keeps, at ~29 ms a state: docs/friction.md,
        "The polish")."""
        return polish_step(fs, sol, flips)

    def solve(self, M, q, keys=None, pair=None):
        """The LCP (``M``, ``q``): the warm start from the last support (``keys``, the
        unknowns' names, :func:`z_keys`) or the frictionless contacts (``pair``), else
        Lemke's pivots."""
        sol = self.last_support(M, q, keys)
        contacts: dict = {}  # the step's frictionless contacts, once
        for budget in (WARM_GUESS_CHANGES, WARM_CHANGES):  # a short try of each guess first
            for slide in (False, True):
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
