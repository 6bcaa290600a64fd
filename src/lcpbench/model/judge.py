"""The result judge: when lcpbench calls a contact result converged.

:mod:`lcpbench.solvers.judge` decides whether one contact step is SOLVED. This
module decides whether a whole answer — the final link angles α and the wall
reactions R (eq. 30) — is the equilibrium of the scene to the accuracy asked
for. Every back-end's answer goes through the same checks, computed by
lcpbench from the primal unknowns; a back-end's own word (its status, its
multipliers) is never enough.

The accuracy asked for is the report's success rule (docs/bench.md): a
relative error of the total reaction F = ΣR of at most

    τ = force_tol(tol) = min(1e-3, 100 · tol),

measured in the force unit F₀ = max(|F|, EI/ℓ²), so that a scene without
contact (F = 0) is judged too. Lengths are measured in the section length ℓ.

``converged`` requires all of the following; an answer that misses one is
``converged=False`` with a reason naming the check. Nothing is relabelled.

1. **driver**: the outer iteration stopped by its criterion max|Δα| < tol.
2. **last step**: the contact step whose reactions are reported was SOLVED by
   lcpbench's residuals (not INACCURATE). Earlier steps may be inexact: they
   only move the iterate, which the line search and the checks below judge;
   their count is kept in the judgement (``inexact_steps``).
3. **sign**: min R ≥ −ε_R, no wall pulls (ε_R = NODE_SHARE · τ · F₀, or the
   round-off of R = K g + z, 256 ε S with S the size of its terms, if larger).
4. **complementarity**: at every node, min(R_i/F₀, g_i/ℓ) ≤ NODE_SHARE · τ:
   a node that carries a reaction touches its wall.
5. **penetration**: min g ≥ −min(1e-6, NODE_SHARE · τ) · ℓ on the exact
   geometry; at an elastic wall also the indentation that the reactions'
   tolerance ε_R leaves open, ε_R/k (a soft wall's compliant gap g + R/k is
   a difference of two large lengths, known only as well as R).

At an elastic wall (:mod:`lcpbench.model.elastic`) g is the compliant gap
g + R/k in checks 4 and 5 (a node indents the wall by exactly R/k), and the
judge step holds a node in contact by the wall's spring instead of on it.
6. **closure, torque**: the exact-geometry certificate
   (:class:`Certificate`, computed by :mod:`lcpbench.model.judge_checks`): the right
   pin on y = 0 to 1e-6 ℓ, the joint torques in balance to max(10 tol, 1e-6) of the
   spring torques (TORQUE_PER_RAD, TORQUE_FLOOR).
7. **force error bound**: lcpbench takes contact steps itself, solved exactly by
   block principal pivoting, independent of every back-end
   (:mod:`lcpbench.model.judge_kernel`; in increments
   :mod:`lcpbench.model.judge_exact_kernel`):
   the *judge step* at the final α from the answer's contact set (forces F_{k+1}),
   and a second one at α₁, where the first moves the chain, from the first's contact
   set (F_{k+2}). If the answer's forces are F_k and the outer iteration contracts
   linearly by ρ per step, F_k − F* ≈ (F_k − F_{k+1}) / (1 − ρ), and
   |F_k − F*| ≤ |F_k − F_{k+1}| + |F_{k+1} − F_{k+2}| / (1 − ρ'). The bound is the
   smaller of the two estimates (:mod:`lcpbench.model.judge_bound`),

       force_error_bound = min(|F_k − F_{k+1}| / (1 − ρ),
                               |F_k − F_{k+1}| + |F_{k+1} − F_{k+2}| / (1 − ρ')) / F₀
                           + round-off (of the one judge step, or of both),

   with ρ from the driver's last two step sizes and the first judge step's, ρ' the
   judge's second step size over its first, each at least ½, at most 0.99 (the
   driver's ρ is pessimistic for a back-end whose last steps carry its own
   inaccuracy; the judge's steps contract at the exact outer step's rate). The
   second step is taken only where the one-step estimate exceeds τ (it can only
   lower the bound, so the verdict is the same without it; ρ' is then NaN); if it
   does not settle, the one-step estimate alone. Per node
   (max_i |R_i − R'_i|) the one-step estimate, κ = 1/(1 − ρ) times it, on which
   the per-node threshold is set. The total must be at most τ and, per node, the
   largest of NODE_FACTOR·τ, NODE_GROSS (5 % of
   F₀: node forces converge more slowly than their sum) and NODE_FACTOR times
   the round-off of a reaction, 256 ε S. This
   is an a-posteriori estimate under linear contraction, not a proof: it is
   what turns "α stopped moving" into "F is within τ".

8. **stability**: the equilibrium is a local minimum of the exact energy on its
   contact set: the Hessian of the Lagrangian has no negative curvature on the
   tangent space of the nodes held by a wall (reaction above ε_R; the others are
   left free, which can only refuse more) and of the right pin's closure
   (:mod:`lcpbench.model.stability_kernel`, an O(N) inertia count). A saddle,
   which passes every first-order check above, is refused here.

With a wall profile y = h(x) (:mod:`lcpbench.model.profile`) the checks are
those of the exact profile problem: gaps h(x_k) − y_k at the nodes' x,
torques with the normal reactions μ (h', −1) (their horizontal parts taken
by the fixed left pin), and a judge step with the answer's reactions as its
lagged multipliers.

The contact set reported with a result counts nodes whose reaction exceeds
ε_R (so no 5e-10 N "contacts"). Every threshold is in :data:`THRESHOLDS` and
docs/solvers.md; their values in :mod:`lcpbench.thresholds`.

**Where the numbers come from.** This module is the rules' Python face: the
:class:`Judgement`, its reasons (:func:`failed_checks`) and the thresholds. Every
number it judges by comes from compiled functions, called from Python through
:func:`lcpbench.numba_cache.kernel_module` (``NUMBA_DISABLE_JIT=1`` runs the same
functions as plain Python, the debugging path): the judge kernel
(:mod:`lcpbench.model.judge_kernel`: its own assembly and exact steps),
the certificate and checks 3-6 and 8 (:mod:`lcpbench.model.judge_checks`), the force
error bound (:mod:`lcpbench.model.judge_bound`) and the stability check
(:mod:`lcpbench.model.stability_kernel`). The kernel takes its exact steps in node
heights; where the solve is in increments (from ``LARGE_N`` links, or a chain marked
``increments``) the same kernel takes them in increments (its entry
``judge_in_increments``), on their twisted tridiagonal factor
(:func:`lcpbench.model.judge_exact_kernel.increments_step`), and the same
certificate, checks and bound follow. The judge shares no code with the solve kernel:
it checks the answer, it does not repeat the solve.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ..numba_cache import kept
from ..problems.scenes import Chain
from ..thresholds import (  # the rule's numbers, read by the judge kernel too
    FORCE_TOL_CAP,
    FORCE_TOL_PER_RAD,
    GEOMETRY_TOL,
    NODE_SHARE,
)
from . import large_n
from .profile import (
    split_reactions,  # noqa: F401 (public here)
    wall_rows,
)

#: friction (issue 39): a node slides when its slip |s| > max(SLIP_FACTOR · tol · a,
#: SLIP_FLOOR · ℓ) (a = ℓ/N; the floor: ten times Lemke's accepted residual on the
#: dimensionless step, what a SOLVED step leaves on a slip)
SLIP_FACTOR, SLIP_FLOOR = 10.0, 1e-7

THRESHOLDS = {
    "force_tol": "min(1e-3, 100·tol), relative to F₀ = max(|F|, EI/ℓ²)",
    "last step": "SOLVED by lcpbench's residuals",
    "sign": "min R >= -max(NODE_SHARE·τ·F₀, FLOOR_ULPS·ε·S)",
    "complementarity": "max_i min(R_i/F₀, g_i/ℓ) <= NODE_SHARE·τ",
    "penetration": "min g >= -min(GEOMETRY_TOL, NODE_SHARE·τ)·ℓ",
    "closure": "|y_right| <= GEOMETRY_TOL·ℓ",
    "torque": "relative torque residual <= max(TORQUE_PER_RAD·tol, TORQUE_FLOOR)",
    "force_error_bound": "<= τ for F; per node <= max(NODE_FACTOR·τ, NODE_GROSS, "
                         "NODE_FACTOR·FLOOR_ULPS·ε·S/F₀)",
    "contact": "R_i > NODE_SHARE·τ·F₀",
    "stability": "no negative curvature of the energy on the contact set (R_i > ε_R held)",
    "cone": "friction: |T_i| <= μ N_i + NODE_SHARE·τ·F₀ (F₀ also >= |pull|)",
    "slip": "friction: |s_i| > ε_s = max(SLIP_FACTOR·tol·a, SLIP_FLOOR·ℓ): μ N_i − |T_i| "
            "and T_i·sign(s_i) <= NODE_SHARE·τ·F₀; inside the cone by more: |s_i| <= ε_s",
    "x balance": "friction, no end holding x: |ΣT + pull| <= NODE_SHARE·τ·F₀",
}


def force_tol(tol: float) -> float:
    """τ: the relative force error a result at driver tolerance ``tol`` (rad) may have,
    min(1e-3, 100·tol). 1e-3 is the paper's agreement criterion (Fig. 26); 100·tol
    is what an exact step solver reaches at driver tolerance tol."""
    return min(FORCE_TOL_CAP, FORCE_TOL_PER_RAD * float(tol))


@dataclass
class Certificate:
    """How well a configuration and its reactions satisfy the exact problem.

    Computed from the final link angles by exact forward kinematics and
    statics — not from the linearised step — so it says the same thing
    whichever back-end or scheme produced the answer.

    Attributes
    ----------
    min_gap : smallest distance of any node to a wall (mm); < 0 is penetration.
        At an elastic wall the compliant gap g + R/k (0 for a node in contact).
    min_force : smallest reaction (N); < 0 would be a wall pulling.
    complementarity : largest |g_i R_i| over the nodes (N·mm).
    closure : |y| of the right pin, which must lie on y = 0 (mm); 0 for a free end.
    torque_residual : per joint, spring torque k(φ − φ*) minus the moment the
        forces demand (N·mm).
    max_torque_residual : its largest magnitude (N·mm).
    relative_torque_residual : that, over the largest spring torque (at least EI/ℓ).
    """

    min_gap: float
    min_force: float
    complementarity: float
    closure: float
    torque_residual: np.ndarray
    max_torque_residual: float
    relative_torque_residual: float

    def to_dict(self) -> dict:
        d = asdict(self)
        d["torque_residual"] = self.torque_residual.tolist()
        return d


@dataclass
class Judgement:
    """The verdict on one answer, with the numbers behind it.

    ``force_error_bound`` is relative to ``force_unit`` F₀ (NaN when the judge
    did not get that far); ``failed`` names the checks that failed.
    """

    converged: bool
    reason: str
    force_tol: float
    force_unit: float
    force_error_bound: float = float("nan")
    node_error_bound: float = float("nan")
    contraction: float = float("nan")
    #: ρ' of the two-step bound: the judge's second step size over its first (NaN: the
    #: second step did not settle, or the judge did not get that far)
    judge_contraction: float = float("nan")
    contact_threshold: float = 0.0
    judge_total_force: float = float("nan")
    judge_rounds: int = 0
    inexact_steps: int = 0
    #: negative-curvature directions of the energy on the contact set (the second-order
    #: check, :mod:`lcpbench.model.stability_kernel`): 0 a stable equilibrium; None
    #: not checked (a joint layout the check does not take)
    unstable_directions: int | None = None
    failed: list[str] = field(default_factory=list)
    # the answer's reactions with round-off set to zero (None: not judged that far)
    forces_upper: np.ndarray | None = field(default=None, repr=False)
    forces_lower: np.ndarray | None = field(default=None, repr=False)
    certificate: Any = field(default=None, repr=False)  # the Certificate it judged

    def to_dict(self) -> dict:
        d = asdict(self)
        for key in ("forces_upper", "forces_lower", "certificate"):
            d.pop(key)
        return d


def _kernel():
    """The judge kernel's module (numba imported, the kernel loaded, at the first call)."""
    return kept(_KERNEL, "lcpbench.model.judge_kernel", "judge_answer")


