"""The frictional step's primal polish (issue 39, target 2; docs/friction.md, "The polish").

An answer of the step's LCP (any back-end) names an index set: per wall row contact or
separate, per friction pair stick, slide forward (s >= 0, T = −μN), slide backward or off
(its rows separate). The polish solves the step once more on that set, in the step's
PRIMAL form, not on the condensed LCP: the Delassus block M_SS = Gᵀ K⁻¹ G of the set is
singular in exact arithmetic where nodes stick in a run (T per node is statically
indeterminate there) and, formed in doubles, its rounding decides N
(results/friction/polish_probe.md). The primal equations are those of
benchmarks/exact_friction.py's oracle, node by node, in doubles:

    H δy = f + G_n N + G_t T          heights' equilibrium, Dᵀ F^x as the links'
                                      horizontal forces L_k (tan α_k L_k at nodes k, k+1)
    δx_i − δx_{i−1} = −tan α_{i−1} (δy_i − δy_{i−1}),  the datum (x_0 = 0, τ; x_N = 0)
    L_k = Σ_{i>k} F^x_i  (left datum)  or  −Σ_{i<=k} F^x_i  (right datum)
    k_τ τ = f_τ + L_0 + F^x_0          (no end holds x)
    contact: n·(δx, δy) + N/k = −g;  separate: N = 0
    stick: t·(δx, δy) = −s;  slide: T = ∓μN;  off: T = 0

with the unknowns ordered node by node (δy_i, δx_i, L_i, its N, its T), so the system is
banded (a few nodes wide) and is solved by Gaussian elimination with partial pivoting
(:func:`lcpbench.linalg.band_lu_kernel.band_factor`), rows and columns equilibrated, in
O(N). A free right end's rotation (K = H + k_r r rᵀ: every height coupled) borders the
band with two unknowns (:mod:`lcpbench.model.friction_primal`), solved by block
elimination on the band's factor (:func:`bordered_factor`: two more banded solves and a
2 × 2 Schur complement). Links level to round-off (|tan α| <= POLISH_LEVEL) are level;
then two sticking nodes joined by level links have dependent slip equations (the link
fixes the second slip), and the second's is replaced by its T held at the answer's split
(T_c − T_p = T⁰_c − T⁰_p, p the run's previous sticking pair; T_c = T⁰_c in a run held
by a pinned end): the null direction of T per node is fixed where the answer put it, N
is not touched by it. The replaced slip equation is checked as a sign (:func:`signs`):
where the two slips from the last state differ, both cannot stick.

Every function is ``@njit(cache=True)``; with NUMBA_DISABLE_JIT=1 they run as plain
Python. :func:`lcpbench.model.friction_lemke.polish_step` calls :func:`polish` and keeps
its answer only where lcpbench's own residual of the LCP still passes.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.band_lu_kernel import band_factor, band_resolve
from ..thresholds import POLISH_LEVEL, POLISH_MOST_FAILING, POLISH_SIGN_RTOL
from .friction_primal import (  # noqa: F401  (by_node, layout: the kernels' names too)
    BACKWARD,
    FORWARD,
    HELD_ALONE,
    KEEP,
    OFF,
    STICK,
    border_size,
    border_values,
    by_node,
    layout,
    primal_system,
)

#: :func:`polish`'s verdicts
KEPT, NO_PRIMAL, SINGULAR, SIGNS, NOT_LOWER = 0, 1, 2, 3, 4


@njit(cache=True)
def banded_factor(ei, ej, ev, n):
    """A (square, in sparse rows) factored for :func:`banded_resolve`: rows then columns
    scaled by their largest entry, banded elimination with partial pivoting
    (:func:`lcpbench.linalg.band_lu_kernel.band_factor`); (factor, kl, row scales, column
    scales, pivots, last columns, ok)."""
    rmax = np.zeros(n)
    for k in range(ei.size):
        rmax[ei[k]] = max(rmax[ei[k]], abs(ev[k]))
    cmax = np.zeros(n)
    kl, ku = 0, 0
    for k in range(ei.size):
        cmax[ej[k]] = max(cmax[ej[k]], abs(ev[k]) / rmax[ei[k]])
        kl = max(kl, ei[k] - ej[k])
        ku = max(ku, ej[k] - ei[k])
    piv = np.empty(n, np.int64)
    last = np.empty(n, np.int64)
    ab = np.zeros((n, 2 * kl + ku + 1))
    for i in range(n):
        if rmax[i] == 0.0 or cmax[i] == 0.0:
            return ab, kl, rmax, cmax, piv, last, False
    for k in range(ei.size):
        i, j = ei[k], ej[k]
        ab[i, j - i + kl] += ev[k] / rmax[i] / cmax[j]
    ok = band_factor(ab, kl, piv, last)
    return ab, kl, rmax, cmax, piv, last, ok


@njit(cache=True)
def banded_resolve(fac, rhs):
    """x with A x = rhs from :func:`banded_factor`'s ``fac``; (x, ok)."""
    ab, kl, rmax, cmax, piv, last, _ = fac
    n = rhs.size
    b = np.empty((n, 1))
    for i in range(n):
        b[i, 0] = rhs[i] / rmax[i]
    ok = band_resolve(ab, kl, piv, last, b)
    x = np.empty(n)
    for j in range(n):
        x[j] = b[j, 0] / cmax[j]
    return x, ok


