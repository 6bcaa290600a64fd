"""An active set on the stick / slide / separate states of 2-D frictional contact.

The problem is Siconos' fc2d form (:mod:`.siconos_fc2d`): per contact c the local
velocity u_c = (u_n, u_t) (gap, slip) and reaction r_c = (r_n, r_t) (N, T), with
u = W r + q, W symmetric positive semidefinite (the Delassus matrix), and
Signorini–Coulomb: 0 <= r_n ⟂ u_n >= 0, |r_t| <= μ_c r_n, r_t = −μ_c r_n sign(u_t)
where u_t ≠ 0.

Each contact is in one of four states, and a state fixes two linear conditions:

| state | conditions |
|---|---|
| separate (0) | r_n = 0, r_t = 0 |
| stick (1) | u_n = 0, u_t = 0 |
| slide forward (2), u_t > 0 | u_n = 0, r_t = −μ r_n |
| slide back (3), u_t < 0 | u_n = 0, r_t = +μ r_n |

Given the states, r follows from one linear solve (least squares of the minimum norm:
in a run of sticking nodes on a flat wall the individual r_t are statically
indeterminate, W is singular there, and any split of their sum is an answer). The
states are then checked: a separate contact must not penetrate (u_n >= 0), a contact
must push (r_n >= 0), a stick must lie in its cone, a slide must move the way its
force opposes. It starts from the frictionless contact set (the same pivoting with
μ = 0), its contacts sticking. Every violated contact changes state at once (block
pivoting, as Júdice–Pires for the LCP); after :data:`BLOCK_TRIES` block changes without
fewer violations, one at a time, the most violated first (at a set of states seen
before, a random one of the violated, seeded, to leave a cycle). Where that fails, it
solves Tresca problems (:func:`tresca_fixed_point`). The method is finite on no class
of these problems that we know of, so it has an iteration limit and reports MAX_ITER
there. SOLVED only when no state is violated and lcpbench's own
Signorini–Coulomb residual (:func:`.siconos_fc2d.coulomb_residual`) is below
:data:`.siconos_fc2d.ACCEPT_TOL`.
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import ProblemError
from .base import Status
from .fc2d_tresca import MAX_FIXED, next_bounds
from .siconos_fc2d import ACCEPT_TOL, FC2DSolution, coulomb_residual, fc2d_arrays

SEPARATE, STICK, FORWARD, BACK = 0, 1, 2, 3
#: block changes without fewer violations before changing one state at a time
BLOCK_TRIES = 3
#: the seed of the random choice among violated contacts at states seen before
RANDOM_SEED = 39
#: a state is violated beyond this share of the problem's scale (max(1, |q|, |r|))
VIOLATION_RTOL = 1e-12


def initial_states(q: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """Where the free motion penetrates (q_n < 0) a contact sticks (slides where μ = 0),
    elsewhere it separates."""
    st = np.where(q[0::2] < 0.0, STICK, SEPARATE)
    return np.where((st == STICK) & (mu <= 0.0), FORWARD, st).astype(np.int64)


def reactions(W: np.ndarray, q: np.ndarray, mu: np.ndarray, states: np.ndarray,
              bound: np.ndarray | None = None) -> np.ndarray:
    """r (interleaved (r_n, r_t)) from the states: one least-squares solve of the
    states' conditions (minimum norm where they do not fix r). With ``bound`` (Tresca:
    a fixed slip bound b per contact) a sliding contact has r_t = ∓b, not ∓μ r_n."""
    nc = mu.size
    contact = np.flatnonzero(states != SEPARATE)
    stick = np.flatnonzero(states == STICK)
    k = contact.size + stick.size
    r = np.zeros(2 * nc)
    if k == 0:
        return r
    E = np.zeros((2 * nc, k))  # r = E x + r0, x = (r_n of the contacts, r_t of the sticks)
    r0 = np.zeros(2 * nc)
    for j, c in enumerate(contact):
        E[2 * c, j] = 1.0
        sign = {FORWARD: -1.0, BACK: 1.0}.get(int(states[c]), 0.0)
        if bound is None:
            E[2 * c + 1, j] = sign * mu[c]
        else:
            r0[2 * c + 1] = sign * bound[c]
    for j, c in enumerate(stick):
        E[2 * c + 1, contact.size + j] = 1.0
    rows = np.concatenate([2 * contact, 2 * stick + 1])
    A = W[rows] @ E
    x = np.linalg.lstsq(A, -(q + W @ r0)[rows], rcond=None)[0]
    return E @ x + r0


def violations(W: np.ndarray, q: np.ndarray, mu: np.ndarray, states: np.ndarray,
               r: np.ndarray, bound: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """The state each contact should change to (−1: its state holds), and by how much
    its state is violated (a penetration, a pull, a force beyond the cone — μ r_n, or
    ``bound`` — a slip the wrong way; dimensionless)."""
    u = W @ r + q
    rn, rt, un, ut = r[0::2], r[1::2], u[0::2], u[1::2]
    eps = VIOLATION_RTOL * max(1.0, float(np.abs(q).max(initial=0.0)),
                               float(np.abs(r).max(initial=0.0)))
    frictional = mu > 0.0
    slide = np.where(ut > 0.0, FORWARD, BACK)
    to = np.full(mu.size, -1, np.int64)
    size = np.zeros(mu.size)
    sep = states == SEPARATE
    hit = sep & (un < -eps)
    to[hit] = np.where(frictional, STICK, slide)[hit]
    size[hit] = -un[hit]
    pulls = ~sep & (rn < -eps)
    to[pulls] = SEPARATE
    size[pulls] = -rn[pulls]
    free = to < 0
    stick = free & (states == STICK)
    limit = mu * rn if bound is None else bound
    over = stick & (rt > limit + eps)  # pushed forward beyond the cone: it slides back
    under = stick & (rt < -limit - eps)
    to[over], to[under] = BACK, FORWARD
    size[over | under] = (np.abs(rt) - limit)[over | under]
    wrong = free & frictional & (((states == FORWARD) & (ut < -eps))
                                 | ((states == BACK) & (ut > eps)))
    # a slide the wrong way sticks; at a cone of size 0 (r_n = 0) it slides the other way
    # (a stick there could hold no force, and would flip back)
    to[wrong] = np.where(limit[wrong] > eps, STICK,
                         np.where(states[wrong] == FORWARD, BACK, FORWARD))
    size[wrong] = np.abs(ut[wrong])
    return to, size


def pivot(W, q, mu, st: np.ndarray, limit: int, block_tries: int,
          bound: np.ndarray | None = None):
    """Change states until none is violated (or ``limit`` changes): (r, states, changes,
    done). ``bound``: Tresca's fixed slip bounds in place of the cone μ r_n."""
    best, stalled, changes, done = np.inf, 0, 0, False
    r = np.zeros(q.size)
    seen: set = set()
    rng = np.random.default_rng(RANDOM_SEED)
    for changes in range(1, limit + 1):  # noqa: B007 (the count is reported)
        r = reactions(W, q, mu, st, bound)
        if not np.all(np.isfinite(r)):
            break
        to, size = violations(W, q, mu, st, r, bound)
        bad = np.flatnonzero(to >= 0)
        if bad.size == 0:
            done = True
            break
        if bad.size < best:
            best, stalled = bad.size, 0
        else:
            stalled += 1
        if stalled < block_tries:
            st[bad] = to[bad]
        else:  # the most violated first; at states seen before, a random one of them
            key = st.tobytes()
            worst = bad[np.argmax(size[bad])] if key not in seen else rng.choice(bad)
            seen.add(key)
            st[worst] = to[worst]
    return r, st, changes, done


