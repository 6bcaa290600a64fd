"""The exact answer of one contact step, in rational arithmetic: an oracle below round-off.

A contact step (``lcpbench.model.step.ContactStep``) is a box QP in the free node
heights u whose gradient is given in factored form,

    ∇(u) = Jᵀ k (φ̂(u₀) + J (u − u₀) − φ*) − f        (eq. 30: R = −∇ on the walls),

J the joints' three-node stencils (``base``, ``coef``), k the joint stiffnesses, φ*
the rest angles, f the nodal loads. Those doubles *are* the step. On a given contact
set A (nodes held at a wall), the answer solves (JᵀkJ)_FF Δu_F = −∇(u₀ + Δu_A)_F with
Δu_A the walls' offsets; this module solves it exactly with :class:`fractions.Fraction`
(banded elimination, no pivoting: JᵀkJ is positive definite) and returns the exact
reactions R = −∇(u) rounded once to double. It then checks the contact set: R of the
sign of its wall on A, the gaps of the other nodes nonnegative. An answer in floating
point (any back-end, any form) differs from this by its own round-off only; two exact
methods in double differ by cond(H)·ε ≈ 1e-8 at N = 140, this by nothing.

Rigid walls and the paper's Gauss–Newton step only (no ``geometric`` term, no elastic
rows): that is the step the targets measure.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np


def _exact(x) -> list:
    return [Fraction(float(v)) for v in np.asarray(x, dtype=float)]


def exact_reactions(step, active_upper: np.ndarray, active_lower: np.ndarray
                    ) -> tuple[np.ndarray, bool]:
    """(R, confirmed): the exact net reactions R (N) on the step's free nodes with the
    nodes of ``active_upper`` / ``active_lower`` (bool per free node) held at the upper /
    lower wall, rounded to double; ``confirmed`` whether that contact set is the
    step's (every held node's reaction of its wall's sign, every other node inside
    its walls), decided in exact arithmetic."""
    if step.geometric is not None or step.elastic:
        raise ValueError("exact_reactions takes a rigid-wall Gauss-Newton step only")
    n = step.size
    f0 = int(np.asarray(step.free_nodes)[0])
    b0 = int(step.base[0])
    # joint j, stencil column c touches free node b0 + j + c − (f0 + 1) (if free)
    touch = [[(b0 + j + c - f0 - 1, Fraction(float(step.coef[j, c]))) for c in range(3)
              if 0 <= b0 + j + c - f0 - 1 < n] for j in range(step.base.size)]
    k = _exact(step.stiffness)
    phi0 = [p - r for p, r in zip(_exact(step.phi_origin), _exact(step.rest_joint))]
    load = _exact(step.nodal_load)
    origin = _exact(step.origin)
    held = np.asarray(active_upper, bool) | np.asarray(active_lower, bool)
    bound = [Fraction(float(step.upper[i])) if active_upper[i] else
             Fraction(float(step.lower[i])) if active_lower[i] else None for i in range(n)]
    du = [bound[i] - origin[i] if held[i] else Fraction(0) for i in range(n)]

    def gradient(du):
        g = [-x for x in load]
        for j, row in enumerate(touch):
            m = k[j] * (phi0[j] + sum(c * du[i] for i, c in row))
            for i, c in row:
                g[i] += c * m
        return g

    free = [i for i in range(n) if not held[i]]
    pos = {i: p for p, i in enumerate(free)}
    # (JᵀkJ)_FF, banded (every joint couples nodes at most two apart)
    A: list[dict] = [dict() for _ in free]
    for j, row in enumerate(touch):
        for i, ci in row:
            if i in pos:
                for m_, cl in row:
                    if m_ in pos:
                        A[pos[i]][pos[m_]] = A[pos[i]].get(pos[m_], 0) + ci * k[j] * cl
    rhs = [-gi for gi in (gradient(du)[i] for i in free)]
    m = len(free)
    for p in range(m):  # elimination within the band; the pivot is positive (SPD)
        piv = A[p][p]
        for r in range(p + 1, min(p + 3, m)):
            f = A[r].get(p, 0)
            if f:
                f = f / piv
                for c_, v in A[p].items():
                    if c_ >= p:
                        A[r][c_] = A[r].get(c_, 0) - f * v
                rhs[r] -= f * rhs[p]
    x = [Fraction(0)] * m
    for p in range(m - 1, -1, -1):
        s = rhs[p] - sum(v * x[c_] for c_, v in A[p].items() if c_ > p)
        x[p] = s / A[p][p]
    for p, i in enumerate(free):
        du[i] = x[p]
    R = [-g for g in gradient(du)]
    u = [origin[i] + du[i] for i in range(n)]
    confirmed = True
    for i in range(n):
        if active_upper[i]:
            confirmed &= R[i] >= 0
        elif active_lower[i]:
            confirmed &= R[i] <= 0
        else:
            confirmed &= R[i] == 0 or abs(R[i]) < Fraction(1, 10**30)
            if np.isfinite(step.upper[i]):
                confirmed &= u[i] <= Fraction(float(step.upper[i]))
            if np.isfinite(step.lower[i]):
                confirmed &= u[i] >= Fraction(float(step.lower[i]))
    return np.array([float(r) for r in R]), bool(confirmed)