@njit(cache=True)
def bordered_factor(ei, ej, ev, n, nb):
    """A (square, in sparse rows) whose last ``nb`` rows and columns border a banded core
    A₀ (:func:`lcpbench.model.friction_primal.primal_system` at a free end), factored for
    :func:`bordered_resolve` by block elimination: A₀ by :func:`banded_factor`, Z = A₀⁻¹ B
    (``nb`` banded solves, B the border's columns in the core's rows) and the Schur
    complement S = D − C Z (C the border's rows in the core's columns, D their corner);
    (A₀'s factor, Z, C, S, ok). ``nb`` 0: A₀ is A (factored as it is, no copy)."""
    nc = n - nb
    if nb == 0:
        fac = banded_factor(ei, ej, ev, n)
        return fac, np.zeros((n, 0)), np.zeros((0, n)), np.zeros((0, 0)), fac[6]
    core = np.ones(ei.size, np.bool_)
    B = np.zeros((nc, nb))
    C = np.zeros((nb, nc))
    S = np.zeros((nb, nb))
    for k in range(ei.size):
        i, j = ei[k], ej[k]
        if i >= nc or j >= nc:
            core[k] = False
            if i < nc:
                B[i, j - nc] += ev[k]
            elif j < nc:
                C[i - nc, j] += ev[k]
            else:
                S[i - nc, j - nc] += ev[k]
    fac = banded_factor(ei[core], ej[core], ev[core], nc)
    Z = np.zeros((nc, nb))
    ok = fac[6]
    for c in range(nb if ok else 0):
        Z[:, c], good = banded_resolve(fac, B[:, c].copy())
        ok = ok and good
    if ok and nb:
        S -= C @ Z
        ok = np.all(np.isfinite(S)) and abs(np.linalg.det(S)) > 0.0
    return fac, Z, C, S, ok


@njit(cache=True)
def bordered_resolve(bfac, rhs):
    """x with A x = rhs from :func:`bordered_factor`'s ``bfac``: x₀ = A₀⁻¹ b, the border
    y = S⁻¹ (b_border − C x₀), the core x₀ − Z y; (x, ok)."""
    fac, Z, C, S, _ = bfac
    nb = S.shape[0]
    nc = rhs.size - nb
    x0, ok = banded_resolve(fac, rhs[:nc].copy())
    x = np.empty(rhs.size)
    if nb:
        y = np.linalg.solve(S, rhs[nc:] - C @ x0)
        x0 = x0 - Z @ y
        x[nc:] = y
    x[:nc] = x0
    return x, ok


@njit(cache=True)
def primal_residual(ei, ej, ev, rhs, v, scale):
    """The largest residual of the equations at v, each relative to its terms' size at
    the unknowns' scales (``scale``: a force or a length per unknown) plus |rhs|."""
    m = rhs.size
    acc = np.zeros(m)
    size = np.abs(rhs)
    for k in range(ei.size):
        acc[ei[k]] += ev[k] * v[ej[k]]
        size[ei[k]] += abs(ev[k]) * scale[ej[k]]
    worst = 0.0
    for i in range(m):
        if size[i] > 0.0:
            worst = max(worst, abs(acc[i] - rhs[i]) / size[i])
    return worst


