"""Active-set methods for the contact step on its banded Hessian, and for any box QP.

Solves ``min ½ uᵀHu + cᵀu  s.t.  lower <= u <= upper`` with H symmetric
positive definite and banded (pentadiagonal for a
:class:`~lcpbench.model.step.ContactStep`; any bandwidth for a QP or an LCP's
``min ½ zᵀMz + qᵀz, z >= 0``). Two exact, finite methods, each solving one face
per active-set change (O(N) on the contact step's bands):

``method="dual"`` (default): a dual active-set method (Goldfarb & Idnani,
Math. Prog. 27, 1983, specialised to bounds). It starts from the unconstrained
minimiser (all reactions zero) and walks in the reactions: every iterate
minimises the Lagrangian for some reactions R >= 0 (H u + c + R_upper −
R_lower = 0), so it is dual feasible and only the walls can be violated. Each iteration puts a
*block* of violated nodes against their walls (every local maximum of the
violations in each run of violated nodes, :mod:`lcpbench.linalg.walk_picks`;
first, on a warm start, the previous contact
set; at large N, warm-started, nodes galloping from the contacts, :mod:`.compiled_walk`),
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
with the step's exact, factored gradient gives the answer to round-off. The
walk is compiled once (:func:`lcpbench.solvers.dual_kernel.dual_active_set`:
the solve kernel's, and here every QP's, :func:`_dual`).

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

from ..errors import ProblemError
from ..linalg import dense_to_bands, sub_bands
from ..thresholds import WALK_RTOL  # the walk's stationarity on a face
from . import compiled_walk
from .base import Status, StepSolution

EPS = np.finfo(float).eps
METHODS = ("dual", "primal")
#: the same in a galloping walk at large N (:mod:`.compiled_walk`), whose mirror pairs differ
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
        from its contacts from this many nodes on (:mod:`.compiled_walk`); 0: bisects.
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
    if getattr(step, "elastic", False) and getattr(step, "factor", None) is None:
        raise ProblemError("step: its walls are elastic (the gap g + R/k) and this walk "
                           "and its certificate take rigid walls; solve it with "
                           "lcpbench.model.step_solver.solve_step(step, 'active-set')")
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


_BOX_QP: list = []  # the compiled walk's entry (solvers/dual_kernel.py), once loaded
_NO_T = np.zeros((2, 0))  # no curvature T: a Gauss–Newton step, or a QP


def _dual(step, warm_up, warm_lo, max_iter, reach=0):
    """The dual active-set walk (the module's docstring), compiled.

    Returns ``(u, grad, S_up, S_lo, face_solves, why)``; ``why`` is None when it ended
    at the optimum (no wall violated; ``grad`` is then the gradient at ``u``), else the
    reason it stopped (the caller hands over to the primal method).

    A step with its own face solves (the twisted factor at large N, in increments)
    walks on them (:func:`lcpbench.solvers.compiled_walk.dual_walk`: galloping from a
    warm contact set ``reach`` nodes on, its violations beyond the round-off of each
    node's height, its refinement to round-off at every optimum). Any other QP walks in
    one call of :func:`lcpbench.solvers.dual_kernel.box_qp`: its faces on the banded
    LDLᵀ where H has at most two sub-diagonals (the contact step's), else on the banded
    Cholesky of the whole face (4 b <= n) or LAPACK's of its free block; its refinement with the contact step's exact gradient
    where the step gives its joint stencil on contiguous nodes (:func:`_stencil`), else
    with H u + c.
    """
    H = getattr(step, "factor", None)
    if H is not None and hasattr(H, "walk") and step.size >= 5:
        lo, hi = step.lower, step.upper
        u = H.solve(-np.asarray(step.linear, dtype=float))  # the unconstrained minimiser
        has_lo = bool(np.count_nonzero(np.isfinite(lo)))
        # a violation is one beyond the round-off of the node's own height (a height
        # error δ costs ~16 EI δ / a³ of force)
        slack = 32 * EPS * (np.abs(u) + np.where(np.isfinite(hi), np.abs(hi), 0.0)
                            + np.where(np.isfinite(lo), np.abs(lo), 0.0))
        warm = bool(np.count_nonzero(warm_up) or np.count_nonzero(warm_lo))
        return compiled_walk.dual_walk(step, H, u, slack, warm_up, warm_lo, has_lo, max_iter,
                                       int(reach) if warm else 0, TIE_LARGE,
                                       compiled_walk.refine_on_face)
    return _compiled_dual(step, warm_up, warm_lo, max_iter)


def _stencil(step):
    """The contact step's joint stencil, as :func:`~lcpbench.solvers.dual_kernel.grad_into`
    takes it (its exact gradient, the refinement's), and its curvature T; None for a QP,
    a step in increments or one whose joints or free nodes are not contiguous."""
    coef = getattr(step, "coef", None)
    if coef is None or getattr(step, "factor", None) is not None:
        return None
    free, base = step.free_nodes, step.base
    if not (free.size and base.size and free[-1] - free[0] == free.size - 1
            and base[-1] - base[0] == base.size - 1):
        return None
    f64 = np.ascontiguousarray
    T = _NO_T if step.geometric is None else f64(step.geometric[:2], dtype=float)
    return (f64(coef, dtype=float), int(base[0]), int(free[0]) + 1, int(step.links),
            *(f64(x, dtype=float) for x in (step.origin, step.phi_origin, step.stiffness,
                                            step.rest_joint, step.nodal_load)), T)


_LOADED: set = set()  # (kernel module, dense faces) whose machine code is loaded


def _walk_kernel(dense: bool | None = None):
    """The compiled walk (:mod:`lcpbench.solvers.dual_kernel`), loaded once; with
    ``dense`` (True: the dense faces, False: the banded ones), that version's machine
    code too, by a call on a one-node QP. The back-end's calls do this before their
    clocks start: a first call's load (~40 ms from numba's cache) is not its solve."""
    from ..numba_cache import kept  # numba: loads or compiles at first use

    kern = kept(_BOX_QP, "lcpbench.solvers.dual_kernel", "box_qp")
    if dense is not None and (id(kern), dense) not in _LOADED:
        one, none, no = np.ones(1), np.zeros(0), np.zeros(1, bool)
        kern.box_qp(np.ones((4 if dense else 3, 1)), one, -one, one, no, no, 50,
                    np.empty((2, 2, 1)) if dense else np.empty((4, 1)), np.zeros((0, 3)),
                    0, 1, 0, none, none, none, none, none, _NO_T)
        _LOADED.add((id(kern), dense))
    return kern


def _compiled_dual(step, warm_up, warm_lo, max_iter):
    """:func:`_dual` in one call of :func:`lcpbench.solvers.dual_kernel.box_qp`."""
    kern = _walk_kernel()
    n = step.size
    f64 = np.ascontiguousarray
    bands = f64(step.bands, dtype=float)
    if bands.shape[0] < 3:  # a diagonal or tridiagonal H: the banded faces, zeros padded
        bands = np.vstack((bands, np.zeros((3 - bands.shape[0], n))))
    b = bands.shape[0] - 1
    if b == 2:  # the contact step's: the banded LDLᵀ, restarted at a face's first change
        fac = np.empty((4, n))
    elif 4 * b <= n:  # a few more: the banded Cholesky of the whole face, O(n b²)
        fac = np.empty((2, b + 1, n))
    else:  # wide: LAPACK's Cholesky of the free block
        fac = np.empty((2, max(n, 2), n))
    masks = (np.zeros(n, bool) if w is None else f64(w, dtype=bool) for w in (warm_up, warm_lo))
    none = np.zeros(0)
    stencil = _stencil(step) or (np.zeros((0, 3)), 0, 1, 0, none, none, none, none, none,
                                 _NO_T)
    code, it, u, g, sigma = kern.box_qp(bands, f64(step.linear, dtype=float),
                                        f64(step.lower, dtype=float),
                                        f64(step.upper, dtype=float), *masks, int(max_iter),
                                        fac, *stencil)
    if code == kern.BAIL_NOT_PD:
        raise LinAlgError("a face of H is not positive definite")
    stops = {kern.BAIL_REPEAT: "a working set repeated (round-off)",
             kern.BAIL_LIMIT: f"limit of {max_iter} face solves (or of the walk's history)"}
    why = None if code == 0 else stops.get(int(code), f"the walk stopped (code {code})")
    return u, (g if why is None else None), sigma > 0, sigma < 0, int(it), why


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
    if getattr(step, "factor", None) is None:  # (else the twisted walk, compiled_walk)
        _walk_kernel(np.shape(step.bands)[0] > 3)
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
    _walk_kernel(prob.bands.shape[0] > 3)
    x, _, _ = _warm_sets(warm, qp.size)
    max_iter = settings.max_iter if settings.max_iter else None
    sol = solve_banded_qp(prob, start=x, max_iter=max_iter)
    y = sol.forces_upper - sol.forces_lower
    return QPResult(sol.u, y, sol.status, sol.iterations, sol.solve_time, setup, sol.message,
                    time_source="solver")
