"""The paper's nonlinear root-finding baseline (Appendix A, eqs. 44–45, Table I).

The same Hencky bar chain as the LCP model, but the contact is a single
reaction R at the midspan node, whose height is prescribed to be h. The
exact (not linearised) equilibrium is written as F(x) = 0 with 3N + 2
equations in 3N + 2 unknowns and handed to MINPACK's Powell hybrid method
(``scipy.optimize.root(method="hybr")``, what MATLAB's ``fsolve`` does by
default) or Levenberg–Marquardt (``method="lm"``).

Unknowns (3N + 2)
-----------------
=============  =====  ==========================================================
α̂_1..α̂_N       N      link angles to the x-axis (rad)
φ̂_1..φ̂_N       N      φ̂_1 = pin angle of link 1, φ̂_i (i ≥ 2) joint angle at node i
τ_2..τ_N       N − 1  bending moments at the interior joints (N·mm)
q_1, q_n       2      support reactions of the left and right pins (N, +y)
R              1      the midspan reaction (N, pushing away from the wall)
=============  =====  ==========================================================

Equations (3N + 2), the rows of Table I
---------------------------------------
=============================================  =====  ===============================
support reactions (eqs. 3, 8, exact geometry)  2      Σ moments about node n = 0 (q_1);
                                                      Σ moments about node 1 = 0 (q_n)
torques, summing external moments (eq. 11)     N − 1  τ_i = Σ moments of the forces left
                                                      of node i (q_1, link weights, R)
torques, constitutive (eq. 17)                 N − 1  τ_i = (EI/a)(φ̂_i − φ̂*_i)
relation between φ̂ and α̂ (eq. 18)             N      φ̂_1 = α̂_1, φ̂_i = α̂_i − α̂_{i−1}
constraining equations (eqs. 44, 45)           2      a Σ_{i≤N} sin(Σ_{j≤i} φ̂_j) = 0;
                                                      a Σ_{i≤⌊N/2⌋} sin(Σ_{j≤i} φ̂_j) = h
=============================================  =====  ===============================

The forces are vertical only: the right pin slides along x and the contact is
frictionless (Sec. III-A), so there is no horizontal force anywhere and the
statics of the chain reduce to the moment equations above (there are no
per-link x/y force balances with internal pin forces in the paper's count).
The link weights μ = wℓ/N act at the link centres, away from the wall, as in
eqs. (3), (8) and in :class:`~lcpbench.problems.scenes.ActuatorScene`.

How the ambiguities of the paper were resolved
----------------------------------------------
* Eq. (44) is described as "the sum of all joint angles φ_{1:N} must be zero",
  but the printed equation is the closure y_{N+1} = a Σ sin α̂_i = 0 with
  α̂_i = Σ_{j≤i} φ̂_j (so φ̂_1 is the angle of link 1 itself, not a joint). The
  printed equation is used: it puts the right pin on y = 0, which the text
  says is its purpose, and it is dimensionally consistent (mm); "Σφ = 0"
  would instead make the last link horizontal. The "relation between φ̂ and
  α̂" row counts N equations, which fixes φ̂_1 = α̂_1.
* Table I counts N − 1 torque equations of each kind: moments at the N − 1
  interior joints only; the pins carry none.
* The sign of τ: eq. (17) reads τ = −(EI/a)(φ̂ − φ̂*). Here τ is the sagging
  bending moment, τ = +(EI/a)(φ̂ − φ̂*) summed from the forces on the left of
  the joint, the same convention as :func:`~lcpbench.model.chain.joint_moments`.
  Flipping the sign of τ in both equations changes nothing else.
* The statics use the link angles α̂, the constraints use the cumulative
  sums of φ̂, as printed; they agree at any solution (the φ̂–α̂ rows).
* The midspan node of eq. (45) is node ⌊N/2⌋ + 1 (1-based). For odd N the
  paper says reactions develop at the two nodes either side of midspan and
  their sum is the total reaction, but keeps a single unknown: R is split
  equally between nodes ⌊N/2⌋ + 1 and ⌊N/2⌋ + 2, and eq. (45) constrains the
  first of them (the other sits at the same height in the symmetric
  solution; the wall check below catches it if it does not).
* Initial guess: the paper states none. The unconstrained arc (α̂ = α*,
  φ̂ = φ̂*, τ = 0), R = 0 and the support reactions of the self-weight alone.
* Scaling: lengths by ℓ, forces by EI/ℓ², moments by EI/ℓ (DESIGN.md), so
  every residual is dimensionless and of order one.

What the result certifies
-------------------------
The model cannot represent a wall that touches the chain anywhere but at
midspan, nor a wall that does not touch it at all. After scipy reports
success the answer is re-checked on the exact geometry (forward kinematics
from α̂): residual, closure of the chain on the right pin, midspan node at h,
torque balance by the independent :func:`~lcpbench.model.chain.torque_residual`.
Failing any of those is ``converged=False`` ("bad solution: ..."). An answer
that solves the equations is ``converged=True`` but only ``valid`` as a
contact answer if no node lies beyond the wall (the documented breakdown at
small h, Fig. 27b: the chain bows out on either side of the midspan node),
no node lies below the lower wall of a channel (which the model ignores),
and R >= 0 (a wall cannot pull).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import root

from ..errors import ProblemError
from ..model.chain import node_positions, torque_residual
from ..problems.checks import describe
from ..problems.scenes import ActuatorScene, Chain
from ..studies.discretisation import auto_links

METHODS = ("hybr", "lm")
JACOBIANS = ("analytic", "fd")  # "fd": MINPACK's forward differences, fsolve's default

GEOMETRY_TOL_MM = 1e-6  # the baseline's own: closure, midspan height and penetration (mm)
RESIDUAL_TOL = 1e-8  # dimensionless residual (moments / (EI/ℓ), lengths / ℓ)


@dataclass
class BaselineResult:
    """The single-reaction equilibrium of a scene and how it was found.

    Attributes
    ----------
    alpha : link angles α̂ (rad), (N,).
    reaction : the midspan reaction R (N), pushing away from the wall.
    forces : the reaction R per free node (nodes 2..N, N), like
        :attr:`ContactResult.forces`: zero except at the midspan node(s).
    total_force : sum of ``forces`` (= ``reaction``) (N).
    converged : the equations are solved (scipy's success, re-checked on the
        exact geometry).
    valid : converged and a possible contact answer: no node beyond the
        wall(s) by more than the geometric tolerance, and R >= 0.
    status : "solved", "bad solution: ...", "no convergence", "max
        evaluations", "time limit" or "diverged".
    message : details (scipy's message, the check that failed).
    iterations : function evaluations scipy reports (nfev).
    jacobian_evaluations : Jacobian evaluations scipy reports (njev).
    time_s : wall time of the root finding (s); setup_time_s: building the system.
    residual_norm : max |F(x)| of the dimensionless system at the answer.
    x, y : node coordinates (mm), nodes 1..N+1, from exact forward kinematics.
    support : pin reactions (q_1, q_n) (N, +y).
    max_penetration : largest distance of a node beyond a wall (mm); <= 0 if none.
    closure : |y| of the right pin (mm).
    midspan_error : y of the midspan node minus h (mm).
    relative_torque_residual : max |k(φ − φ*) − M| over joints, by
        :func:`~lcpbench.model.chain.torque_residual`, relative to EI/ℓ.
    """

    scene: ActuatorScene
    links: int
    method: str
    alpha: np.ndarray
    reaction: float
    forces: np.ndarray
    total_force: float
    converged: bool
    valid: bool
    status: str
    message: str
    iterations: int
    jacobian_evaluations: int
    time_s: float
    residual_norm: float
    x: np.ndarray
    y: np.ndarray
    support: tuple[float, float]
    max_penetration: float
    closure: float
    midspan_error: float
    relative_torque_residual: float
    setup_time_s: float = 0.0
    extra: dict = field(default_factory=dict)


class BaselineSystem:
    """F(x) = 0 of the single-reaction model, dimensionless, with its Jacobian.

    The unknown vector is ``[α̂ (N), φ̂ (N), τ/(EI/ℓ) (N−1), q_1, q_n, R]``
    with forces over EI/ℓ²; the residual rows are, in order, φ̂–α̂ (N),
    constitutive torques (N−1), torques from statics (N−1), support reactions
    (2) and the constraints (44), (45).
    """

    def __init__(self, chain: Chain, height: float):
        n = chain.links
        self.n = n
        self.size = 3 * n + 2
        self.ell = chain.length
        self.fs = chain.force_scale  # EI/ℓ²
        self.a = chain.link_length / self.ell  # â = 1/N
        self.h = height / self.ell
        self.k = chain.joint_stiffness / (self.fs * self.ell)  # = ℓ/a
        self.rest_joint = chain.rest_joint
        self.load = chain.link_load / self.fs  # P̃_i, +y, at link centres
        m = n // 2  # 0-based midspan node: node ⌊N/2⌋ + 1 in the paper's numbering
        self.mid = m
        self.share = np.zeros(n + 1)  # how R is spread over the nodes
        if n % 2 == 0:
            self.share[m] = 1.0
        else:
            self.share[m] = self.share[m + 1] = 0.5
        self._below = np.tril(np.ones((n + 1, n)), -1)  # [p, j] = 1 if link j < node p

    # -- layout ---------------------------------------------------------------
    def split(self, z: np.ndarray):
        n = self.n
        return z[:n], z[n:2 * n], z[2 * n:3 * n - 1], z[3 * n - 1], z[3 * n], z[3 * n + 1]

    def initial(self, alpha: np.ndarray, reaction: float = 0.0) -> np.ndarray:
        """A consistent start from link angles: φ̂ and τ from α̂, q from statics."""
        phi = np.diff(alpha, prepend=0.0)
        tau = self.k * (phi[1:] - self.rest_joint)
        r = reaction / self.fs
        x, xc = self._x(alpha)
        force = -r * self.share
        q1 = -(force @ (x[-1] - x) + self.load @ (x[-1] - xc)) / x[-1]  # eq. (3)
        qn = -(force @ x + self.load @ xc) / x[-1]  # eq. (8)
        return np.concatenate([alpha, phi, tau, [q1, qn, r]])

    def _x(self, alpha):
        x = np.concatenate(([0.0], np.cumsum(self.a * np.cos(alpha))))
        return x, x[:-1] + 0.5 * self.a * np.cos(alpha)

    def _forces(self, q1, qn, r):
        f = -r * self.share
        f[0] += q1
        f[-1] += qn
        return f

    # -- residual and Jacobian ------------------------------------------------
    def residual(self, z: np.ndarray) -> np.ndarray:
        alpha, phi, tau, q1, qn, r = self.split(z)
        x, xc = self._x(alpha)
        f = self._forces(q1, qn, r)
        p = self.load
        # moments at every node from the forces on its left (sagging positive)
        sf = np.concatenate(([0.0], np.cumsum(f[:-1])))
        sfx = np.concatenate(([0.0], np.cumsum((f * x)[:-1])))
        sp = np.concatenate(([0.0], np.cumsum(p)))
        spx = np.concatenate(([0.0], np.cumsum(p * xc)))
        moment = x * (sf + sp) - (sfx + spx)
        beta = np.cumsum(phi)  # α̂ from φ̂, as eqs. (44), (45) write it
        sin_b = self.a * np.sin(beta)
        return np.concatenate([
            phi - np.diff(alpha, prepend=0.0),  # eq. (18) and φ̂_1 = α̂_1
            tau - self.k * (phi[1:] - self.rest_joint),  # eq. (17)
            tau - moment[1:-1],  # eq. (11)
            [moment[-1],  # moments about the right pin: fixes q_1, eq. (3)
             f @ x + p @ xc,  # moments about the left pin: fixes q_n, eq. (8)
             np.sum(sin_b),  # eq. (44)
             np.sum(sin_b[:self.mid]) - self.h],  # eq. (45)
        ])

    def jacobian(self, z: np.ndarray) -> np.ndarray:
        n = self.n
        alpha, phi, _, q1, qn, r = self.split(z)
        x, _ = self._x(alpha)
        f = self._forces(q1, qn, r)
        p = self.load
        s = self.a * np.sin(alpha)
        # ∂M_p/∂α_j = −â sin α_j V_j (j < p), V_j = Σ_{q<=j} F_q + Σ_{i<j} P_i + P_j/2
        v = np.cumsum(f[:-1]) + np.cumsum(p) - 0.5 * p
        dm_dalpha = -self._below * (s * v)
        dm_dq1 = x.copy()
        dm_dq1[0] = 0.0
        # ∂M_p/∂R = −Σ_{q<p} share_q (x_p − x_q)
        ss = np.concatenate(([0.0], np.cumsum(self.share[:-1])))
        ssx = np.concatenate(([0.0], np.cumsum((self.share * x)[:-1])))
        dm_dr = -(x * ss - ssx)
        # ∂(Σ F x + Σ P xc)/∂α_j = −â sin α_j W_j, W_j = Σ_{q>j} F_q + Σ_{i>j} P_i + P_j/2
        w = np.cumsum(f[::-1])[::-1][1:] + np.cumsum(p[::-1])[::-1] - 0.5 * p
        beta = np.cumsum(phi)
        c = self.a * np.cos(beta)
        tail = np.cumsum(c[::-1])[::-1]  # Σ_{i>=k} â cos β_i
        mid_tail = np.where(np.arange(n) < self.mid, tail - tail[self.mid], 0.0)

        jac = np.zeros((self.size, self.size))
        ia, ip, it = 0, n, 2 * n  # column offsets of α, φ, τ
        iq1, iqn, ir = 3 * n - 1, 3 * n, 3 * n + 1
        rows = np.arange(n)
        # φ̂ − Dα̂
        jac[rows, ip + rows] = 1.0
        jac[rows, ia + rows] = -1.0
        jac[rows[1:], ia + rows[:-1]] = 1.0
        # τ − k(φ̂ − φ̂*)
        r0 = n
        jr = np.arange(n - 1)
        jac[r0 + jr, it + jr] = 1.0
        jac[r0 + jr, ip + jr + 1] = -self.k
        # τ − M
        r0 = 2 * n - 1
        jac[r0 + jr, it + jr] = 1.0
        jac[r0 + jr, ia:ia + n] = -dm_dalpha[1:-1]
        jac[r0 + jr, iq1] = -dm_dq1[1:-1]
        jac[r0 + jr, ir] = -dm_dr[1:-1]
        # supports
        r0 = 3 * n - 2
        jac[r0, ia:ia + n] = dm_dalpha[-1]
        jac[r0, iq1] = dm_dq1[-1]
        jac[r0, ir] = dm_dr[-1]
        jac[r0 + 1, ia:ia + n] = -s * w
        jac[r0 + 1, iqn] = x[-1]
        jac[r0 + 1, ir] = -self.share @ x
        # constraints (44), (45)
        jac[r0 + 2, ip:ip + n] = tail
        jac[r0 + 3, ip:ip + n] = mid_tail
        return jac


class _Stop(Exception):
    """Raised inside the residual to end the root finding (time limit, non-finite)."""

    def __init__(self, status: str, message: str):
        super().__init__(message)
        self.status = status
        self.message = message


class _Watched:
    """The system's residual and Jacobian, counting calls and watching the clock."""

    def __init__(self, system: BaselineSystem, deadline: float | None):
        self.system = system
        self.deadline = deadline
        self.nfev = 0
        self.njev = 0
        self.last = None

    def _check(self, out):
        if not np.all(np.isfinite(out)):
            raise _Stop("diverged", "the residual or Jacobian became non-finite")
        if self.deadline is not None and time.perf_counter() > self.deadline:
            raise _Stop("time limit", "time limit reached")

    def fun(self, z):
        self.nfev += 1
        self.last = np.array(z, copy=True)
        out = self.system.residual(z)
        self._check(out)
        return out

    def jac(self, z):
        self.njev += 1
        out = self.system.jacobian(z)
        self._check(out)
        return out


def _check_options(scene, method, tol, max_nfev, time_limit):
    if not isinstance(scene, ActuatorScene):
        raise ProblemError(
            "the root-finding baseline models the pinned-pinned actuator only: scene must be "
            f"an ActuatorScene, got {describe(scene)}"
        )
    if method not in METHODS:
        raise ProblemError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    try:
        tol = float(tol)
    except (TypeError, ValueError) as exc:
        raise ProblemError(f"tol must be a number in (0, 1), got {tol!r}") from exc
    if not (np.isfinite(tol) and 0 < tol < 1):
        raise ProblemError(f"tol must be in (0, 1), got {tol:g}")
    if max_nfev is not None and not (
        isinstance(max_nfev, (int, np.integer)) and not isinstance(max_nfev, bool)
        and max_nfev >= 1
    ):
        raise ProblemError(f"max_nfev must be an integer >= 1 or None, got {max_nfev!r}")
    if time_limit is not None:
        try:
            time_limit = float(time_limit)
        except (TypeError, ValueError) as exc:
            raise ProblemError(f"time_limit must be a number of seconds > 0, got {time_limit!r}") \
                from exc
        if not (np.isfinite(time_limit) and time_limit > 0):
            raise ProblemError(f"time_limit must be > 0 s, got {time_limit:g}")
    return tol, time_limit


def _start(system: BaselineSystem, chain: Chain, x0) -> np.ndarray:
    if x0 is None:
        return system.initial(chain.rest_alpha)
    if isinstance(x0, BaselineResult):
        if x0.links != chain.links:
            raise ProblemError(f"x0 has {x0.links} links, the scene {chain.links}")
        return system.initial(np.asarray(x0.alpha, float), x0.reaction)
    try:
        alpha = np.asarray(x0, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ProblemError("x0 must be None, N link angles (rad) or a BaselineResult") from exc
    if alpha.shape != (chain.links,) or not np.all(np.isfinite(alpha)):
        raise ProblemError(
            f"x0 must be {chain.links} finite link angles (rad), got shape {alpha.shape}"
        )
    return system.initial(alpha)


def _scipy_status(method: str, sol) -> str:
    """Map MINPACK's codes to the shared set."""
    code = int(sol.status)
    if sol.success:
        return "solved"
    if (method == "hybr" and code == 2) or (method == "lm" and code == 5):
        return "max evaluations"
    return "no convergence"


def solve_baseline(
    scene: ActuatorScene,
    *,
    tol: float = 1e-10,
    method: str = "hybr",
    x0=None,
    max_nfev: int | None = None,
    time_limit: float | None = None,
    jacobian: str = "analytic",
) -> BaselineResult:
    """Solve the paper's single-reaction nonlinear system (Appendix A) for a scene.

    Parameters
    ----------
    scene : ActuatorScene
        ``links="auto"`` is resolved by :func:`baseline_links`: the Sec. III-D
        rule on the baseline's own answers (the LCP path never picks its N). A channel's lower wall is not part of the
        model; the answer is only ``valid`` if no node crosses it.
    tol : relative step tolerance handed to MINPACK (``xtol``; also ``ftol``
        for "lm"). The answer is accepted if the dimensionless residual is
        below max(1e-8, tol) and the geometry checks pass.
    method : "hybr" (Powell hybrid, fsolve-like; default) or "lm".
    x0 : None (the unconstrained arc, R = 0), N link angles (rad), or a
        previous :class:`BaselineResult` of the same N (warm start).
    max_nfev : limit on residual evaluations (None: MINPACK's default).
    time_limit : wall-clock limit (s) on the root finding.
    jacobian : "analytic" (exact, default) or "fd" (forward differences by
        MINPACK, what ``fsolve`` does unless given a Jacobian: the paper's
        baseline as it was most likely run).

    Returns
    -------
    BaselineResult
        Never raises on non-convergence; see ``converged``, ``valid``, ``status``.
    """
    tol, time_limit = _check_options(scene, method, tol, max_nfev, time_limit)
    if jacobian not in JACOBIANS:
        raise ProblemError(f"jacobian must be one of {', '.join(JACOBIANS)}, got {jacobian!r}")
    if scene.links == "auto":
        scene = scene.with_links(baseline_links(scene, method=method, jacobian=jacobian,
                                                tol=tol, time_limit=time_limit))
    t_setup = time.perf_counter()
    chain = scene.chain()
    system = BaselineSystem(chain, scene.height)
    z0 = _start(system, chain, x0)
    setup = time.perf_counter() - t_setup

    t0 = time.perf_counter()
    watched = _Watched(system, None if time_limit is None else t0 + time_limit)
    options: dict = {"xtol": tol}
    if method == "lm":
        options["ftol"] = tol
        if max_nfev is not None:
            options["maxiter"] = int(max_nfev)
    elif max_nfev is not None:
        options["maxfev"] = int(max_nfev)
    try:
        jac = watched.jac if jacobian == "analytic" else None
        sol = root(watched.fun, z0, jac=jac, method=method, options=options)
        z, status, message = sol.x, _scipy_status(method, sol), str(sol.message)
        # scipy's own counts (ours also include its shape-check call)
        watched.nfev = int(getattr(sol, "nfev", watched.nfev))
        watched.njev = int(getattr(sol, "njev", watched.njev))
    except _Stop as stop:
        z = watched.last if watched.last is not None else z0
        status, message = stop.status, stop.message
    elapsed = time.perf_counter() - t0
    out = _judge(scene, chain, system, watched, z, status, message, method, tol,
                 elapsed, setup)
    out.extra["jacobian"] = jacobian
    return out


def _judge(scene, chain, system, watched, z, status, message, method, tol, elapsed, setup):
    """Re-check scipy's answer on the exact geometry and build the result."""
    n = chain.links
    alpha, _, _, q1, qn, r = system.split(np.asarray(z, float))
    alpha = alpha.copy()
    reaction = float(r * system.fs)
    forces = (reaction * system.share)[1:-1]
    with np.errstate(all="ignore"):
        res = system.residual(z)
        x, y = node_positions(chain, alpha)
        tr = torque_residual(chain, alpha, -forces)
    residual_norm = float(np.max(np.abs(res))) if np.all(np.isfinite(res)) else float("inf")
    finite = np.all(np.isfinite(z)) and np.all(np.isfinite(y))
    h = scene.height
    closure = abs(float(y[-1]))
    midspan = float(y[system.mid] - h)
    above = y[1:-1] - h
    below = -h - y[1:-1] if scene.channel else np.full(n - 1, -np.inf)
    beyond = np.maximum(above, below)
    penetration = float(np.max(beyond))
    rel_torque = float(np.max(np.abs(tr))) / (system.fs * system.ell) if finite else float("inf")
    geom_tol = max(GEOMETRY_TOL_MM, tol * chain.length)

    converged = status == "solved"
    if converged and not finite:
        converged, status, message = False, "diverged", "the answer is not finite"
    if converged:
        problems = []
        if residual_norm > max(RESIDUAL_TOL, tol):
            problems.append(f"residual {residual_norm:.1e}")
        if closure > geom_tol:
            problems.append(f"chain not closed on the right pin by {closure:.1e} mm")
        if abs(midspan) > geom_tol:
            problems.append(f"midspan node {midspan:+.1e} mm off the wall")
        if rel_torque > max(RESIDUAL_TOL, tol) * 100:
            problems.append(f"torque residual {rel_torque:.1e} (relative to EI/l)")
        if problems:
            converged = False
            status = "bad solution: " + problems[0]
            message = "scipy reported success but " + ", ".join(problems)
    valid = converged
    if converged:
        problems = []
        for name, gap in (("the wall", above), ("the lower wall", below)):
            if np.max(gap) > geom_tol:
                problems.append(f"penetrates {name}: {int(np.sum(gap > geom_tol))} nodes, up to "
                                f"{float(np.max(gap)):.3g} mm beyond")
        if reaction < 0:
            problems.append(f"the wall pulls (R = {reaction:.3g} N < 0)")
        if problems:
            valid = False
            status = "bad solution: " + problems[0].split(":")[0]
            message = ("the single-reaction equations are solved but the shape is not a contact "
                       "answer: " + "; ".join(problems))
        else:
            message = f"solved ({message})"
    return BaselineResult(
        scene=scene,
        links=n,
        method=method,
        alpha=alpha,
        reaction=reaction,
        forces=forces,
        total_force=float(np.sum(forces)),
        converged=bool(converged),
        valid=bool(valid),
        status=status,
        message=message,
        iterations=watched.nfev,
        jacobian_evaluations=watched.njev,
        time_s=elapsed,
        residual_norm=residual_norm,
        x=x,
        y=y,
        support=(float(q1 * system.fs), float(qn * system.fs)),
        max_penetration=penetration,
        closure=closure,
        midspan_error=midspan,
        relative_torque_residual=rel_torque,
        setup_time_s=setup,
    )


def baseline_links(scene: ActuatorScene, *, threshold: float = 0.01, method: str = "hybr",
                   jacobian: str = "analytic", tol: float = 1e-10,
                   time_limit: float | None = None) -> int:
    """The baseline's own N: the Sec. III-D rule (refine N by 10 until the total
    force changes by less than ``threshold`` percent) on its own answers.

    Raises ProblemError when the baseline has no valid answer at some N (its
    single-reaction model does not fit the scene).
    """

    def total_force(s):
        res = solve_baseline(s, method=method, jacobian=jacobian, tol=tol,
                             time_limit=time_limit)
        if not (res.converged and res.valid):
            raise ProblemError(f"baseline_links: the baseline has no valid answer at "
                               f"links={s.links} ({res.status}: {res.message})")
        return res.total_force

    return auto_links(scene, threshold=threshold, total_force=total_force)