@njit(cache=True)
def answer_values(n, lay, t, right_datum, dy, tau, N, T, first, normal_node, normal_xy,
                  friction_node, tangent_xy):
    """Every unknown of the primal system (:func:`layout`) from an answer's δy, τ, N, T:
    δx by its recurrence from the datum, L by summing F^x."""
    tv, Y, X, L, Nv, Tv = lay
    links = t.size
    v = np.zeros(n)
    yd = np.zeros(links + 1)
    for i in range(links + 1):
        if Y[i] >= 0:
            yd[i] = dy[i - first]
            v[Y[i]] = yd[i]
    if tv >= 0:
        v[tv] = tau
    x = np.zeros(links + 1)
    x[0] = tau
    for i in range(1, links + 1):
        x[i] = x[i - 1] - t[i - 1] * (yd[i] - yd[i - 1])
    if right_datum:
        x -= x[links]
    fx = np.zeros(links + 1)
    for r in range(N.size):
        fx[first + normal_node[r]] += normal_xy[r, 0] * N[r]
        v[Nv[r]] = N[r]
    for c in range(T.size):
        fx[friction_node[c]] += tangent_xy[c, 0] * T[c]
        v[Tv[c]] = T[c]
    acc = 0.0
    if right_datum:
        for k in range(links):
            acc -= fx[k]
            v[L[k]] = acc
    else:
        for k in range(links - 1, -1, -1):
            acc += fx[k + 1]
            v[L[k]] = acc
    for i in range(links + 1):
        v[X[i]] = x[i]
    return v


@njit(cache=True)
def index_set(z, w, mn, mt, pair, mu):
    """The index set of an LCP answer z, w = M z + q (z = (N, β⁺, β⁻, λ)), each pair's
    larger side: a row is in contact when N >= its gap; a pair is off (T = 0, its slip
    free) when none of its rows with μ > 0 is in contact, sticks when its cone's margin μN − |T| is at least its slip
    size λ, else slides against T (forward where β⁻ > β⁺)."""
    contact = np.empty(mn, np.bool_)
    pressed = np.zeros(mt, np.bool_)
    for r in range(mn):
        contact[r] = z[r] >= w[r]
        if contact[r] and pair[r] >= 0 and mu[r] > 0.0:
            pressed[pair[r]] = True
    state = np.empty(mt, np.int64)
    lam = mn + 2 * mt
    for c in range(mt):
        if not pressed[c]:
            state[c] = OFF
        elif w[lam + c] >= z[lam + c]:
            state[c] = STICK
        else:
            state[c] = FORWARD if z[mn + mt + c] > z[mn + c] else BACKWARD
    return contact, state


@njit(cache=True)
def stick_holds(t, state, friction_node, tangent_xy, has_tau, right_datum):
    """Per pair: KEEP its slip equation, or hold its T (:func:`primal_system`) where a
    sticking pair is joined to an earlier sticking pair, or to a pinned end, by level
    links (t = 0: their x move together, the slip equations are dependent)."""
    links = t.size
    run = np.zeros(links + 1, np.int64)
    for i in range(1, links + 1):
        run[i] = run[i - 1] + (0 if t[i - 1] == 0.0 else 1)
    pinned = -1
    if right_datum:
        pinned = run[links]
    elif not has_tau:
        pinned = run[0]
    last = np.full(links + 1, -1, np.int64)
    hold = np.full(state.size, KEEP, np.int64)
    order = np.argsort(friction_node, kind="mergesort")
    for k in range(order.size):
        c = order[k]
        if state[c] != STICK or tangent_xy[c, 1] != 0.0:
            continue
        g = run[friction_node[c]]
        if g == pinned:
            hold[c] = HELD_ALONE
        elif last[g] >= 0:
            hold[c] = last[g]
        last[g] = c
    return hold


