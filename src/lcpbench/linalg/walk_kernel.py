"""One move of the dual walk on a twisted factor, compiled (large N).

:func:`lcpbench.solvers.banded._dual` moves from ``u`` (gradient ``g``) to the
minimiser on the face S: the held nodes onto their walls, d₀ = (wall − u) on S,
then Newton on the free nodes, d = d₀ − H_S⁻¹ r with r = g + H d₀ zeroed on S,
and the gradient there, g + H d. In numpy that is a face solve and two products
with H plus a dozen full-length array passes (~1.7 ms at N = 10⁵ besides the
face solve). Here it is one call: the same arithmetic (H x as Aᵀ(A x), never
the rounded H; the face solve of :mod:`.twisted_kernel`), with the face solve's
refinement optional: the walk carries g by exact products, so an unrefined face
solve leaves a residual on the free nodes that the next move's r takes up,
and every optimum the walk finds is refined to round-off before it is accepted
(:func:`lcpbench.solvers.banded._refine`).
"""

from __future__ import annotations

from numba import njit

from .face_kernel import matvec_into as _matvec
from .twisted_kernel import factor, resolve


@njit(cache=True)
def _held_product(A, fixed, x, out):
    """out += Aᵀ (A x) for x zero off the ``fixed`` nodes: O(held nodes), the same
    terms as :func:`_matvec` (column i of A lives in rows i − 1 .. i + 1)."""
    n = x.size
    for i in range(n):
        if not fixed[i] or x[i] == 0.0:
            continue
        for j in range(max(i - 1, 0), min(i + 2, n)):
            yj = A[j, i - j + 1] * x[i]
            for k in range(max(j - 1, 0), min(j + 2, n)):
                out[k] += A[j, k - j + 1] * yj


@njit(cache=True)
def face_move(rows, rrows, fixed, rfixed, R, filled, snap, B, bfilled, bsnap, tri,
              invR, invB, j0, k0, m, wall, u, g, refine, d, g_face, r, x, y):
    """Writes the move ``d`` to the face minimiser and the gradient there ``g_face``;
    False on a zero pivot (``fixed`` = S). ``r``, ``x``, ``y``: work arrays (n,)."""
    if not factor(rows, rrows, fixed, rfixed, R, filled, snap, B, bfilled, bsnap, tri,
                  invR, invB, j0, k0, m):
        return False
    n = u.size
    for i in range(n):
        d[i] = (wall[i] - u[i]) if fixed[i] else 0.0
        g_face[i] = 0.0
    _held_product(rows, fixed, d, g_face)  # H d₀: d₀ lives on the held nodes only
    for i in range(n):
        r[i] = 0.0 if fixed[i] else g[i] + g_face[i]
        x[i] = r[i]
    resolve(R, B, tri, invR, invB, m, x)
    if refine:  # the corrected seminormal equations, as twisted_kernel.face_solve
        for i in range(n):
            d[i] = 0.0 if fixed[i] else x[i]  # d as a work array until below
        _matvec(rows, d, g_face, y)
        for i in range(n):
            r[i] = r[i] - (x[i] if fixed[i] else g_face[i])
        resolve(R, B, tri, invR, invB, m, r)
        for i in range(n):
            x[i] += r[i]
        for i in range(n):
            d[i] = (wall[i] - u[i]) if fixed[i] else 0.0
    for i in range(n):
        d[i] -= x[i]
    _matvec(rows, d, g_face, y)
    for i in range(n):
        g_face[i] += g[i]
    return True