_KERNEL: list = []  # the kernel module, once loaded (emptied by numba_cache.use_aot)


def _bound_kernel():
    """The compiled force error bound (:mod:`lcpbench.model.judge_bound`), numba at the
    first call."""
    from ..numba_cache import kernel_module

    return kernel_module("lcpbench.model.judge_bound", "force_error_bound")


def contraction_estimate(step_sizes: list[float], judge_dalpha: float) -> float:
    """ρ from the last step sizes: the larger of the last two ratios, in [½, 0.99]
    (:func:`lcpbench.model.judge_bound.contraction`; sizes below STEP_NOISE rad, the
    round-off of an angle, are left out)."""
    return float(_bound_kernel().contraction(np.asarray(step_sizes, dtype=float),
                                             float(judge_dalpha)))


def takes(chain: Chain) -> bool:
    """Whether the judge kernel takes this chain: consecutive joints, contiguous free
    nodes (the solve kernel's layouts, :func:`lcpbench.model.kernel_call.applies`), flat
    walls or walls of a profile with a table of cubic pieces."""
    from .kernel_call import applies, profile_applies

    return applies("auto", "globalised", chain) or profile_applies("auto", "globalised", chain)


def judged_in(chain: Chain) -> str:
    """Where :func:`judge` takes its exact steps: "increments"
    (:func:`lcpbench.model.judge_exact_kernel.increments_step`, from ``LARGE_N`` links or a
    chain marked ``increments``), else "heights"; the result's ``judge`` field. The one
    judge kernel takes either."""
    return "increments" if large_n.applies(chain) else "heights"