@njit(cache=True)
def signs(x, lay, first, gap, slip, normal_node, normal_xy, friction_node, tangent_xy, mu,
          pair, contact, state, hold, ftol, ltol):
    """The sign conditions of the index set at the primal solution x: (how many fail, the
    set with those nodes flipped, the slips s). A contact row with N < 0 separates, a
    separate row with a gap < 0 comes into contact, a sticking pair outside its cone
    slides against its T, a sticking pair whose T is held (``hold``, :func:`stick_holds`:
    its slip equation, dependent on a level link, not solved) with a slip slides that
    way, a sliding pair whose slip has the wrong sign sticks (and a pair
    none of whose rows with μ > 0 is in contact is off; one that comes into contact
    sticks). To
    ``ftol`` (forces) and ``ltol`` (lengths)."""
    tv, Y, X, L, Nv, Tv = lay
    mn, mt = contact.size, state.size
    new_contact, new_state = contact.copy(), state.copy()
    s = np.zeros(mt)
    for c in range(mt):
        i = friction_node[c]
        s[c] = slip[c] + tangent_xy[c, 0] * x[X[i]]
        if Y[i] >= 0:
            s[c] += tangent_xy[c, 1] * x[Y[i]]
    fails = 0
    for r in range(mn):
        i = first + normal_node[r]
        if contact[r]:
            if x[Nv[r]] < -ftol:
                new_contact[r] = False
                fails += 1
        elif gap[r] + normal_xy[r, 0] * x[X[i]] + normal_xy[r, 1] * x[Y[i]] < -ltol:
            new_contact[r] = True
            fails += 1
    pressed = np.zeros(mt, np.bool_)
    for r in range(mn):
        if new_contact[r] and pair[r] >= 0 and mu[r] > 0.0:
            pressed[pair[r]] = True
    for c in range(mt):
        if state[c] == STICK:
            limit = 0.0
            for r in range(mn):
                if pair[r] == c:
                    limit += mu[r] * x[Nv[r]]
            if abs(x[Tv[c]]) > limit + ftol:
                new_state[c] = FORWARD if x[Tv[c]] < 0.0 else BACKWARD
                fails += 1
            elif hold[c] != KEEP and abs(s[c]) > ltol:
                new_state[c] = FORWARD if s[c] > 0.0 else BACKWARD
                fails += 1
        elif state[c] != OFF and state[c] * s[c] < -ltol:
            new_state[c] = STICK
            fails += 1
        if not pressed[c]:
            new_state[c] = OFF
        elif new_state[c] == OFF:
            new_state[c] = STICK
    return fails, new_contact, new_state, s


@njit(cache=True)
def polish(bands, f, tan, k_tau, first, right_datum, gap, slip, compliance, normal_node,
           normal_xy, friction_node, tangent_xy, mu, pair, rot, rot_k, z, w, dy, tau, N, T,
           force, length, link, stick_compliance, sweeps, flips):
    """The answer z (w = M z + q; its δy, τ, N, T in mm and N) polished on its index set
    (the module's note): (verdict, z polished (the LCP's units: forces by ``force``,
    lengths by ``length``), the primal residual before, after); :func:`polish_on` the
    set :func:`index_set` reads from z, w."""
    contact, state = index_set(z, w, N.size, T.size, pair, mu)
    code, z_new, r0, r1, _, _, _, _, _ = polish_on(
        bands, f, tan, k_tau, first, right_datum, gap, slip, compliance, normal_node,
        normal_xy, friction_node, tangent_xy, mu, pair, rot, rot_k, z, dy, tau, N, T, force,
        length, link, stick_compliance, sweeps, flips, contact, state)
    return code, z_new, r0, r1


