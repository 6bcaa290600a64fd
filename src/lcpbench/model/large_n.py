"""Large N: the contact step in increments, on the tridiagonal factor of H.

Two things limit the height formulation of the step (:mod:`.step`) at large N:

1. **Forming H = Jᵀ diag(k) J squares the conditioning of J.** cond(H) grows
   as N⁴; at N ≈ 7,000 one refinement of the dual active set no longer
   reaches round-off (the judge sees reactions of −2.7 EI/ℓ² where the active
   set certified zero), and near N = 3·10⁴ the banded Cholesky of the rounded
   H fails. The face solves here use J itself
   (:class:`lcpbench.linalg.saddle.TridiagonalFactor`): error ~ cond(J) ε ~ N² ε.
2. **Heights rounded to doubles carry force.** A reaction is a second
   difference of the joint moments, which are second differences of the
   heights: R ~ 16 EI δu / a³. Heights of a few mm rounded to ε give
   δR ~ 1e-5 N at N = 10⁴ and ~1e-2 N (a few % of the paper scene's force)
   at N = 10⁵. So the step here is written in *increments* d = u − u₀ about
   the linearisation point (whose joint angles come from α, not from
   heights), and the driver moves α by exact inverse kinematics of the
   increments, sin α'_i = sin α_i + (d_{i+1} − d_i)/a (:func:`trial_of`):
   round-off then scales with the increment and with ε·k/a² per node, not with
   the heights.

The same minimisation, the same walls and the same Armijo search as the
globalised driver (:mod:`.driver`); only the unknown (increments, not
heights) and the face solves differ. The driver is :mod:`.large_driver`;
the result judge (:mod:`.judge`) takes its own judge step the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..linalg.twisted import TwistedFactor
from ..problems.scenes import Chain
from .chain import joint_arrays
from .elastic import compliances
from .step import ContactStep, residuals_of


def _kernel():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.model.large_kernel")

#: links from which :func:`lcpbench.solve` and the judge use this formulation
#: (below it the Cholesky of H is accurate: one refinement contracts by
#: cond(H) ε ≈ 1e-2 at N = 4000, 0.26 at N = 7000)
LARGE_N = 4000


def layout_fits(chain: Chain) -> bool:
    """J is square and tridiagonal: joint j joins links j, j + 1 and bends at free node j
    (both ends pinned, as an actuator section)."""
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]
    f = chain.free_nodes
    n = f.size
    return bool(n >= 3 and right.size == n and np.array_equal(f, np.arange(1, n + 1))
                and np.array_equal(right, np.arange(1, n + 1))
                and np.array_equal(left, np.arange(n)) and chain.links == n + 1)


def takes(chain: Chain) -> bool:
    """Whether the increment formulation takes the chain at all: :func:`layout_fits`.
    Every wall model is a parameter of its assembly (:func:`increments_at`): rigid or
    elastic walls (their springs in the step's face solves,
    :mod:`lcpbench.solvers.spring_newton`), flat or of any profile (the walls at the
    nodes' x and the lagged slope load, :mod:`.large_driver`)."""
    return layout_fits(chain)


def applies(chain: Chain) -> bool:
    """Whether solves and the judge use the increment formulation: N >= LARGE_N, or a
    chain marked ``increments`` (:func:`roundoff_limited`), that it :func:`takes`."""
    return (chain.links >= LARGE_N or chain.increments) and takes(chain)


def heights_condition(links: int) -> float:
    """cond H of the height formulation, (2N/π)⁴: H ∝ (LM)², whose tridiagonal factor LM
    (second differences) has eigenvalues 4 sin²(jπ/2N), from ≈ π²/N² to 4."""
    return (2.0 * links / np.pi) ** 4


def roundoff_may_limit(chain: Chain, tau: float, method: str) -> bool:
    """Whether the round-off of node heights may keep an answer from a relative force
    accuracy τ, where increments would not: cond H · ε (:func:`heights_condition`)
    reaches τ, and the increment formulation takes the chain (:func:`takes`) and the
    scheme (``method``: the globalised one, which it runs) but is not used already.

    cond H · ε is what round-off can do to a height step, an upper estimate: on the
    paper scene the forces of the height answers are 10⁻⁴–10⁻³ of it off (1.6·10⁻⁷ F₀
    at N = 3000, 6.6·10⁻¹⁰ F₀ at N = 500)."""
    return (method == "globalised"
            and heights_condition(chain.links) * np.finfo(float).eps >= tau
            and not applies(chain) and takes(chain))


def roundoff_limited(chain: Chain, judgement, method: str) -> bool:
    """Whether an answer in node heights that the judge did not certify may have been
    kept from it by round-off (:func:`roundoff_may_limit` at its τ), so that the same
    solve in increments (whose round-off grows as N², not N⁴) is worth a try: the judge
    did not accept, but the driver converged (its steps stopped moving α). As
    cond H · ε is an upper estimate, a retry is tried in more cases than it is needed
    in; it runs only where the judge rejected the answer."""
    return (not judgement.converged and "driver" not in judgement.failed
            and roundoff_may_limit(chain, judgement.force_tol, method))


@dataclass
class IncrementStep(ContactStep):
    """The step in increments d = u − u₀: the QP of
    :func:`~lcpbench.model.compiled_driver.assemble_step` moved to the origin (its linear
    term the factored gradient at u₀, from the joint angles of α, no cancellation; its
    walls the gaps of u₀; its face solves on the twisted tridiagonal factor,
    :class:`~lcpbench.linalg.twisted.TwistedFactor`), assembled by one compiled pass
    (:func:`increments_at`), with the factored gradient and its term sizes compiled
    (:mod:`.large_kernel`). ``heights``: u₀, the free nodes' heights at α (mm)."""

    heights: np.ndarray | None = None

    def __post_init__(self):  # its own gradient's work row (not ContactStep's arguments)
        self._m = np.empty(self.size)

    def __getattr__(self, name: str):
        """``v`` and ``phi0``, computed on first use (:func:`increments_at` leaves them)."""
        tangent = self.__dict__.get("_tangent")
        if name in ("v", "phi0") and tangent is not None:
            v, phi0 = tangent
            _kernel().tangent_terms(self.alpha, v, phi0)
            self.v, self.phi0 = v, phi0
            del self._tangent
            return getattr(self, name)
        raise AttributeError(name)

    def gradient(self, u: np.ndarray) -> np.ndarray:
        g = np.empty(self.size)
        _kernel().gradient(self.coef, self.stiffness, self.phi_origin, self.rest_joint,
                           self.nodal_load, self.origin, self._heights(u), g, self._m)
        return g

    def gradient_scale(self, u: np.ndarray) -> np.ndarray:
        g = np.empty(self.size)
        _kernel().gradient_scale(self.coef, self.stiffness, self.phi_origin, self.rest_joint,
                                 self.nodal_load, self.origin, self._heights(u), g, self._m)
        return g


    def compiled_residuals(self, u: np.ndarray):
        """step_residuals' ``(residuals, R)`` in one compiled call
        (:func:`~lcpbench.model.large_kernel.residuals`, independent of the walk; at
        elastic walls the compliant gaps g + R/k), or None (the numpy reference
        decides)."""
        none = np.empty(0)
        cu, cl = (np.ascontiguousarray(c, dtype=float) for c in compliances(self)) \
            if self.elastic else (none, none)
        ok, res, R = _kernel().residuals(
            np.ascontiguousarray(u, dtype=float), self.coef, self.stiffness, self.phi_origin,
            self.rest_joint, self.nodal_load, self.origin, self.factor.rows, self.bands,
            self.linear, self.lower, self.upper, cu, cl, float(self.length_scale),
            float(self.force_scale))
        if not ok:
            return None
        return residuals_of(res), R

    def walk_refine(self, S: np.ndarray, u: np.ndarray, rounds: int = 4):
        """``(u, g)``: the dual walk's refinement at an optimum (``u`` on the walls on S)
        in one compiled call on the face its twisted factor holds
        (:func:`~lcpbench.model.large_kernel.walk_refine`: the arithmetic of
        :func:`lcpbench.solvers.compiled_walk.dual_walk` and
        :func:`lcpbench.solvers.compiled_walk.refine_on_face`)."""
        H = self.factor
        return _kernel().walk_refine(self.coef, self.stiffness, self.phi_origin,
                                     self.rest_joint, self.nodal_load, self.origin, H.R, H.B,
                                     H._tri, H._inv, H._invB, H._m,
                                     np.ascontiguousarray(S, dtype=np.bool_),
                                     np.ascontiguousarray(u, dtype=float), int(rounds))

    def solve_on(self, idx: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """H[idx, idx]⁻¹ rhs. Few nodes: by the independent blocks of ``idx``, O(|idx|)
        (compiled: :func:`~lcpbench.model.large_kernel.descend`; the step judge re-solves
        the ~20 % of the nodes that no wall reaches at every step). Many nodes: the
        whole factor."""
        idx = np.ascontiguousarray(idx, dtype=np.int64)
        n = self.size
        if idx.size * 2 > n:
            return super().solve_on(idx, rhs)
        grad, d = np.zeros(n), np.full(n, -0.0)  # −(−0 − x) is x, a zero's sign too
        grad[idx] = rhs
        if not _kernel().descend(self.factor.rows, idx, grad, d):
            raise np.linalg.LinAlgError("a face of H is singular (zero pivot)")
        return -d[idx]


def _chain_arrays(chain: Chain) -> tuple:
    """The chain's arrays the compiled assembly reads (kept with the chain)."""
    def make():
        f64 = np.ascontiguousarray
        k = f64(chain.joint_stiffness, dtype=float)
        return (k, f64(chain.rest_joint, dtype=float),
                f64(chain.nodal_load, dtype=float), f64(chain.lower, dtype=float),
                f64(chain.upper, dtype=float), f64(chain.link_load, dtype=float),
                np.arange(chain.links, dtype=np.int64), np.sqrt(k))

    return chain.derived("_large_arrays", make)


class StepWork:
    """The arrays of one :func:`increments_at` step (and its twisted factor's state), to
    be written again by a later step (the large-N driver's outer steps: at N = 10⁵
    fresh arrays cost ~5,000 page faults a step). The next step's assembly overwrites
    this step: never use one for two steps that are read together."""

    def __init__(self, links: int):
        nl, n = links, links - 1
        e = np.empty
        self.link = (e(nl), e(nl), e(nl), e(nl))  # inv_a_cos, v, alpha0, sin α
        self.rows3 = (e((n, 3)), e((n, 3)), e((n, 3)))  # coef, rows, rrows
        self.node = tuple(e(n) for _ in range(7))  # phi0, origin, phi_origin, linear, lo, hi,
        # work
        self.bands = e((3, n))
        self.factor_state: dict = {}  # TwistedFactor.from_rows's arrays, once made


def increments_at(chain: Chain, alpha: np.ndarray, work: StepWork | None = None, *,
                  walls: tuple[np.ndarray, np.ndarray] | None = None,
                  load: np.ndarray | None = None) -> IncrementStep:
    """The step in increments at α (:class:`IncrementStep`) in one compiled pass (a chain
    of :func:`applies`), its face solves on the twisted factor. ``work``:
    the arrays to write (:class:`StepWork`; default: new ones). A wall profile's step
    (the large-N driver's, :mod:`lcpbench.model.large_driver`) gives ``walls`` = (lower, upper), the
    profile at the nodes' x, and ``load``, the nodal load f plus the slope load s of
    the lagged reactions; elastic walls' springs ride on the chain."""
    k, rest, load0, lower, upper, _, base, sk = _chain_arrays(chain)
    if walls is not None:
        lower, upper = (np.ascontiguousarray(w, dtype=float) for w in walls)
    load = load0 if load is None else np.ascontiguousarray(load, dtype=float)
    alpha = np.array(alpha, dtype=float)
    nl = alpha.size
    if work is None:
        work = StepWork(nl)
    inv_a_cos, v, alpha0, sin_alpha = work.link
    coef, rows, rrows = work.rows3
    phi0, origin, phi_origin, linear, lo, hi, tmp = work.node
    bands = work.bands
    n = nl - 1
    _kernel().assemble_into(alpha, float(chain.link_length), k, sk, rest, load, lower, upper,
                            inv_a_cos, coef, origin, alpha0, phi_origin, bands,
                            linear, lo, hi, rows, rrows, sin_alpha, tmp)
    step = IncrementStep(
        bands=bands, linear=linear, lower=lo, upper=hi, alpha=alpha, inv_a_cos=inv_a_cos,
        v=None, free_nodes=chain.free_nodes, links=chain.links, base=base[1:n + 1], coef=coef,
        phi0=None, origin=np.full(n, 0.0), alpha0=alpha0, phi_origin=phi_origin,
        stiffness=k, rest_joint=rest, nodal_load=load, length_scale=chain.length,
        force_scale=chain.force_scale, upper_stiffness=chain.upper_stiffness,
        lower_stiffness=chain.lower_stiffness,
        factor=TwistedFactor.from_rows(rows, rrows, state=work.factor_state), heights=origin)
    step.sin_alpha = sin_alpha
    # v and phi0 (a tan per link) on first use: the steps in increments never read them
    step._tangent = (v, phi0)
    del step.v, step.phi0
    return step


def trial_of(chain: Chain, alpha: np.ndarray, du: np.ndarray, step: IncrementStep | None = None):
    """``t -> (α', E(α'))`` moved by t·du (sin α'_i = sin α_i + t(du_(i+1) − du_i)/a, each link
    on its branch and winding, and the chain's
    energy without walls, :func:`lcpbench.model.chain.energy`, in one compiled pass);
    ``(None, nan)`` where no chain fits. ``step``: the step assembled at this α
    (:func:`increments_at`), whose sin α and sign of cos α it reuses (the same numbers)."""
    jl, jr, k, rest, link_load = joint_arrays(chain)
    kern = _kernel()
    a = float(chain.link_length)
    alpha = np.ascontiguousarray(alpha, dtype=float)
    du = np.ascontiguousarray(du, dtype=float)
    sin_alpha = getattr(step, "sin_alpha", None)
    if sin_alpha is not None and not np.array_equal(step.alpha, alpha):
        sin_alpha = None

    def at(t: float):
        out = np.empty(alpha.size)
        if sin_alpha is not None:
            E = kern.trial_energy_at(alpha, sin_alpha, step.inv_a_cos, du, float(t), a, jl, jr,
                                     k, rest, link_load, out)
        else:
            E = kern.trial_energy(alpha, du, float(t), a, jl, jr, k, rest, link_load, out)
        return (None, E) if np.isnan(E) else (out, E)

    return at
