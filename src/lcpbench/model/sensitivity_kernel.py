"""The sensitivities' face solve compiled (:mod:`lcpbench.model.sensitivity`).

At the answer α with reactions R: the step assembled (the solve kernel's
:func:`~lcpbench.model.compiled_kernel.banded_step`), the exact Hessian H + T (its
:func:`~lcpbench.model.compiled_kernel.geometric_bands`), the face of the answer's contact
set factored by the walk's LDLᵀ (a rigid wall's node fixed, an elastic wall's held by
its spring in the compliance form), and per parameter one right-hand side and one
solve. ∂∇E/∂p is the energy gradient of :func:`~lcpbench.solvers.dual_kernel.grad_into`
with the parameter's derivative in place of the joint stiffness, rest angles or loads
(the gradient is linear in each). Loaded through :func:`lcpbench.numba_cache.kernel_module`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..linalg.ldl_kernel import refactor, resolve
from ..solvers.dual_kernel import grad_into, matvec_row
from .compiled_kernel import banded_step, geometric_bands

#: the flat actuator's output rows (one θ, EI and weight row each): the layout of
#: :func:`rows_of` with one of each
THETA, HEIGHT, EI_, WEIGHT, WALL = range(5)
OK, NOT_PD = 0, 1
#: what a parameter changes in the energy's gradient (:func:`gradient_derivative`)
REST, SPRING, LOAD = range(3)


@njit(cache=True)
def gradient_derivative(dgrad, kind, vec, coef, b0, fs, links, origin, phi_origin, k, rest, m,
                        none_n, none_j, Tz):
    """∂∇E/∂p at the linearisation point into ``dgrad``; the gradient Jᵀ k (φ − φ*) − f
    is linear in each of k, φ* and f: ``kind`` REST, ``vec`` = ∂φ*/∂p per joint
    (∂∇E = Jᵀ k (−∂φ*)); SPRING, ``vec`` = ∂k/∂p per joint (Jᵀ ∂k (φ − φ*)); LOAD,
    ``vec`` = ∂f/∂p per free node (−∂f). ``m``: scratch per joint; ``none_n``,
    ``none_j``, ``Tz``: zeros (per node, per joint, 2 × n)."""
    if kind == REST:
        grad_into(dgrad, m, origin, (coef, b0, fs, links, origin, none_j, k, vec, none_n), Tz)
    elif kind == SPRING:
        grad_into(dgrad, m, origin, (coef, b0, fs, links, origin, phi_origin, vec, rest,
                                      none_n), Tz)
    else:
        for i in range(dgrad.size):
            dgrad[i] = -vec[i]


@njit(cache=True)
def derivatives(alpha, a, jl, jr, k, rest, fs, nodal_load, lo, hi, cu, cl, fu, fl, eps_R,
                drest, dk, unit_load, wall_k, want):
    """(code, du, dfu, dfl, u): the derivatives of the free nodes' heights and the upper and
    lower reactions, one output row per parameter, those of ``want`` (bool per row)
    written, the rest zero; code NOT_PD where the face is not positive definite.

    The rows: one per row of ``drest`` (mt, nj) (∂φ*/∂θ_k per joint: a bend angle),
    then the wall height, one per row of ``dk`` (me, nj) (∂k/∂EI_k per joint), one per
    row of ``unit_load`` (mw, n) (the nodal load at unit weight w_k), then the Winkler
    stiffness ``wall_k`` (k_i ∝ it). ``cu``, ``cl``: the walls' compliances (empty:
    rigid); ``u``: the free nodes' heights at α (the step's linearisation point)."""
    n, links, nj = lo.size, alpha.size, jr.size
    mt, me, mw = drest.shape[0], dk.shape[0], unit_load.shape[0]
    rows = mt + me + mw + 2
    bands, _, _, coef, origin, _, phi_origin = banded_step(alpha, a, jl, jr, k, rest, fs, n,
                                                         nodal_load)
    T, mu = np.zeros((2, n)), np.empty(links)
    geometric_bands(alpha, a, jl, jr, k, rest, fs, n, T, mu, np.sin(alpha), np.cos(alpha))
    for i in range(n):
        bands[0, i] += T[0, i]
        bands[1, i] += T[1, i]
    soft = cu.size == n
    up, down = np.empty(n, np.bool_), np.empty(n, np.bool_)
    rigid, comp = np.empty(n, np.bool_), np.zeros(n)
    for i in range(n):
        up[i] = fu[i] > eps_R
        down[i] = fl[i] > eps_R and not up[i]
        if soft:
            comp[i] = cu[i] if up[i] else (cl[i] if down[i] else 0.0)
        rigid[i] = (up[i] or down[i]) and not comp[i] > 0.0
    du, dfu, dfl = np.zeros((rows, n)), np.zeros((rows, n)), np.zeros((rows, n))
    fac = np.empty((4, n))
    if not refactor(fac, bands, rigid, comp if soft else comp[:0], 0, n):
        return NOT_PD, du, dfu, dfl, origin
    none_n, none_j, m, Tz = np.zeros(n), np.zeros(nj), np.empty(nj), np.zeros((2, n))
    dgrad, du0, r = np.empty(n), np.empty(n), np.empty(n)
    for p in range(rows):
        if not want[p]:
            continue
        dgrad[:] = 0.0
        du0[:] = 0.0
        if p < mt:
            gradient_derivative(dgrad, REST, drest[p], coef, jr[0], fs, links, origin, phi_origin,
                                k, rest, m, none_n, none_j, Tz)
        elif p == mt:  # the walls move: +1 the upper, −1 the lower (at −h)
            for i in range(n):
                du0[i] = 1.0 if up[i] else (-1.0 if down[i] else 0.0)
        elif p <= mt + me:
            gradient_derivative(dgrad, SPRING, dk[p - mt - 1], coef, jr[0], fs, links,
                                origin, phi_origin, k, rest, m, none_n, none_j, Tz)
        elif p <= mt + me + mw:
            gradient_derivative(dgrad, LOAD, unit_load[p - mt - me - 1], coef, jr[0], fs,
                                links, origin, phi_origin, k, rest, m, none_n, none_j, Tz)
        for i in range(n):
            r[i] = 0.0 if rigid[i] else dgrad[i] + matvec_row(bands, du0, i, n, False)
            if p == rows - 1 and (up[i] or down[i]) and not rigid[i]:  # ∂k_i (u − h) = R_i / k
                r[i] += (fu[i] - fl[i]) / wall_k
        resolve(fac, r)
        for i in range(n):
            du[p, i] = du0[i] - r[i]
        for i in range(n):
            dR = -(dgrad[i] + matvec_row(bands, du[p], i, n, False))
            dfu[p, i] = dR if up[i] else 0.0
            dfl[p, i] = -dR if down[i] else 0.0
    return OK, du, dfu, dfl, origin