def tresca_fixed_point(W, q, mu, st: np.ndarray, limit: int):
    """Where the pivoting on the cone cycles: from ``st``, Tresca problems (slip bounds
    b = μ r_n of the last answer, fixed), each solved by the same pivoting with the
    bounds in place of the cone, until the answer satisfies Coulomb (lcpbench's
    residual) or the bounds stop moving or :data:`~.fc2d_tresca.MAX_FIXED` problems. (r, states,
    changes, done)."""
    r = reactions(W, q, np.zeros(mu.size), np.where(st == STICK, FORWARD, st))
    bound = mu * np.maximum(r[0::2], 0.0)
    changes = 0
    for _ in range(MAX_FIXED):
        r, st, used, ok = pivot(W, q, mu, st, limit, BLOCK_TRIES, bound)
        changes += used
        if not ok:
            return r, st, changes, False
        bound, solved, fixed, _ = next_bounds(W, q, mu, r, bound)
        if solved:
            return r, st, changes, True
        if fixed:
            break
    return r, st, changes, False


def solve_fc2d_active(W, q, mu, *, states: np.ndarray | None = None,
                      max_iter: int | None = None) -> FC2DSolution:
    """Solve u = W r + q with 2-D Coulomb friction by the active set on the contacts'
    states (module docstring). ``states``: a start (one of 0–3 per contact); by default
    the frictionless contact set (the same pivoting with μ = 0, where W_nn is positive
    definite and the lowest-index rule is finite), its contacts then sticking.
    ``max_iter``: the limit on state changes per phase (default 20 + 10 nc). Never
    raises for a failure: MAX_ITER or INACCURATE with a message; ProblemError for
    shapes."""
    W, q, mu = fc2d_arrays(W, q, mu)
    nc = mu.size
    t0 = time.perf_counter()
    limit = 20 + 10 * nc if max_iter is None else int(max_iter)
    used = 0
    if states is None:
        frictionless = np.zeros(nc)
        _, st, used, _ = pivot(W, q, frictionless, initial_states(q, frictionless), limit, 0)
        st = np.where((st != SEPARATE) & (mu > 0.0), STICK, st)
    else:
        st = np.asarray(states, np.int64).copy()
    if st.shape != (nc,) or np.any((st < 0) | (st > 3)):
        raise ProblemError(f"states must be {nc} values in 0..3, got {states!r}")
    st[(st == STICK) & (mu <= 0.0)] = FORWARD
    r, st, changes, done = pivot(W, q, mu, st, limit, BLOCK_TRIES)
    changes += used
    if not done:  # cycling on the cone: Tresca problems, each by the same pivoting
        r, st, more, done = tresca_fixed_point(W, q, mu, st, limit)
        changes += more
    u = W @ r + q
    residual = coulomb_residual(W, q, mu, r) if np.all(np.isfinite(r)) else np.inf
    elapsed = time.perf_counter() - t0
    extra = {"states": st.copy(), "solve_time": elapsed}
    if done and residual <= ACCEPT_TOL:
        return FC2DSolution(r, u, Status.SOLVED, changes, residual, "", extra)
    if not np.isfinite(residual):
        return FC2DSolution(r, u, Status.FAILED, changes, residual,
                            "the states' linear solve was not finite", extra)
    if done:
        return FC2DSolution(r, u, Status.INACCURATE, changes, residual,
                            f"states consistent but the Coulomb residual is {residual:.3g}",
                            extra)
    return FC2DSolution(r, u, Status.MAX_ITER, changes, residual,
                        f"no consistent states in {limit} changes (Coulomb residual "
                        f"{residual:.3g})", extra)