def chain_args(chain: Chain, kernel_args: tuple | None = None) -> tuple:
    """The chain's arrays in the order :func:`judge_kernel.judge_answer` takes them
    (``kernel_args``: the solve kernel's, :func:`lcpbench.model.kernel_call.kernel_args`,
    when the caller has them: the same arrays, so none is copied twice)."""
    if kernel_args is None:
        from .kernel_call import kernel_args as solve_args

        kernel_args = solve_args(chain)
    args = (*kernel_args[1:], float(chain.wall), bool(chain.channel))
    if chain.profiled_walls:  # (judge_walls: the walls' tables after these)
        from .kernel_call import profile_args

        return (*args, *profile_args(chain)[4:8])
    return args


_contiguous = np.ascontiguousarray
_NO_TABLES = (np.zeros(0), np.zeros((4, 0)), np.zeros(0), np.zeros((4, 0)))  # flat walls


def judge(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
          forces_lower: np.ndarray, *, tol: float, driver_converged: bool,
          driver_reason: str, step_statuses: list[str], step_sizes: list[float],
          certificate, args: tuple | None = None) -> Judgement:
    """Judge an answer: link angles ``alpha`` and reactions R (N) on the free nodes.

    ``step_statuses`` are lcpbench's verdicts of the contact steps taken,
    ``step_sizes`` their max|Δα|; ``certificate`` the exact-geometry
    :class:`~lcpbench.model.result.Certificate` of the answer, or a callable
    ``(upper, lower) -> Certificate`` that the judge calls on the reactions it
    reports (round-off set to zero), used where the judge kernel does not make its
    own (a driver that did not converge, a chain it does not take); the one it used is
    ``judgement.certificate``. ``args``: the chain's :func:`chain_args`, when the
    caller has them already.
    """
    increments = large = large_n.applies(chain)
    if increments and chain.profiled_walls:
        from .kernel_call import profile_args

        increments = profile_args(chain) is not None  # (the walls' tables: the checks')
    if not driver_converged or not (increments or args is not None or takes(chain)):
        return _unjudged(chain, forces_upper, forces_lower, tol=tol,
                         driver_converged=driver_converged, driver_reason=driver_reason,
                         certificate=certificate)
    k = _kernel()
    if args is None:
        args = chain_args(chain)
    f64 = _contiguous
    answer = (f64(forces_upper, dtype=float), f64(forces_lower, dtype=float), float(tol),
              np.array(step_sizes, dtype=float))
    if large or len(args) > 16:  # (flat walls: empty tables)
        tables = _NO_TABLES if len(args) == 16 else ()
        entry = k.judge_in_increments if large else k.judge_walls
        code, st, fu, fl, res = entry(f64(alpha, dtype=float), *args, *tables, *answer)
    else:
        code, st, fu, fl, res = k.judge_answer(f64(alpha, dtype=float), *args, *answer)
    return verdict_from_stats(code == k.SETTLED, dict(zip(k.STATS, st.tolist(), strict=True)),
                              fu, fl, res, tol=tol, driver_reason=driver_reason,
                              step_statuses=step_statuses)