@njit(cache=True)
def polish_on(bands, f, tan, k_tau, first, right_datum, gap, slip, compliance, normal_node,
              normal_xy, friction_node, tangent_xy, mu, pair, rot, rot_k, z, dy, tau, N, T,
              force, length, link, stick_compliance, sweeps, flips, contact, state):
    """The answer (z; its δy, τ, N, T) polished on the index set (``contact`` per wall
    row, ``state`` per pair): (verdict, z polished, the primal residual before, after,
    and where a sign fails the set with the failing nodes flipped (:func:`signs`), else
    the set solved; and where a sign fails the sets solved, in order, as two arrays;
    and at each set solved how many signs failed, rows and pairs).

    The set's primal system is solved with the sticking nodes' compliance
    ``stick_compliance`` (link lengths per largest force) as ``sweeps`` steps of
    refinement from the answer against the equations without it. Where a sign of the set
    fails at the solution, those nodes are flipped (:func:`signs`) and the set solved
    again, at most ``flips`` times; a flip onto a set solved before ends it (the flips
    are a function of the set: they would go round), and so does a set at which the
    signs of more than POLISH_MOST_FAILING rows and pairs fail (a polish repairs
    round-off at a few nodes). KEPT where every sign of the (last) set holds (to
    POLISH_SIGN_RTOL of the largest force and of the link length ``link``) and the
    residual of its primal equations (tan α as is, every stick equation) is below the
    answer's. A free right end (``rot``, ``rot_k``: its rotation about the pin) is
    solved bordered (:func:`bordered_factor`)."""
    mn, mt = N.size, T.size
    nb = border_size(rot)
    z_new = z.copy()
    nan = np.nan
    has_tau = f.size > bands.shape[1]
    tl = tan.copy()
    for k in range(tl.size):
        if abs(tl[k]) <= POLISH_LEVEL:
            tl[k] = 0.0
    big0 = 0.0
    for r in range(mn):
        big0 = max(big0, abs(N[r]))
    for c in range(mt):
        big0 = max(big0, abs(T[c]))
    if big0 == 0.0:
        big0 = force
    x0 = np.empty(0)
    failing = np.zeros(flips + 1, np.int64)  # how many signs fail at each set solved
    seen_c = np.empty((flips + 1, mn), np.bool_)  # the sets solved, in order
    seen_s = np.empty((flips + 1, mt), np.int64)
    solved = 0  # the sets solved
    for attempt in range(flips + 1):
        solved = attempt + 1
        seen_c[attempt], seen_s[attempt] = contact, state
        hold = stick_holds(tl, state, friction_node, tangent_xy, has_tau, right_datum)
        # the system solved (si, …: sticking nodes compliant) and the equations (ei, …:
        # its entries but the compliances, the right-hand side without them)
        si, sj, sv, _, n, lay, plain, rhs = primal_system(
            bands, f, tl, k_tau, first, right_datum, gap, slip, compliance, normal_node,
            normal_xy, friction_node, tangent_xy, mu, pair, rot, rot_k, contact, state, hold,
            T, stick_compliance * link / big0)
        ei, ej, ev = si[plain], sj[plain], sv[plain]
        if attempt == 0:  # the layout is the set's nodes', the same for every set
            x0 = border_values(answer_values(n, lay, tl, right_datum, dy, tau, N, T, first,
                                             normal_node, normal_xy, friction_node,
                                             tangent_xy), rot, dy)
        x = x0.copy()
        fac = bordered_factor(si, sj, sv, n, nb)
        if rhs.size != n or not fac[4]:
            return (SINGULAR, z_new, nan, nan, contact, state, seen_c[:0], seen_s[:0],
                    failing[:attempt])
        for _ in range(sweeps):  # x += A_ε⁻¹ (b − A x)
            res = rhs.copy()
            for k in range(ei.size):
                res[ei[k]] -= ev[k] * x[ej[k]]
            d, ok = bordered_resolve(fac, res)
            if not ok:
                return (SINGULAR, z_new, nan, nan, contact, state, seen_c[:0], seen_s[:0],
                        failing[:attempt])
            x += d
        big = big0
        for r in range(mn):
            big = max(big, abs(x[lay[4][r]]))
        for c in range(mt):
            big = max(big, abs(x[lay[5][c]]))
        fails, new_contact, new_state, s = signs(
            x, lay, first, gap, slip, normal_node, normal_xy, friction_node, tangent_xy, mu,
            pair, contact, state, hold, POLISH_SIGN_RTOL * big, POLISH_SIGN_RTOL * link)
        failing[attempt] = fails
        if fails == 0:
            break
        # the budget, a set with more failing nodes than a polish repairs (the flips
        # have left the answer), or a set solved before (a cycle: exact)
        if attempt == flips or fails > POLISH_MOST_FAILING or tried(
                seen_c[:attempt + 1], seen_s[:attempt + 1], new_contact, new_state):
            return (SIGNS, z_new, nan, nan, new_contact, new_state, seen_c[:attempt + 1],
                    seen_s[:attempt + 1], failing[:attempt + 1])
        contact, state = new_contact, new_state
    tv, Y, X, L, Nv, Tv = lay
    # both answers in the set's own equations: tan α as is, every stick equation
    keep = np.full(mt, KEEP, np.int64)
    ei, ej, ev, rhs, n, lay, _, _ = primal_system(bands, f, tan, k_tau, first, right_datum,
                                                  gap, slip, compliance, normal_node,
                                                  normal_xy, friction_node, tangent_xy, mu,
                                                  pair, rot, rot_k, contact, state, keep, T,
                                                  0.0)
    scale = np.full(n, link)
    for r in range(mn):
        scale[Nv[r]] = max(big, 1e-300)
    for c in range(mt):
        scale[Tv[c]] = max(big, 1e-300)
    for k in range(L.size if tan.size else 0):
        scale[L[k]] = max(big, 1e-300)
    if nb:  # ρ = rᵀ δy at moves of a link length (ς: the tip's height, a length)
        scale[n - 2] = np.sum(np.abs(rot)) * link
    v0 = border_values(answer_values(n, lay, tan, right_datum, dy, tau, N, T, first,
                                     normal_node, normal_xy, friction_node, tangent_xy),
                       rot, dy)
    r0 = primal_residual(ei, ej, ev, rhs, v0, scale)
    r1 = primal_residual(ei, ej, ev, rhs, x, scale)
    if not r1 < r0:
        return (NOT_LOWER, z_new, r0, r1, contact, state, seen_c[:0], seen_s[:0],
                failing[:solved])
    for r in range(mn):
        z_new[r] = x[Nv[r]] / force
    for c in range(mt):
        tc = x[Tv[c]]
        z_new[mn + c] = max(tc, 0.0) / force
        z_new[mn + mt + c] = max(-tc, 0.0) / force
        z_new[mn + 2 * mt + c] = 0.0 if state[c] == STICK else abs(s[c]) / length
    return KEPT, z_new, r0, r1, contact, state, seen_c[:0], seen_s[:0], failing[:solved]


