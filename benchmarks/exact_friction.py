"""The frictional step on an index set, solved exactly in rational arithmetic: an oracle
that says whether a back-end's answer is an answer, and whether a step has several.

The step (``lcpbench.model.friction_driver.FrictionStep``, docs/friction.md) is taken
from the doubles it was built from (``FrictionStep.parts``: H's bands, f, tan α, the
gaps and slips, k_τ, a free end's rotation), not from its Delassus matrix W = GᵀK⁻¹G:
in floating point W is only nearly singular where it is singular in fact (a run of
nodes sticking to a wall: T per node is statically indeterminate), and an exact solve
on the rounded W would decide T per node by round-off. In its primal form the step is
sparse and banded, node by node: the heights' equilibrium K δ = f + G_n N + G_t T,
with the slips' Jacobian D (dense) written as its recurrence δx_i − δx_{i−1} =
−tan α_{i−1} (δy_i − δy_{i−1}) (from the datum: the left end, τ, or the right end),
and Dᵀ F^x as the links' horizontal forces L_k (F^x: n_x N + t_x T at each node). The
index set (per wall row: contact or separate; per friction pair: stick, slide forward
(s ≥ 0, T = −μN), slide backward (s ≤ 0, T = +μN), or off when its row is separate)
adds one equation per row and per pair; :func:`solve` eliminates the whole system in
:class:`fractions.Fraction` (exact Gaussian elimination, sparse rows) and then checks
every sign condition exactly: N >= 0 in contact, g >= 0 when separate, |T| <= μN when
sticking, s of its sign when sliding.

Where the index set makes the equations dependent (two sticking neighbours on a wall:
the link between them fixes the second slip), the step's doubles meet the dependent
equation only to their own round-off: it is dropped and its residual reported
(``inconsistency``, relative to the size of its terms); beyond
:data:`CONSISTENT_RTOL` (and, for a gap or slip equation, beyond the round-off of the
positions it is built from, :data:`POSITION_ROUNDOFF` ℓ) the set has no exact solution
(the neighbours make that node
slip). A null direction is a free unknown (T per node in a stick run), set where the
exact solution is nearest the answer (least squares over the exact null directions:
any choice is an exact solution). Links level to round-off (|tan α| <= :data:`LEVEL`)
are level. A null direction that moves the chain (δy, δx, τ) and not only the forces
is a ray of answers (``ray``). An answer at the edge of two index sets is searched
for on its neighbours (:func:`nearest_exact`: flips, then :func:`edge_search`).
Not library code: the tests and benchmarks/friction_agreement.py use it.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from exact_friction_step import (  # noqa: F401 (re-exported: the oracle's callers read them here)
    LEVEL,
    PrimalStep,
    answer_values,
    chain_step,
)
from exact_friction_step import to_fraction as _q

#: a pair's states: stick, slide forward (s >= 0, T = −μN), backward, off (row separate)
STICK, FORWARD, BACKWARD, OFF = 0, 1, -1, None
#: an answer is near its exact solution when N and the move differ by at most this
#: (relative to the answer's largest force, and to the link length): target 2's 1e-6
NEAR_RTOL = 1e-6
#: dropped dependent equations may be off by at most this share of their terms' size,
#: or, for a gap or slip equation, by :data:`POSITION_ROUNDOFF` ℓ: their constants are
#: differences of node positions of size up to ℓ (x_i − x_i^prev, h − y_i), so where the
#: terms themselves are round-off (a slip of 2e-14 mm) the relative test reads noise
#: (1.8e-15 mm is 4 % of such terms); 16 ε ℓ is 1.1e-13 mm at ℓ = 30 mm, far below a
#: real mismatch (9e-12 mm between two sticking neighbours, docs/friction.md)
CONSISTENT_RTOL = 1e-12
POSITION_ROUNDOFF = 16 * float(np.finfo(float).eps)
#: index sets tried per answer: the one read from it, then with failing nodes flipped;
#: then :func:`edge_search`: a node is at the edge of two states when both sides of one
#: of its LCP pairs are within EDGE_RTOL of 0 (target 2's 1e-6); every state of at most
#: EDGE_NODES of them, at most EDGE_SETS index sets, the fewest changes first
FLIP_ROUNDS, EDGE_RTOL, EDGE_NODES, EDGE_SETS = 6, 1e-6, 6, 160


def _affine(expr, v):
    const, d = expr
    return float(const) + sum(float(c) * v[k] for k, c in d.items())


def read_states(step: PrimalStep, v: np.ndarray) -> tuple[list, list]:
    """The index set of an answer (its unknowns v, floats), each LCP pair's larger side:
    a row is in contact when N/F >= g/ℓ; a pair sticks when its cone's margin
    (μN − |T|)/F is at least |s|/ℓ, else slides against T."""
    F, ell = step.force, step.length
    rows = [v[step.normal[r]] / F >= _affine(step.gap[r], v) / ell
            for r in range(len(step.normal))]
    pairs = []
    for c in range(len(step.tangential)):
        mine = [r for r in range(len(rows)) if step.pair[r] == c]
        if not any(rows[r] for r in mine):
            pairs.append(OFF)
            continue
        limit = sum(float(step.mu[r]) * v[step.normal[r]] for r in mine)
        T, s = v[step.tangential[c]], _affine(step.slip[c], v)
        if (limit - abs(T)) / F >= abs(s) / ell:
            pairs.append(STICK)
        else:
            pairs.append(FORWARD if (T < 0 or (T == 0 and s > 0)) else BACKWARD)
    return rows, pairs


def _eliminate(eqs, n, first_choice=0):
    """Exact Gaussian elimination of sparse rows, columns in order (the band), as pivot
    the sparsest of the rows before ``first_choice`` (the mechanics), else the
    sparsest: a dependent equation left over is one of the index set's. (pivots
    {column: row}, rows, rhs, the rows left over)."""
    rows = [dict(c) for c, _ in eqs]
    rhs = [Fraction(r) for _, r in eqs]
    where: dict = {}
    for i, r in enumerate(rows):
        for c in r:
            where.setdefault(c, set()).add(i)
    pivots, used = {}, set()
    for c in range(n):
        cands = [i for i in where.get(c, ()) if i not in used]
        if not cands:
            continue
        p = min(cands, key=lambda i: (i >= first_choice, len(rows[i])))
        used.add(p)
        pivots[c] = p
        prow, pv = rows[p], rows[p][c]
        for i in cands:
            if i == p:
                continue
            r = rows[i]
            m = r[c] / pv
            for cc, val in prow.items():
                new = r.get(cc, 0) - m * val
                if new == 0:
                    if cc in r:
                        del r[cc]
                        where[cc].discard(i)
                else:
                    if cc not in r:
                        where.setdefault(cc, set()).add(i)
                    r[cc] = new
            rhs[i] -= m * rhs[p]
    left = [i for i in range(len(rows)) if i not in used]
    return pivots, rows, rhs, left


def _back(pivots, rows, rhs, n, free_value):
    x: list = [None] * n
    for c in range(n):
        if c not in pivots:
            x[c] = free_value(c)
    for c in sorted(pivots, reverse=True):
        p = pivots[c]
        s = rhs[p] - sum(v * x[cc] for cc, v in rows[p].items() if cc != c)
        x[c] = s / rows[p][c]
    return x


@dataclass
class Exact:
    """The exact solution of a step on one index set and what it satisfies."""

    rows: list
    pairs: list
    x: list  # the unknowns (Fractions)
    failed: list  # the sign conditions it breaks: ("row"/"pair", index)
    inconsistency: float  # the dropped equations' largest residual, relative to their terms
    ray: bool  # a null direction that moves the chain
    free: int  # null directions (free unknowns)

    @property
    def solution(self) -> bool:
        return not self.failed


def solve(step: PrimalStep, rows: list, pairs: list, v: np.ndarray | None = None,
          fit_t: float = 1.0) -> Exact:
    """The step on the index set (``rows``: contact per wall row; ``pairs``: STICK,
    FORWARD, BACKWARD or OFF per pair), exactly; free unknowns (null directions) at
    the answer's values ``v`` (0 without), fitted to its N, T (T weighted by ``fit_t``)
    and move."""
    eqs = list(step.mechanics)
    for r, contact in enumerate(rows):
        if contact:
            const, d = step.gap[r]
            eqs.append((d, -const))
        else:
            eqs.append(({step.normal[r]: Fraction(1)}, Fraction(0)))
    for c, state in enumerate(pairs):
        Tc = step.tangential[c]
        if state is OFF:
            eqs.append(({Tc: Fraction(1)}, Fraction(0)))
        elif state == STICK:
            const, d = step.slip[c]
            eqs.append((d, -const))
        else:
            d = {Tc: Fraction(1)}
            for r in range(len(rows)):
                if step.pair[r] == c:
                    d[step.normal[r]] = d.get(step.normal[r], 0) + state * step.mu[r]
            eqs.append((d, Fraction(0)))
    pivots, erows, rhs, left = _eliminate(eqs, step.n, len(step.mechanics))
    free = [c for c in range(step.n) if c not in pivots]
    guess = [_q(v[c]) if v is not None else Fraction(0) for c in free]
    x = _back(pivots, erows, rhs, step.n, dict(zip(free, guess)).__getitem__)
    ray = False
    if free:  # the null directions, exactly: one per free unknown
        zero = [Fraction(0)] * len(rhs)
        basis = [_back(pivots, erows, zero, step.n,
                       lambda c, f=f: Fraction(int(c == f))) for f in free]
        ray = any(b[k] != 0 for b in basis for k in step.moves)
        if v is not None:  # the exact solution nearest the answer (least squares in
            # floats over the null directions: every choice is an exact solution)
            keys = step.normal + step.tangential
            scale = max(float(np.max(np.abs(v[keys]), initial=0.0)), 1e-300)
            keys = keys + list(step.moves)
            w = np.array([1 / scale] * len(step.normal)
                         + [fit_t / scale] * len(step.tangential)
                         + [1 / step.link] * len(step.moves))
            B = np.array([[float(b[k]) for b in basis] for k in keys]) * w[:, None]
            r = (v[keys] - np.array([float(x[k]) for k in keys])) * w
            theta = np.linalg.lstsq(B, r, rcond=None)[0]
            shift = dict(zip(free, (g + _q(t) for g, t in zip(guess, theta))))
            x = _back(pivots, erows, rhs, step.n, shift.__getitem__)

    def off(i):  # a dropped equation's residual at x, relative to its terms' size
        d, r = eqs[i]
        terms = [c * x[k] for k, c in d.items()]
        size = sum(abs(t) for t in terms) + abs(r)
        return abs(sum(terms) - r) / size if size else Fraction(0)

    bad = max((off(i) for i in left), default=Fraction(0))
    m, mr = len(step.mechanics), len(rows)
    floor = Fraction(POSITION_ROUNDOFF) * _q(step.length)

    def roundoff(i):  # a gap (contact row) or slip (sticking pair) equation, in mm, met
        d, r = eqs[i]  # to the round-off of its positions; never a force equation
        kin = (m <= i < m + mr and rows[i - m]) or (i >= m + mr and pairs[i - m - mr] == STICK)
        return kin and abs(sum(c * x[k] for k, c in d.items()) - r) <= floor

    failed = []
    for i in left:  # a dependent equation the answer's own round-off cannot explain
        if off(i) > CONSISTENT_RTOL and not roundoff(i):
            failed.append(("mechanics", i) if i < m else ("gap", i - m) if i < m + mr
                          else ("slip", i - m - mr))

    def val(expr):
        const, d = expr
        return const + sum(cf * x[k] for k, cf in d.items())

    for r, contact in enumerate(rows):
        if (x[step.normal[r]] < 0) if contact else (val(step.gap[r]) < 0):
            failed.append(("row", r))
    for c, state in enumerate(pairs):
        if state is OFF:
            continue
        if state == STICK:
            limit = sum((step.mu[r] * x[step.normal[r]] for r in range(len(rows))
                         if step.pair[r] == c), Fraction(0))
            if abs(x[step.tangential[c]]) > limit:
                failed.append(("pair", c))
        elif state * val(step.slip[c]) < 0:
            failed.append(("pair", c))
    return Exact(list(rows), list(pairs), x, failed, float(bad), ray, len(free))


def distance(step: PrimalStep, ex: Exact, v: np.ndarray, scale: float | None = None
             ) -> tuple[float, float, float]:
    """How far an answer v is from an exact solution: the largest difference in N and
    in T (relative to ``scale``, by default the larger of the two's largest force) and
    in the move (in link lengths)."""
    forces = step.normal + step.tangential
    if scale is None:
        scale = max(float(np.max(np.abs(v[forces]), initial=0.0)),
                    max((abs(float(ex.x[k])) for k in forces), default=0.0))
    scale = max(scale, 1e-300)

    def d(keys, by):
        return max((abs(float(ex.x[k]) - v[k]) for k in keys), default=0.0) / by

    return d(step.normal, scale), d(step.tangential, scale), d(step.moves, step.link)


def _flip(rows, pairs, ex, step, tried):
    """The index set with the nodes that break a sign condition in ``ex`` flipped: a row
    to the other side, a pair that sticks outside its cone to sliding against its
    exact T, a sliding pair whose slip has the wrong sign to sliding the other way (or,
    when that was tried, to sticking); ``tried``: the slides flipped from, by pair."""
    rows, pairs = list(rows), list(pairs)
    for kind, i in ex.failed:
        if kind == "slip":  # a sticking pair its neighbours make slip: it slides
            const, d = step.slip[i]
            pairs[i] = FORWARD if const + sum(c * ex.x[k] for k, c in d.items()) > 0 \
                else BACKWARD
        elif kind == "gap":  # a row in contact its neighbours lift off: it separates
            rows[i] = False
        elif kind == "mechanics":
            continue
        elif kind == "row":
            rows[i] = not rows[i]
        elif pairs[i] == STICK:
            pairs[i] = FORWARD if ex.x[step.tangential[i]] < 0 else BACKWARD
        else:  # sliding with the slip against T: the other way, then sticking
            pairs[i] = STICK if tried.get(i) == -pairs[i] else -pairs[i]
            tried[i] = -pairs[i] if pairs[i] != STICK else tried.get(i)
    for c in range(len(pairs)):  # a pair whose rows all separate is off, and back
        mine = [r for r in range(len(rows)) if step.pair[r] == c]
        if not any(rows[r] for r in mine):
            pairs[c] = OFF
        elif pairs[c] is OFF:
            pairs[c] = STICK
    return rows, pairs


def edge_nodes(step: PrimalStep, v: np.ndarray, rows: list, pairs: list,
               failed: list) -> tuple[list, list]:
    """The wall rows and friction pairs of the answer v (on its set ``rows``, ``pairs``)
    at the edge of two states: both sides of their LCP pair within :data:`EDGE_RTOL` of 0
    (a row: N/F and g/ℓ; a pair: (μN − |T|)/F and |s|/ℓ), or broken by the set's exact
    solution (``failed``); those first, then the nearest the edge, :data:`EDGE_NODES`."""
    hit_rows = {i for kind, i in failed if kind in ("row", "gap")}
    hit_pairs = {i for kind, i in failed if kind in ("pair", "slip")}
    cand = []  # (rank, kind, index)
    for r in range(len(rows)):
        edge = max(abs(v[step.normal[r]]) / step.force,
                   abs(_affine(step.gap[r], v)) / step.length)
        if r in hit_rows or edge <= EDGE_RTOL:
            cand.append((-1.0 if r in hit_rows else edge, "row", r))
    for c in range(len(pairs)):
        mine = [r for r in range(len(rows)) if step.pair[r] == c]
        if c not in hit_pairs and not any(rows[r] for r in mine):
            continue
        limit = sum(float(step.mu[r]) * v[step.normal[r]] for r in mine)
        edge = max((limit - abs(v[step.tangential[c]])) / step.force,
                   abs(_affine(step.slip[c], v)) / step.length)
        if c in hit_pairs or edge <= EDGE_RTOL:
            cand.append((-1.0 if c in hit_pairs else edge, "pair", c))
    cand = sorted(cand, key=lambda e: e[0])[:EDGE_NODES]
    return [i for _, k, i in cand if k == "row"], [i for _, k, i in cand if k == "pair"]


def edge_search(step: PrimalStep, v: np.ndarray, rows: list, pairs: list,
                failed: list) -> tuple[Exact | None, int]:
    """(the exact solution nearest the answer v in N and the move, or None; the sets
    solved) over the index sets that differ from (``rows``, ``pairs``) at its edge nodes
    only (:func:`edge_nodes`), every state of each (a row contact or separate, a pair
    stick, slide forward or backward; off where its rows separate), the fewest changes
    first, at most :data:`EDGE_SETS`; it stops at the first within :data:`NEAR_RTOL`."""
    er, ep = edge_nodes(step, v, rows, pairs, failed)
    now = [rows[r] for r in er] + [STICK if pairs[c] is OFF else pairs[c] for c in ep]
    picks = sorted(itertools.product(*([(True, False)] * len(er)
                                       + [(STICK, FORWARD, BACKWARD)] * len(ep))),
                   key=lambda pick: sum(a != b for a, b in zip(pick, now)))
    best, best_d, seen = None, np.inf, set()
    for pick in picks[1:] if (er or ep) else []:  # (the first is the set as read)
        r2, p2 = list(rows), list(pairs)
        for r, val in zip(er, pick):
            r2[r] = val
        for c, val in zip(ep, pick[len(er):]):
            p2[c] = val
        for c in range(len(p2)):  # a pair whose rows all separate is off, and back
            on = any(r2[r] for r in range(len(r2)) if step.pair[r] == c)
            p2[c] = OFF if not on else STICK if p2[c] is OFF else p2[c]
        if (tuple(r2), tuple(p2)) in seen or len(seen) >= EDGE_SETS:
            continue
        seen.add((tuple(r2), tuple(p2)))
        ex = solve(step, r2, p2, v)
        d = distance(step, ex, v) if ex.solution else (np.inf,) * 3
        if max(d[0], d[2]) < best_d:
            best, best_d = ex, max(d[0], d[2])
        if best_d <= NEAR_RTOL:
            break
    return best, len(seen)


def nearest_exact(step: PrimalStep, v: np.ndarray, search: bool = True
                  ) -> tuple[Exact, float, int]:
    """(the exact solution on the index set read from the answer v, its distance, the
    rounds of flips it took): where the read set's exact solution breaks a sign
    condition or a dependent equation, those nodes are flipped (:func:`_flip`), up to
    :data:`FLIP_ROUNDS` times; where that confirms nothing and ``search``, every state of
    the answer's edge nodes is tried (:func:`edge_search`) and the nearest solution kept.
    When none is a solution, the first (the set as read)."""
    rows, pairs = read = read_states(step, v)
    ex = first = solve(step, rows, pairs, v)
    rounds, tried = 0, {}
    while ex.failed and rounds < FLIP_ROUNDS:
        rounds += 1
        new = _flip(rows, pairs, ex, step, tried)
        if new == (rows, pairs):
            break
        rows, pairs = new
        ex = solve(step, rows, pairs, v)
    if ex.failed:  # none found: the answer's own index set, as read
        ex = first
    dist = distance(step, ex, v)
    found = edge_search(step, v, *read, first.failed)[0] if search and not \
        confirmed(ex, dist) else None
    d = distance(step, found, v) if found is not None else dist
    if found is not None and (not ex.solution or max(d[0], d[2]) < max(dist[0], dist[2])):
        ex, dist = found, d
    return ex, dist, rounds


#: the classes of a disagreement
MULTIPLE = "(i) two exact answers"
INACCURATE = "(ii) not near an exact answer"
RAY = "(iii) a ray"
SAME = "(iv) one exact answer, both near it"


def confirmed(ex: Exact, dist: tuple) -> bool:
    """Whether an answer is an exact answer's rounding: the exact solution on its index
    set satisfies every condition and is within :data:`NEAR_RTOL` of it in N and in the
    move (T per node is not judged: along a stretch of chain that is straight to a few
    1e-5 rad a horizontal force moves between nodes at almost no cost, and its split is
    as ill-conditioned as that)."""
    return ex.solution and max(dist[0], dist[2]) <= NEAR_RTOL


def classify(step: PrimalStep, va: np.ndarray, vb: np.ndarray, a=None) -> tuple[str, dict]:
    """The class of a disagreement between two answers va, vb of one step (unknowns,
    floats; ``a``: va's :func:`nearest_exact` when known): RAY when either's index set
    has a null direction that moves the chain; INACCURATE when either is not
    :func:`confirmed`; MULTIPLE when both are and their exact solutions differ by more
    than :data:`NEAR_RTOL` in N or the move; SAME when both are the same exact answer in
    N and the move: each answer is within NEAR_RTOL of it, and they differ by the sum of
    their two roundings (up to 2·NEAR_RTOL in N), or in T per run where a near-null
    direction moves T between runs at almost no cost (state 41.2 of
    friction_agreement.py, docs/friction.md: "State 41.2 taken apart")."""
    ea, da, _ = a if a is not None else nearest_exact(step, va)
    eb, db, _ = nearest_exact(step, vb)
    info = dict(a=(ea, da), b=(eb, db))
    if ea.ray or eb.ray:
        return RAY, info
    if not confirmed(ea, da) or not confirmed(eb, db):
        info["which"] = "a" if not confirmed(ea, da) else "b"
        # an exact answer on its index set, but farther than NEAR_RTOL (ill-conditioned),
        # or none found on the sets read from it
        info["exact_there"] = (ea if info["which"] == "a" else eb).solution
        return INACCURATE, info
    xa = np.array([float(v) for v in ea.x])
    forces = step.normal + step.tangential
    gap = distance(step, eb, xa, float(max(np.max(np.abs(va[forces]), initial=0.0),
                                            np.max(np.abs(vb[forces]), initial=0.0))))
    info["apart"] = gap
    return (MULTIPLE if max(gap[0], gap[2]) > NEAR_RTOL else SAME), info