def verdict_from_stats(settled: bool, s: dict, fu: np.ndarray, fl: np.ndarray,
                       torque_residual: np.ndarray, *, tol: float, driver_reason: str,
                       step_statuses: list[str]) -> Judgement:
    """The Judgement (and its Certificate) from the judge kernel's numbers (``s``: its
    ``stats`` by name, :data:`lcpbench.model.judge_kernel.STATS`), check by check."""
    tau, F0 = s["tau"], s["F0"]
    verdict = Judgement(False, driver_reason, tau, F0, contact_threshold=s["eps_R"])
    if settled:
        verdict.forces_upper, verdict.forces_lower = fu, fl
    cert = Certificate(min_gap=s["min_gap"], min_force=s["min_force"],
                       complementarity=s["complementarity"], closure=s["closure"],
                       torque_residual=torque_residual,
                       max_torque_residual=s["max_torque_residual"],
                       relative_torque_residual=s["relative_torque_residual"])
    verdict.certificate = cert
    verdict.inexact_steps = sum(st != "solved" for st in step_statuses)
    unstable = s["unstable"]
    verdict.unstable_directions = int(unstable) if math.isfinite(unstable) else None
    if settled:
        verdict.force_error_bound, verdict.node_error_bound = s["total"], s["node"]
        verdict.contraction, verdict.judge_contraction = s["rho"], s["judge_rho"]
        verdict.judge_total_force = s["judge_total_force"]
        verdict.judge_rounds = int(s["rounds"])
    fails = failed_checks(settled, s, step_statuses, tol=tol)
    return settle_verdict(verdict, fails, driver_reason)