@njit(cache=True)
def tried(seen_c, seen_s, contact, state):
    """Whether the set (``contact``, ``state``) is a row of (``seen_c``, ``seen_s``)."""
    for a in range(seen_c.shape[0]):
        same = True
        for r in range(contact.size):
            if seen_c[a, r] != contact[r]:
                same = False
                break
        for c in range(state.size if same else 0):
            if seen_s[a, c] != state[c]:
                same = False
                break
        if same:
            return True
    return False


@njit(cache=True)
def polish_sets(bands, f, tan, k_tau, first, right_datum, gap, slip, compliance,
                normal_node, normal_xy, friction_node, tangent_xy, mu, pair, rot, rot_k, z,
                dy, tau, N, T, force, length, link, stick_compliance, sweeps, contact, state,
                nodes, picks, most, seen_c, seen_s):
    """:func:`polish_on` (no flips) on the index sets that differ from (``contact``,
    ``state``) at ``nodes`` (an index below N.size a wall row, else the pair
    ``index − N.size``) only, each row of ``picks`` their states (a row 1 contact, 0
    separate; a pair STICK, FORWARD or BACKWARD), in order, at most ``most`` of them;
    a pair none of whose rows with μ > 0 is in contact is off, one that comes into
    contact sticks: (verdict, z, r0, r1) of the first KEPT, else SIGNS. A set solved
    before, here or in (``seen_c``, ``seen_s``: sets whose signs failed), is passed over:
    its verdict is known."""
    mn, mt = N.size, T.size
    done_c = np.empty((seen_c.shape[0] + picks.shape[0], mn), np.bool_)
    done_s = np.empty((done_c.shape[0], mt), np.int64)
    done_c[:seen_c.shape[0]], done_s[:seen_c.shape[0]] = seen_c, seen_s
    done = seen_c.shape[0]
    for p in range(picks.shape[0]):
        if p >= most:
            break
        c2, s2 = contact.copy(), state.copy()
        for j in range(nodes.size):
            if nodes[j] < mn:
                c2[nodes[j]] = picks[p, j] != 0
            else:
                s2[nodes[j] - mn] = picks[p, j]
        pressed = np.zeros(mt, np.bool_)
        for r in range(mn):
            if c2[r] and pair[r] >= 0 and mu[r] > 0.0:
                pressed[pair[r]] = True
        for c in range(mt):
            if not pressed[c]:
                s2[c] = OFF
            elif s2[c] == OFF:
                s2[c] = STICK
        if tried(done_c[:done], done_s[:done], c2, s2):
            continue
        done_c[done], done_s[done] = c2, s2
        done += 1
        out = polish_on(bands, f, tan, k_tau, first, right_datum, gap, slip, compliance,
                        normal_node, normal_xy, friction_node, tangent_xy, mu, pair, rot,
                        rot_k, z, dy, tau, N, T, force, length, link, stick_compliance,
                        sweeps, 0, c2, s2)
        if out[0] == KEPT:
            return out[0], out[1], out[2], out[3]
    return SIGNS, z.copy(), np.nan, np.nan
