"""The contact step, assembled from the energy of the chain (banded, O(N)).

At a configuration α the node heights are linearised as in eq. (20),

    α̂_i = (û_{i+1} − û_i) / (a cos α_i) − v_i,   v_i = tan α_i − α_i   (eq. 21),

so the joint angles φ̂ = J û + φ₀ are affine in the free node heights û and
the energy ½ Σ k (φ̂ − φ*)² − fᵀû is the quadratic

    ½ ûᵀ H û + cᵀ û,   H = Jᵀ diag(k) J,   c = Jᵀ k (φ₀ − φ*) − f.

Each joint touches three consecutive nodes, so H is pentadiagonal. In gap
coordinates g = h̄ − û this is the paper's LCP: K = H and z = −K h̄ − c
(eqs. 29–31). :mod:`lcpbench.reference.dense` assembles the same K and z
literally from eqs. (3)–(31); a test checks they agree.

The step is assembled once, compiled (:func:`lcpbench.model.compiled_driver.assemble_step`,
the kernel of :mod:`lcpbench.model.driver_kernel` that the solve kernel's assembly
is); this module holds the :class:`ContactStep` it fills, its methods (the gradient,
its term sizes and eq. 21's α̂: the solve kernel's, compiled) and its forms for the
back-ends (the compiled ones of :mod:`lcpbench.model.driver_kernel`).

A :class:`ContactStep` is the bound-constrained QP

    minimise ½ uᵀ H u + cᵀ u   subject to   lower <= u <= upper,

whose bounds are the walls (±inf where a node cannot reach a wall). Its
multipliers are the reactions. It can also state itself as a standard LCP.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..linalg import banded_matvec, solveh_banded, sub_bands


@dataclass
class ContactStep:
    """One linearised contact step (a convex, bound-constrained QP).

    Attributes
    ----------
    bands : ndarray (3, n)
        H in lower banded storage (``scipy.linalg.solveh_banded`` with
        ``lower=True``): ``bands[k, i] = H[i + k, i]``.
    linear : ndarray (n,)
        c, the linear term (N).
    lower, upper : ndarray (n,)
        Bounds on the free node heights u (mm): the walls.
    alpha : ndarray (N,)
        The configuration the step was linearised at.
    """

    bands: np.ndarray
    linear: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    alpha: np.ndarray
    inv_a_cos: np.ndarray  # 1 / (a cos α_i), the slope of eq. (21)
    v: np.ndarray  # tan α − α (eq. 24)
    free_nodes: np.ndarray
    links: int
    # J in stencil form (for the factored gradient): joint j touches shifted
    # nodes base[j] + (0, 1, 2) with coefficients coef[j]; φ̂ = J u + phi0.
    base: np.ndarray
    coef: np.ndarray
    phi0: np.ndarray
    origin: np.ndarray  # u₀, heights of the free nodes at the linearisation point
    alpha0: np.ndarray  # α̂(u₀): α, except the last link when the chain is not closed
    phi_origin: np.ndarray  # φ̂(u₀), computed from α̂(u₀) directly (no cancellation)
    stiffness: np.ndarray
    rest_joint: np.ndarray
    nodal_load: np.ndarray
    # Nondimensionalisation (DESIGN: lengths by ℓ, forces by EI/ℓ²)
    length_scale: float = 1.0
    force_scale: float = 1.0
    # The Newton step's curvature term T (lower banded, in ``bands`` already);
    # None for the paper's Gauss–Newton step (:mod:`lcpbench.model.newton`)
    geometric: np.ndarray | None = None
    # Elastic walls: spring stiffness k_i (N/mm) of the upper / lower wall per free
    # node, None = rigid (Chain.upper_stiffness). The step is then the QP with the
    # walls' penalty, handed over in its own forms (:mod:`lcpbench.model.elastic`).
    upper_stiffness: np.ndarray | None = None
    lower_stiffness: np.ndarray | None = None

    kernel = None  # the compiled step's module (None: :func:`step_kernels` at the first use)

    @property
    def elastic(self) -> bool:
        """Whether a wall of this step yields (a finite stiffness at some node)."""
        return any(k is not None and bool(np.isfinite(k).any())
                   for k in (self.upper_stiffness, self.lower_stiffness))
    # Face solves on the tridiagonal factor of H (large N, :mod:`lcpbench.model.large_n`:
    # a :class:`lcpbench.linalg.saddle.TridiagonalFactor`); None: banded Cholesky of H
    factor: Any = None

    @property
    def size(self) -> int:
        return self.linear.size

    # -- linear algebra on H --------------------------------------------------
    def matvec(self, u: np.ndarray) -> np.ndarray:
        """H @ u using the bands."""
        return banded_matvec(self.bands, u)

    def __post_init__(self):
        # the compiled gradient's arguments (free nodes and joints contiguous:
        # assemble_step checks); T with no columns for the Gauss–Newton step
        f, f64 = self.free_nodes, np.ascontiguousarray
        T = (np.empty((2, 0)) if self.geometric is None
             else f64(self.geometric[:2], dtype=float))
        self._terms = (f64(self.coef, dtype=float), int(self.base[0]) if self.base.size else 0,
                       int(f[0]) + 1 if f.size else 1, int(self.links),
                       f64(self.origin, dtype=float), f64(self.phi_origin, dtype=float),
                       f64(self.stiffness, dtype=float), f64(self.rest_joint, dtype=float),
                       f64(self.nodal_load, dtype=float), T)

    def gradient(self, u: np.ndarray) -> np.ndarray:
        """H u + c, computed in factored form Jᵀ k (φ̂(u) − φ*) − f (+ T (u − u₀) for
        the Newton step), φ̂(u) = φ̂(u₀) + J (u − u₀) written about the linearisation
        point (compiled: ``driver_kernel.gradient``).

        Equal to ``matvec(u) + linear`` in exact arithmetic, but it never forms
        the large, cancelling terms of H u: its round-off scales with the
        spring torques, not with |H||u|. At a solution it is minus the
        reactions (the upper wall pushes down).
        """
        return self.kernels().gradient(self._heights(u), *self._terms)

    def gradient_scale(self, u: np.ndarray) -> np.ndarray:
        """Size of the terms summed in :meth:`gradient` (for round-off tolerances)."""
        return self.kernels().gradient_scale(self._heights(u), *self._terms)

    def dense_hessian(self) -> np.ndarray:
        n = self.size
        H = np.diag(self.bands[0])
        for k in (1, 2):
            off = np.diag(self.bands[k, : n - k], -k)
            H += off + off.T
        return H

    def unconstrained_minimiser(self) -> np.ndarray:
        if self.factor is not None:
            return self.factor.solve(-self.linear)
        return solveh_banded(self.bands, -self.linear, lower=True, check_finite=False)

    def solve_on(self, idx: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """H[idx, idx]⁻¹ rhs: the principal block of the nodes ``idx`` (sorted)."""
        if self.factor is None:
            return solveh_banded(sub_bands(self.bands, idx), rhs, lower=True,
                                 check_finite=False)
        fixed = np.ones(self.size, bool)
        fixed[idx] = False
        full = np.zeros(self.size)
        full[idx] = rhs
        return self.factor.face_solve(fixed, full)[idx]

    # -- back to the chain ----------------------------------------------------
    def predict_alpha(self, u: np.ndarray) -> np.ndarray:
        """α̂ from the linearised kinematics, eq. (21), written about u₀ (compiled:
        :func:`lcpbench.model.chain_kernel.predict_alpha`, every loop's)."""
        u = self._heights(u)
        return self.kernels().predict(u, np.ascontiguousarray(self.alpha0, dtype=float),
                                      np.ascontiguousarray(self.origin, dtype=float),
                                      np.ascontiguousarray(self.inv_a_cos, dtype=float),
                                      int(self.free_nodes[0]) + 1)

    def _heights(self, u) -> np.ndarray:
        """``u`` as the kernels read it: the free nodes' heights, one float each (a
        ValueError names a wrong length: the kernels do not check it)."""
        u = np.ascontiguousarray(u, dtype=float)
        if u.shape != (self.size,):
            raise ValueError(f"u: the heights of the step's {self.size} free nodes, "
                             f"got shape {u.shape}")
        return u

    # -- the back-ends' forms, compiled (:mod:`.driver_kernel`) ----------------
    def kernels(self):
        """The compiled step's module (:func:`step_kernels`; kept by a step the driver
        assembled, else looked up)."""
        return self.kernel if self.kernel is not None else step_kernels()

    def qp_form(self, L: float, F: float) -> tuple:
        """The step as a box QP in units of length ``L`` and force ``F``
        (:func:`~.driver_kernel.qp_form`): (P̃ = H·(L/F) as CSC data, indices, indptr,
        c̃ = c/F, lower/L, upper/L, the scaled bands)."""
        return self.kernels().qp_form(self.bands, self.linear, self.lower, self.upper,
                                      float(L), float(F))

    def lcp_form(self, L: float = 1.0, F: float = 1.0) -> tuple:
        """The step as a standard LCP ``w = M ζ + q``, ``0 <= ζ ⟂ w >= 0``, and the same
        LCP in units of length ``L`` and force ``F``: ``(form, M̃, q̃, dz, dw)`` with
        ``z = dz ⊙ z̃`` and ``w = dw ⊙ w̃`` (:func:`~.driver_kernel.lcp_form`).

        Only the nodes that can reach a wall are rows; the others are condensed out (M
        stays pentadiagonal). With a lower wall (the channel) the unknowns are
        ζ = [g; R_lower] and w = [R_upper; g_lower], M = [[K, I], [−I, 0]].
        """
        code, M, q, Ms, qs, dz, dw, rows, top, cond = self.kernels().lcp_form(
            self.bands, self.linear, self.lower, self.upper, float(L), float(F))
        if code:
            raise NotImplementedError("a lower wall on only some contact rows")
        return (LCPForm(M=M, q=q, rows=rows, heights=top, condense=cond, n_gap=rows.size),
                Ms, qs, dz, dw)

    def lcp(self) -> LCPForm:
        """The step as a standard LCP (:meth:`lcp_form` in the step's units)."""
        return self.lcp_form()[0]

    def from_lcp(self, form: LCPForm, zeta: np.ndarray) -> np.ndarray:
        """Free node heights u from an LCP solution (recovers condensed nodes)."""
        return self.kernels().from_lcp(self.bands, self.linear, form.rows, form.heights,
                                       form.condense, np.ascontiguousarray(zeta, dtype=float))


@dataclass
class LCPForm:
    """A contact step as a standard LCP (see :meth:`ContactStep.lcp`)."""

    M: np.ndarray
    q: np.ndarray
    rows: np.ndarray  # free-node indices of the gap unknowns
    heights: np.ndarray  # upper wall height of each gap row (mm)
    condense: np.ndarray  # free-node indices eliminated from the LCP
    n_gap: int


#: the step's residuals (:func:`lcpbench.model.step_solver.step_residuals`), named once in
#: the order every kernel returns them (:func:`.compiled_dual.judge_step`'s ``out``)
RESIDUALS = ("natural", "min_gap", "min_reaction", "complementarity", "term_size")


def residuals_of(values) -> dict:
    """The residuals dict of a kernel's values (an array, or floats), in
    :data:`RESIDUALS`' order."""
    vals = values.tolist() if isinstance(values, np.ndarray) else map(float, values)
    return dict(zip(RESIDUALS, vals, strict=True))


#: the entries of :mod:`.driver_kernel` the driver around a back-end calls from Python
def step_kernels():
    """The compiled step's module, :mod:`.driver_kernel` (numba imported, its kernels
    loaded from the cache lightly, at the first call)."""
    from ..numba_cache import kernel_module  # numba at the first use

    return kernel_module("lcpbench.model.driver_kernel", "assemble")