def _unjudged(chain: Chain, forces_upper: np.ndarray, forces_lower: np.ndarray, *,
              tol: float, driver_converged: bool, driver_reason: str,
              certificate) -> Judgement:
    """:func:`judge` where no judge step is taken: a driver that did not converge (check 1
    fails, the reason is the driver's) or a chain neither the judge kernel nor the judge
    in increments takes (refused); ``certificate`` (or its callable) is the one kept."""
    tau = force_tol(tol)
    F0 = max(abs(float(np.sum(forces_upper))), abs(float(np.sum(forces_lower))),
             chain.force_scale)
    verdict = Judgement(False, driver_reason, tau, F0, contact_threshold=NODE_SHARE * tau * F0)
    verdict.failed.append("driver" if not driver_converged else "layout")
    if driver_converged:
        verdict.reason = ("not accepted by lcpbench's judge: layout: the judge kernel does not "
                          "take this chain (joints or free nodes not consecutive, or a wall "
                          "profile without a table of cubic pieces)")
    verdict.certificate = (certificate(forces_upper, forces_lower) if callable(certificate)
                           else certificate)
    return verdict


def unstable_directions(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
                        forces_lower: np.ndarray, threshold: float) -> int | None:
    """The second-order check of an answer (:mod:`lcpbench.model.stability_kernel`):
    how many directions lower the energy on its contact set (0: stable), None where
    it does not apply (joints that are not neighbours)."""
    kern, args = stability_args(chain, alpha, forces_upper, forces_lower)
    code, unstable, _ = kern.unstable_directions(*args, float(threshold),
                                                 bool(chain.free_nodes[-1] < chain.links))
    return int(unstable) if code == kern.CHECKED else None


def stability_args(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
                   forces_lower: np.ndarray) -> tuple:
    """The stability kernel's module and the arguments of its ``unstable_directions``
    up to the threshold: the chain's arrays, the reactions, the walls' springs (inf:
    rigid) and their slopes and curvatures at the nodes' x (0: flat)."""
    from ..numba_cache import kernel_module  # numba at the first judgement

    kern = kernel_module("lcpbench.model.stability_kernel", "unstable_directions")
    n = len(forces_upper)
    rigid, flat = np.full(n, np.inf), np.zeros(n)
    # the walls' slopes and curvatures at the nodes' x (0 where a wall has no profile)
    _, _, _, _, h1, l1, h2, l2 = (wall_rows(chain, alpha) if chain.profiled_walls
                                  else (flat,) * 8)
    walls = [(rigid if stiffness is None else np.asarray(stiffness, float), slope, curve)
             for stiffness, slope, curve in ((chain.upper_stiffness, h1, h2),
                                             (chain.lower_stiffness, l1, l2))]
    (ku, su, cu), (kl, sl, cl) = walls
    f64 = np.ascontiguousarray
    return kern, (f64(alpha, dtype=float), float(chain.link_length),
                  f64(chain.joint_links[:, 0]), f64(chain.joint_links[:, 1]),
                  f64(chain.joint_stiffness, dtype=float), f64(chain.rest_joint, dtype=float),
                  f64(chain.link_load, dtype=float), int(chain.free_nodes[0]),
                  f64(forces_upper, dtype=float), f64(forces_lower, dtype=float), f64(ku),
                  f64(kl), f64(su), f64(sl), f64(cu), f64(cl))


