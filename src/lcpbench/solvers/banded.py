"""Active-set methods for the contact step on its banded Hessian.

Solves ``min ½ uᵀHu + cᵀu  s.t.  lower <= u <= upper`` with H symmetric
positive definite and banded (pentadiagonal for a
:class:`~lcpbench.model.step.ContactStep`). Two exact, finite methods share the
banded Cholesky solve of a face (O(N) per active-set change):

``method="dual"`` (default): a dual active-set method (Goldfarb & Idnani,
Math. Prog. 27, 1983, specialised to bounds). It starts from the unconstrained
minimiser (all reactions zero) and walks in the reactions: every iterate
minimises the Lagrangian for some reactions R >= 0 (H u + c + R_upper −
R_lower = 0), so it is dual feasible and only the walls can be violated. Each iteration puts a
*block* of violated nodes against their walls (the deepest node of every run
of consecutive violated nodes; first, on a warm start, the previous contact
set; at large N, warm-started, nodes galloping from the contacts, :mod:`.gallop`),
computes the minimiser on that face with one banded solve, and moves
towards it until it gets there or a reaction would turn negative, in which
case that wall is released (with every wall whose reaction reaches zero
within round-off of the same point, which keeps mirror pairs of a symmetric
chain together). The dual objective is concave and the face minimiser is its
maximiser on the face, so it never falls along a move and rises on every
move of non-zero length; a move of zero length releases a wall. So no working
set at a face minimiser repeats and the walk ends in finitely many steps on a
strictly convex QP, at the optimum: a feasible u. A soft actuator touches its
wall at a few nodes, and the walk needs about as many face solves as that
(6 on the paper's N = 140 step, where the primal method, started from the
clipped unconstrained shape, needs 220 single changes). The gradient is
carried along by increments on the bands; at the end one step of refinement
with the step's exact, factored gradient gives the answer to round-off.

``method="primal"``: the primal active-set method (Nocedal & Wright, Alg.
16.3): every iterate is feasible; each iteration minimises over the current
face, then either moves to a blocking wall or releases the wall with the most
negative reaction. It is also the safeguard of the dual method: if the dual
walk sees a working set twice (round-off in a degenerate problem) or cannot
certify its answer, the primal method continues from the dual's last contact
set, one change at a time.

The answer is certified before it is called solved: primal feasibility,
stationarity on the free nodes and non-negative reactions, each against a
round-off scale computed from the size of the terms that cancel.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.linalg import LinAlgError, solveh_banded
from scipy.linalg.lapack import dpbsv, dpbtrs

from ..errors import ProblemError
from ..linalg import dense_to_bands, sub_bands
from ..thresholds import TIE, WALK_RTOL  # ties of the walk; its stationarity on a face
from . import compiled_walk
from .base import Status, StepSolution
from .gallop import gallop_picks

EPS = np.finfo(float).eps
METHODS = ("dual", "primal")
#: the same in a galloping walk at large N (:mod:`.gallop`), whose mirror pairs differ
#: by its round-off, ~cond(J) ε ~ N² ε (1e-6 at N = 10⁵)
TIE_LARGE = 1e-4



def solve_banded_qp(
    step,
    *,
    start: np.ndarray | None = None,
    active_upper: np.ndarray | None = None,
    active_lower: np.ndarray | None = None,
    max_iter: int | None = None,
    rtol: float = WALK_RTOL,
    method: str = "dual",
    reach: int = 0,
) -> StepSolution:
    """Solve a contact step exactly by an active-set method.

    Parameters
    ----------
    step : ContactStep (or anything with ``bands``, ``linear``, ``lower``,
        ``upper``, ``gradient``, ``gradient_scale``, ``unconstrained_minimiser``).
    start : heights of a previous answer. The nodes it has on a wall join the
        warm contact set; the primal method also starts from it (clipped to
        the walls). Default: no warm start (the primal method starts from the
        unconstrained minimiser clipped to the walls).
    active_upper, active_lower : boolean masks of walls to start in contact
        (a warm start, e.g. the previous step's contact set).
    max_iter : face solves (active-set changes) allowed, both methods together
        (default 20 n + 50).
    rtol : relative tolerance of the final certificate.
    reach : > 0: a step with its own face solves (large N), warm-started, gallops
        from its contacts from this many nodes on (:mod:`.gallop`); 0: bisects.
    method : "dual" (default) or "primal"; see the module docstring.

    Returns
    -------
    StepSolution
        ``iterations`` counts face solves (active-set changes of the primal
        method, blocks of changes of the dual one); ``message`` says when the
        primal safeguard took over from the dual method.
    """
    if method not in METHODS:
        raise ProblemError(f"method must be one of {METHODS}, got {method!r}")
    t0 = time.perf_counter()
    lo, hi = step.lower, step.upper
    n = step.size
    max_iter = 20 * n + 50 if max_iter is None else max_iter
    try:
        warm_up, warm_lo = _warm_masks(step, start, active_upper, active_lower)
        if method == "primal" or np.count_nonzero(lo > hi):
            if start is None:
                start = step.unconstrained_minimiser()
            return _primal(step, np.asarray(start, dtype=float), warm_up, warm_lo, max_iter,
                           t0, rtol)
        u, grad, S_up, S_lo, it, why = _dual(step, warm_up, warm_lo, max_iter, reach)
        u = np.minimum(np.maximum(u, lo), hi)  # round-off off the walls
        if why is None:
            sol = _finish(step, u, S_up, S_lo, it, t0, rtol, grad)
            if sol.status is Status.SOLVED:
                return sol
            why = sol.message
        # the safeguard: single changes from the dual's last contact set
        sol = _primal(step, u, S_up, S_lo, max(max_iter - it, 1), t0, rtol, done=it)
        note = f"dual active set: {why}; primal active set took over"
        sol.message = f"{note}; {sol.message}" if sol.message else note
        return sol
    except (LinAlgError, ValueError) as exc:
        return _fail(step, np.zeros(n), 0, t0, f"{type(exc).__name__}: {exc}")


def _warm_masks(step, start, active_upper, active_lower):
    """Walls to start in contact: the given masks, and the walls ``start`` is on."""
    lo, hi = step.lower, step.upper
    W_up = np.zeros(step.size, bool)
    W_lo = np.zeros(step.size, bool)
    if start is None and active_upper is None and active_lower is None:
        return W_up, W_lo
    fin_up, fin_lo = np.isfinite(hi), np.isfinite(lo)
    if start is not None:
        u = np.clip(np.asarray(start, dtype=float), lo, hi)
        W_up |= fin_up & (u >= hi)
        W_lo |= fin_lo & (u <= lo)
    if active_upper is not None:
        W_up |= np.asarray(active_upper, bool) & fin_up
    if active_lower is not None:
        W_lo |= np.asarray(active_lower, bool) & fin_lo
    W_lo &= ~W_up
    return W_up, W_lo


class _Banded:
    """Scratch space for the dual walk on a banded H: products and face solves.

    Both are written as a few whole-array numpy operations on strided views of
    zero-padded buffers (at N ~ 100 the cost of a numpy call, not of the
    arithmetic, is what counts).

    ``matvec(x)``: H x. Row k of the (2b + 1, n) view ``shift`` holds x
    shifted by k − b, row k of ``coef`` the matching diagonal of H.

    ``face_solve(fixed, rhs)``: the Newton step on a face. H with the rows and
    columns of the ``fixed`` nodes replaced by the identity (in lower banded
    storage) is factored and solved with ``rhs`` (which must be zero on the
    fixed nodes): one banded factorisation of the full size, without gathering
    the free nodes. ``solve(rhs)`` solves with H itself. The last factor is
    kept: ``resolve(rhs)`` solves again with it.
    """

    def __init__(self, bands: np.ndarray):
        self.bands = bands
        b = bands.shape[0] - 1
        n = bands.shape[1]
        coef = np.zeros((2 * b + 1, n))
        coef[b] = bands[0]
        for k in range(1, b + 1):
            coef[b + k, : n - k] = bands[k, : n - k]  # H[i, i + k]
            coef[b - k, k:] = bands[k, : n - k]  # H[i, i − k]
        self.coef = coef
        self.buf = np.zeros(n + 2 * b)
        step = self.buf.strides[0]
        self.shift = np.ndarray((2 * b + 1, n), buffer=self.buf, strides=(step, step))
        self.keep = np.zeros(n + b)  # 1.0 on free nodes, zero padding
        self.keep_pairs = np.ndarray((b + 1, n), buffer=self.keep, strides=(step, step))
        self.b, self.n = b, n
        self.factor = None

    def matvec(self, x: np.ndarray) -> np.ndarray:
        self.buf[self.b : self.b + self.n] = x
        return np.add.reduce(self.coef * self.shift, axis=0)

    def face_solve(self, fixed: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """Overwrites ``rhs``."""
        keep = self.keep
        keep[: self.n] = ~fixed
        face = self.bands * (keep[: self.n] * self.keep_pairs)  # entry kept iff both free
        face[0] += fixed
        self.factor, x, info = dpbsv(face, rhs, lower=1, overwrite_ab=True, overwrite_b=True)
        _check_info(info)
        return x

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """H x = rhs, on no face (overwrites ``rhs``)."""
        self.factor, x, info = dpbsv(self.bands, rhs, lower=1, overwrite_b=True)
        _check_info(info)
        return x

    def resolve(self, rhs: np.ndarray) -> np.ndarray:
        """Overwrites ``rhs``."""
        x, info = dpbtrs(self.factor, rhs, lower=1, overwrite_b=True)
        _check_info(info)
        return x


def _check_info(info: int) -> None:
    if info > 0:
        raise LinAlgError(f"{info}-th leading minor not positive definite")
    if info < 0:
        raise ValueError(f"illegal value in argument {-info} of a LAPACK call")


def _run_maxima(v: np.ndarray, slack: float) -> np.ndarray:
    """The deepest violation ``v > slack`` of every run of consecutive violated nodes."""
    viol = v > slack
    if not np.count_nonzero(viol):
        return viol
    # A node that is not violated has v <= slack < v of a violated neighbour, so it
    # never wins the comparisons: v itself can stand in the padded buffer.
    w = np.empty(v.size + 2)
    w[0] = w[-1] = -np.inf
    w[1:-1] = v
    mid = w[1:-1]
    return viol & (mid >= w[:-2]) & (mid > w[2:])


def _dual(step, warm_up, warm_lo, max_iter, reach=0):
    """The dual active-set walk.

    Returns ``(u, grad, S_up, S_lo, face_solves, why)``; ``why`` is None when
    it ended at the optimum (no wall violated; ``grad`` is then the gradient
    at ``u``), else the reason it stopped (the caller hands over to the
    primal method).

    Every iterate satisfies H u + c = −σ λ with λ >= 0 on the working set
    (σ = +1 upper wall, −1 lower wall, 0 free), so the gradient ``g`` is
    carried along by increments (H times a step, on the bands) instead of
    being recomputed; at the end one step of refinement with the exact,
    factored gradient removes what the increments accumulated.
    """
    lo, hi = step.lower, step.upper
    n = step.size
    # a step may bring its own face solves (the tridiagonal factor at large N)
    H = getattr(step, "factor", None) or _Banded(step.bands)
    matvec, face_solve = H.matvec, H.face_solve
    has_lo = bool(np.count_nonzero(np.isfinite(lo)))
    S = np.zeros(n, bool)  # the working set: nodes held against a wall
    u = H.solve(-np.asarray(step.linear, dtype=float))  # the unconstrained minimiser
    g = np.full(n, 0.0)  # the gradient there, up to round-off (written: see wall)
    # violations at the round-off of the heights are not violations (the walls that
    # matter are within a violation of u)
    slack = 32 * EPS * (1.0 + float(np.max(np.abs(u), initial=0.0)))
    # a step with its own face solves (large N, in increments): heights are refined to
    # round-off at every optimum found, and a violation is one beyond the round-off of
    # the node's own height (a height error δ costs ~16 EI δ / a³ of force)
    own = getattr(step, "factor", None) is not None
    refined = False
    if own:
        slack = 32 * EPS * (np.abs(u) + np.where(np.isfinite(hi), np.abs(hi), 0.0)
                            + np.where(np.isfinite(lo), np.abs(lo), 0.0))
    sigma = np.zeros(n)  # +1: held against the upper wall, −1: the lower one, 0: free
    wall = np.full(n, 0.0)  # the wall height of each held node (written: np.zeros pages
    # that are only read are slow to read in compiled loops)
    warm = bool(np.count_nonzero(warm_up) or np.count_nonzero(warm_lo))
    # large N, warm-started with a hint of how far the contacts move: gallop from them
    # instead of bisecting the spans between them (:mod:`.gallop`)
    reach = int(reach) if (own and warm) else 0
    tie = TIE_LARGE if own else TIE
    if own and compiled_walk.ENABLED and hasattr(H, "walk") and n >= 5:  # large N
        return compiled_walk.dual_walk(step, H, u, slack, warm_up, warm_lo, has_lo,
                                       max_iter, reach, tie, compiled_walk.refine_on_face)
    seen: set[bytes] = set()
    at_face_minimiser = True
    it = 0
    while True:
        if at_face_minimiser:
            v_up = u - hi
            v_up[S] = -np.inf
            v_lo = None
            if has_lo:
                v_lo = lo - u
                v_lo[S] = -np.inf
            J_up = J_lo = None
            if warm:  # first, the warm contact set, where it is violated
                warm = False
                J_up = warm_up & (v_up > slack)
                J_lo = (warm_lo & (v_lo > slack)) if has_lo else None
                if not (np.count_nonzero(J_up) or (has_lo and np.count_nonzero(J_lo))):
                    J_up = None
            if J_up is None:
                if reach:
                    J_up = gallop_picks(v_up, slack, S, reach)
                    J_lo = gallop_picks(v_lo, slack, S, reach) if has_lo else None
                    reach *= 2
                else:
                    J_up = _run_maxima(v_up, slack)
                    J_lo = _run_maxima(v_lo, slack) if has_lo else None
                if not (np.count_nonzero(J_up) or (has_lo and np.count_nonzero(J_lo))):
                    if refined and not own:  # no wall crossed by the refinement
                        return u, g, sigma > 0, sigma < 0, it, None
                    # the optimum: one step of refinement with the exact gradient, on
                    # the face just factored
                    u = np.where(S, wall, u)
                    g = step.gradient(u)
                    r = g.copy()
                    r[S] = 0.0
                    p = H.resolve(r)
                    if own and not refined:  # refine, then look at the walls again
                        u, g = compiled_walk.refine_on_face(step, H, S, u - p)
                        refined = True
                        continue
                    if own:
                        return u, g, sigma > 0, sigma < 0, it, None
                    # then the walls once more: the unrefined heights carry the
                    # round-off of the factor (cond(H) ε |u|), and a node the walk left
                    # free may cross its wall once refined (a grazing contact)
                    u, g = u - p, g - matvec(p)
                    refined = True
                    continue
            held = np.flatnonzero(sigma)  # the working set, compactly
            key = held.tobytes() + sigma[held].tobytes()
            if key in seen:
                return u, None, sigma > 0, sigma < 0, it, "a working set repeated (round-off)"
            seen.add(key)
            sigma[J_up] = 1.0
            wall[J_up] = hi[J_up]
            if has_lo:
                J_lo &= ~J_up
                sigma[J_lo] = -1.0
                wall[J_lo] = lo[J_lo]
            S = sigma != 0.0
        if it >= max_iter:
            return u, None, sigma > 0, sigma < 0, it, f"limit of {max_iter} face solves"
        it += 1
        # d: from u to the minimiser on the face S (S onto its walls, then Newton
        # on the free nodes), as an increment
        d = (wall - u) * S
        r = g + matvec(d)
        r[S] = 0.0
        d -= face_solve(S, r)
        g_face = g + matvec(d)
        # the reactions there are −σ g_face; move towards it until one turns negative
        # (only held nodes have reactions: the tests run on them, not on all n)
        held = np.flatnonzero(S)
        sg = sigma[held] * g_face[held]
        fall = sg > 0.0
        if np.count_nonzero(fall):
            falling = held[fall]
            lam = np.maximum(-sigma[falling] * g[falling], 0.0)
            ratio = lam / (lam + sg[fall])
            s = float(ratio.min())
            if s < 1.0:
                u = u + s * d
                g = g + s * (g_face - g)
                # release every wall whose reaction reaches zero here, ties within
                # round-off included (a symmetric chain has its contacts in mirror pairs)
                drop = falling[ratio <= s + tie]
                sigma[drop] = 0.0
                S[drop] = False
                at_face_minimiser = False
                continue
        u = u + d
        g = g_face
        at_face_minimiser = True
        refined = False


def _primal(step, start, W_up, W_lo, max_iter, t0, rtol, done=0) -> StepSolution:
    """The primal active-set method from ``start`` (clipped) and the walls W."""
    lo, hi = step.lower, step.upper
    n = step.size
    u = np.clip(start, lo, hi)
    W_up = W_up | (np.isfinite(hi) & (u >= hi))
    W_lo = (W_lo | (np.isfinite(lo) & (u <= lo))) & ~W_up
    u[W_up] = hi[W_up]
    u[W_lo] = lo[W_lo]
    at_minimiser = False  # True after a full step: u minimises H on the current face
    for it in range(1, max_iter + 1):
        free = ~(W_up | W_lo)
        if at_minimiser or not free.any():
            grad = step.gradient(u)
            noise = 64 * EPS * step.gradient_scale(u)
            lam_up = np.where(W_up, -grad, np.inf) / noise  # upper-wall reactions
            lam_lo = np.where(W_lo, grad, np.inf) / noise
            worst_up, worst_lo = int(np.argmin(lam_up)), int(np.argmin(lam_lo))
            if min(lam_up[worst_up], lam_lo[worst_lo]) >= -1.0:
                return _finish(step, u, W_up, W_lo, done + it, t0, rtol)
            if lam_up[worst_up] <= lam_lo[worst_lo]:
                W_up[worst_up] = False
            else:
                W_lo[worst_lo] = False
            at_minimiser = False
            continue
        # Newton step on the current face, as an increment (accurate near the answer)
        idx = np.flatnonzero(free)
        p = np.zeros(n)
        rhs = -step.gradient(u)[idx]
        solve_on = getattr(step, "solve_on", None)
        p[idx] = (solve_on(idx, rhs) if solve_on is not None else
                  solveh_banded(sub_bands(step.bands, idx), rhs, lower=True, check_finite=False))
        if not np.all(np.isfinite(p)):
            return _fail(step, u, done + it, t0, "non-finite face minimiser")
        # ratio test: the first wall met along p (smallest index on ties)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_up = np.where(free & (p > 0) & np.isfinite(hi), (hi - u) / p, np.inf)
            t_lo = np.where(free & (p < 0) & np.isfinite(lo), (lo - u) / p, np.inf)
        j_up, j_lo = int(np.argmin(t_up)), int(np.argmin(t_lo))
        t = min(1.0, t_up[j_up], t_lo[j_lo])
        u = u + max(t, 0.0) * p
        if t < 1.0:
            if t_up[j_up] <= t_lo[j_lo]:
                W_up[j_up] = True
                u[j_up] = hi[j_up]
            else:
                W_lo[j_lo] = True
                u[j_lo] = lo[j_lo]
        else:
            at_minimiser = True
    sol = _finish(step, u, W_up, W_lo, done + max_iter, t0, rtol)
    sol.status = Status.MAX_ITER
    sol.message = f"active-set limit of {done + max_iter} changes reached"
    return sol


def _finish(step, u, W_up, W_lo, iterations, t0, rtol, grad=None) -> StepSolution:
    """The answer with its reactions, timed up to here, then certified.

    ``grad``: the gradient at ``u`` when the caller has it (the dual walk's,
    after its refinement); the certificate recomputes the exact one itself.
    """
    if grad is None:
        grad = step.gradient(u)
    r_up = np.where(W_up, np.maximum(-grad, 0.0), 0.0)
    r_lo = np.where(W_lo, np.maximum(grad, 0.0), 0.0)
    elapsed = time.perf_counter() - t0
    sol = StepSolution(
        u=u, forces_upper=r_up, forces_lower=r_lo, status=Status.SOLVED,
        iterations=iterations, solve_time=elapsed,
        active_upper=W_up.copy(), active_lower=W_lo.copy(),
    )
    err = step_certificate(step, sol)
    if err > rtol:
        sol.status = Status.INACCURATE
        sol.message = f"certificate residual {err:.2e} > {rtol:.1e}"
    return sol


def _fail(step, u, iterations, t0, message) -> StepSolution:
    n = step.size
    return StepSolution(
        u=u, forces_upper=np.zeros(n), forces_lower=np.zeros(n), status=Status.FAILED,
        iterations=iterations, solve_time=time.perf_counter() - t0, message=message,
    )


def step_certificate(step, sol: StepSolution) -> float:
    """Scaled KKT residual of a step solution, the same for every back-end.

    max over rows of |H u + c − R_lower + R_upper| (stationarity), bound
    violations and |gap·R| (complementarity), each divided by the size of the
    terms that make it up, so 1e-12 means "round-off" whatever the units.
    (Written with array methods and few temporaries: at N ~ 100 each numpy
    call, not its arithmetic, is the cost.)
    """
    u, ru, rl = sol.u, sol.forces_upper, sol.forces_lower
    if not (np.isfinite(u).all() and np.isfinite(ru).all() and np.isfinite(rl).all()):
        return np.inf
    if u.size == 0:
        return 0.0
    grad = step.gradient(u)
    size = step.gradient_scale(u)
    size += ru
    size += rl
    force = max(float(size.max()), np.finfo(float).tiny)
    grad += ru
    grad -= rl
    stat = float(np.abs(grad).max()) / force
    span = 1.0 + float(np.abs(u).max())
    with np.errstate(invalid="ignore"):  # inf − inf cannot occur: u is finite
        g_up = step.upper - u  # +inf where there is no upper wall
        g_lo = u - step.lower
    feas = max(-float(g_up.min()), -float(g_lo.min()), 0.0) / span
    neg = max(-float(ru.min()), -float(rl.min()), 0.0) / force
    # complementarity where a wall exists (a reaction on a node with no wall is
    # already a stationarity error; 0 * inf is avoided by zeroing the infinite gaps)
    g_up[np.isinf(g_up)] = 0.0
    g_lo[np.isinf(g_lo)] = 0.0
    g_up *= ru
    g_lo *= rl
    comp = max(float(np.abs(g_up).max()), float(np.abs(g_lo).max())) / (force * span)
    return max(stat, feas, neg, comp)


# -- the back-end interface ---------------------------------------------------
class _BandedBoxQP:
    """A general :class:`~lcpbench.solvers.base.BoxQP` in the shape the active
    set needs (bands, gradient, a round-off scale of the gradient)."""

    def __init__(self, qp):
        self.P = qp.P
        self.linear = np.asarray(qp.c, dtype=float)
        self.lower = np.asarray(qp.lower, dtype=float)
        self.upper = np.asarray(qp.upper, dtype=float)
        self.bands = qp.bands if qp.bands is not None else dense_to_bands(qp.dense())
        self.absP = abs(self.P)

    @property
    def size(self) -> int:
        return self.linear.size

    def gradient(self, u):
        return self.P @ u + self.linear

    def gradient_scale(self, u):
        return self.absP @ np.abs(u) + np.abs(self.linear) + np.finfo(float).tiny

    def unconstrained_minimiser(self):
        return solveh_banded(self.bands, -self.linear, lower=True, check_finite=False)



def _warm_sets(warm, n):
    if warm is None:
        return None, None, None
    x = getattr(warm, "u", None)
    if x is None:
        x = warm.x
    up = getattr(warm, "active_upper", None)
    lo = getattr(warm, "active_lower", None)
    return x, up, lo


def solve_step(step, settings, warm=None, **options) -> StepSolution:
    """The contact step by the active set on its own banded, factored form.

    The method is scale-invariant (its tests are relative to the size of the
    terms that cancel), so it always works on the step in physical units.
    """
    x, up, lo = _warm_sets(warm, step.size)
    max_iter = settings.max_iter if settings.max_iter else None
    return solve_banded_qp(step, start=x, active_upper=up, active_lower=lo, max_iter=max_iter,
                           reach=int(getattr(warm, "reach", 0) or 0))


def solve_qp(qp, settings, warm=None, **options):
    """Any bound-constrained QP with positive-definite P (banded or not)."""
    from .base import QPResult

    t0 = time.perf_counter()
    try:
        prob = _BandedBoxQP(qp)
    except (LinAlgError, ValueError) as exc:
        return QPResult.failure(qp.size, Status.FAILED, f"{type(exc).__name__}: {exc}")
    setup = time.perf_counter() - t0
    x, _, _ = _warm_sets(warm, qp.size)
    max_iter = settings.max_iter if settings.max_iter else None
    sol = solve_banded_qp(prob, start=x, max_iter=max_iter)
    y = sol.forces_upper - sol.forces_lower
    return QPResult(sol.u, y, sol.status, sol.iterations, sol.solve_time, setup, sol.message,
                    time_source="solver")