def penetration_allowed(tau: float, L: float, eps_R: float, c_up: np.ndarray,
                        c_lo: np.ndarray) -> float:
    """Check 5's allowance (mm): min(GEOMETRY_TOL, NODE_SHARE τ) ℓ, plus ε_R times the
    largest compliance 1/k of an elastic wall (0 for rigid walls)."""
    c = max(float(np.max(c_up, initial=0.0)), float(np.max(c_lo, initial=0.0)))
    return min(GEOMETRY_TOL, NODE_SHARE * tau) * L + eps_R * c


def _rule_kernel():
    """The judge's rule, compiled (:mod:`lcpbench.model.batch_verdict`)."""
    from ..numba_cache import kernel_module

    return kernel_module("lcpbench.model.batch_verdict", "accepted")


def failed_checks(settled: bool, s: dict, step_statuses: list[str], *,
                  tol: float) -> list[str]:
    """The checks of :func:`judge` that fail, each as "check: why", in one order.

    Which checks fail the compiled rule decides
    (:func:`lcpbench.model.batch_verdict.failed`, as a batch line and the one-wall route
    do) on the judge's numbers ``s`` (by the names of
    :data:`lcpbench.model.judge_checks.STATS`; ``settled``: the judge step settled);
    check 2 is the last of ``step_statuses``. The text of each is written here.
    """
    rule = _rule_kernel()
    # (the judge kernel's STATS, judge_checks' own: its module is loaded for every
    # judge, where judge_checks' may never be called from Python, nor be ahead of time)
    stats = _kernel().STATS
    numbers = np.array([float(s[name]) for name in stats])
    mask = int(rule.failed(bool(settled), numbers, float(tol)))
    fails: list[str] = []
    if step_statuses and step_statuses[-1] != "solved":
        fails.append(f"last step: the contact step whose reactions are reported was "
                     f"{step_statuses[-1]} by lcpbench's residuals")
    comp, R_min, unstable = s["comp"], s["R_min"], s["unstable"]
    if mask & rule.FAILS_COMPLEMENTARITY:
        fails.append(f"complementarity: a node carries a reaction {comp:.1e} F₀ while "
                     f"{comp:.1e} ℓ from its wall (allowed {s['comp_allowed']:.1e})")
    if mask & rule.FAILS_PENETRATION:
        fails.append(f"penetration: {-s['min_gap']:.1e} mm through a wall "
                     f"(allowed {s['pen']:.1e} mm)")
    if mask & rule.FAILS_CLOSURE:
        fails.append(f"closure: the right pin is {s['closure']:.1e} mm off y = 0")
    if mask & rule.FAILS_TORQUE:
        fails.append(f"torque: relative torque residual {s['relative_torque_residual']:.1e}")
    if mask & rule.FAILS_SIGN:
        allowed_R = max(s["eps_R"], s["floor_R"])
        fails.append(f"sign: a wall pulls with {R_min:.2e} N (allowed down to "
                     f"{-allowed_R:.1e} N)")
    if mask & rule.FAILS_STABILITY:
        many = not unstable <= 1
        fails.append(f"stability: the answer is an unstable equilibrium (a saddle): "
                     f"{unstable:g} direction{'s' if many else ''} on its contact set "
                     f"lower{'' if many else 's'} the energy")
    if mask & rule.FAILS_UNSETTLED:
        fails.append("force error bound: the judge step did not settle")
    elif mask & rule.FAILS_TOTAL:
        fails.append(f"force error bound: the total force may be {s['total']:.1e} F₀ off "
                     f"(allowed {s['tau']:.1e}; one more exact step moves it to "
                     f"{s['judge_total_force']:.6g} N)")
    elif mask & rule.FAILS_NODE:
        fails.append(f"force error bound: a node's force may be {s['node']:.1e} F₀ off "
                     f"(allowed {s['node_allowed']:.1e})")
    return fails


def settle_verdict(verdict: Judgement, fails: list[str], driver_reason: str) -> Judgement:
    """The verdict with its failed checks: converged only if none failed."""
    verdict.failed = [f.split(":")[0] for f in fails]
    if fails:
        verdict.reason = "not accepted by lcpbench's judge: " + "; ".join(fails)
        return verdict
    verdict.converged = True
    verdict.reason = driver_reason
    return verdict
