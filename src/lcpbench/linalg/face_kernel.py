"""Compiled face solves of :class:`.saddle.TridiagonalFactor`, refactored from the first change.

The same Givens QR of A = diag(√k) J as :mod:`.givens_kernel` (rows of A
rotated into R in order; a fixed node's column leaves A and its unit row
joins), with two differences that keep its arithmetic but cut its cost in the
dual walk, where consecutive faces differ by a few nodes:

- **restart.** Before row j is rotated in, R's rows 0..j−2 are final and rows
  j−1, j hold everything rows 0..j−1 left (a row of A reaches R's rows j−1..j+1
  only). That state is kept per row (``snap``). A face whose first change
  against the last one is node i changes rows i−1, i, i+1 of A (and the unit
  row before row i + 1), so it is refactored from row i − 1 on, from the kept
  state: the same operations on the same numbers as a full factorisation, so
  the same R, bit for bit. The walk moves the contacts of one region of the
  chain; a factorisation then costs the rows from there to the end.
- **one call per face solve**: the factor, the solve, the residual of the face
  with H = Aᵀ A (never the rounded H) and one refinement (corrected
  seminormal equations, Björck), with the reciprocals of R's diagonal kept.

``R[p, i] = R_{i, i+p}``; ``snap[j] = (R_{j−1,j−1}, R_{j−1,j}, R_{j,j}, filled[j−1] + 2 filled[j])``
before row j.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def rotate_in(R, filled, w0, w1, w2, c):
    """Rotate the row (w0, w1, w2) from column c on into R (:func:`.givens_kernel._rotate_in`
    on scalars, one division per rotation)."""
    n = R.shape[1]
    while c < n:
        if w0 == 0.0:
            w0, w1, w2 = w1, w2, 0.0
            c += 1
            if w0 == 0.0 and w1 == 0.0:
                return
            continue
        if not filled[c]:
            R[0, c] = w0
            if c + 1 < n:
                R[1, c] = w1
            if c + 2 < n:
                R[2, c] = w2
            filled[c] = True
            return
        a = R[0, c]
        r = np.sqrt(a * a + w0 * w0)
        ir = 1.0 / r
        cs, sn = a * ir, w0 * ir
        R[0, c] = r
        if c + 1 < n:
            x = R[1, c]
            R[1, c] = cs * x + sn * w1
            w1 = cs * w1 - sn * x
        if c + 2 < n:
            x = R[2, c]
            R[2, c] = cs * x + sn * w2
            w2 = cs * w2 - sn * x
        w0, w1, w2 = w1, w2, 0.0
        c += 1


@njit(cache=True)
def save_snapshot(R, filled, snap, j):
    # before row j only R_{j-1,j-1}, R_{j-1,j} and R_{j,j} can be non-zero among rows >= j-1
    n = R.shape[1]
    snap[j, 0] = R[0, j - 1] if j >= 1 else 0.0
    snap[j, 1] = R[1, j - 1] if j >= 1 else 0.0
    snap[j, 2] = R[0, j] if j < n else 0.0
    snap[j, 3] = (1.0 if (j >= 1 and filled[j - 1]) else 0.0) + (2.0 if filled[j] else 0.0)


@njit(cache=True)
def restore_before(R, filled, snap, j):
    """Rows j − 1 and j of the factor as they were before row j was rotated in
    (the columns beyond are left as they are; the twisted kernel's restore)."""
    if j >= 1:
        R[0, j - 1] = snap[j, 0]
        R[1, j - 1] = snap[j, 1]
        R[2, j - 1] = 0.0
        filled[j - 1] = (int(snap[j, 3]) & 1) != 0
    filled[j] = (int(snap[j, 3]) & 2) != 0
    R[0, j] = snap[j, 2]
    R[1, j] = 0.0
    R[2, j] = 0.0


@njit(cache=True)
def _restore(R, filled, snap, j):
    """The state before row j, the columns beyond it cleared."""
    restore_before(R, filled, snap, j)
    n = R.shape[1]
    for c in range(j + 1, n):
        R[0, c] = 0.0
        R[1, c] = 0.0
        R[2, c] = 0.0
        filled[c] = False


@njit(cache=True)
def factor_from(rows, fixed, R, filled, snap, inv, j0):
    """Factor the face ``fixed`` from row ``j0`` on (0: from scratch; R, filled and
    snap hold a factorisation whose face agrees with ``fixed`` on nodes < j0 + 1).
    False on a zero pivot."""
    n = rows.shape[0]
    if j0 >= n:  # the same face as the last factorisation
        return True
    if j0 <= 0:
        j0 = 0
        R[:, :] = 0.0
        filled[:] = False
    else:
        _restore(R, filled, snap, j0)
    for j in range(j0, n):
        save_snapshot(R, filled, snap, j)
        if j >= 1 and fixed[j - 1]:  # the unit row of a fixed node, before row j
            rotate_in(R, filled, 1.0, 0.0, 0.0, j - 1)
        w0 = rows[j, 0] if (j >= 1 and not fixed[j - 1]) else 0.0
        w1 = rows[j, 1] if not fixed[j] else 0.0
        w2 = rows[j, 2] if (j + 1 < n and not fixed[j + 1]) else 0.0
        if j == 0:  # row 0 starts at column 0
            rotate_in(R, filled, w1, w2, 0.0, 0)
        else:
            rotate_in(R, filled, w0, w1, w2, j - 1)
    if fixed[n - 1]:
        rotate_in(R, filled, 1.0, 0.0, 0.0, n - 1)
    for i in range(max(j0 - 1, 0), n):
        if not (filled[i] and R[0, i] != 0.0):
            return False
        inv[i] = 1.0 / R[0, i]
    return True


@njit(cache=True)
def resolve(R, inv, x):
    """Overwrites x with (RᵀR)⁻¹ x."""
    n = x.size
    for i in range(n):  # Rᵀ y = x
        s = x[i]
        if i >= 1:
            s -= R[1, i - 1] * x[i - 1]
        if i >= 2:
            s -= R[2, i - 2] * x[i - 2]
        x[i] = s * inv[i]
    for i in range(n - 1, -1, -1):  # R x = y
        s = x[i]
        if i + 1 < n:
            s -= R[1, i] * x[i + 1]
        if i + 2 < n:
            s -= R[2, i] * x[i + 2]
        x[i] = s * inv[i]
    return x


@njit(cache=True)
def matvec_into(A, x, out, y):
    """out = Aᵀ (A x), with the work array ``y`` (A x) given."""
    n = x.size
    for i in range(n):
        s = A[i, 1] * x[i]
        if i >= 1:
            s += A[i, 0] * x[i - 1]
        if i + 1 < n:
            s += A[i, 2] * x[i + 1]
        y[i] = s
    for i in range(n):
        s = A[i, 1] * y[i]
        if i + 1 < n:
            s += A[i + 1, 0] * y[i + 1]
        if i >= 1:
            s += A[i - 1, 2] * y[i - 1]
        out[i] = s


@njit(cache=True)
def matvec(A, x, out):
    """out = Aᵀ (A x) (H x without the rounded H); A = the rows of diag(√k) J."""
    matvec_into(A, x, out, np.empty(x.size))
    return out


@njit(cache=True)
def face_residual(rows, fixed, rhs, x):
    """rhs − H_face x, H_face = H with the ``fixed`` rows and columns the identity
    (H x as Aᵀ(A x), without the rounded H): the right side of one refinement step
    of a face solve, here and in the twisted kernel."""
    n = rhs.size
    xf = np.empty(n)
    for i in range(n):
        xf[i] = 0.0 if fixed[i] else x[i]
    hx = np.empty(n)
    matvec(rows, xf, hx)
    for i in range(n):
        xf[i] = rhs[i] - (x[i] if fixed[i] else hx[i])
    return xf


@njit(cache=True)
def face_solve(rows, fixed, R, filled, snap, inv, j0, rhs, x):
    """x with H_face x = rhs, refined once with the face's residual; False on a zero
    pivot. ``rhs`` is kept."""
    if not factor_from(rows, fixed, R, filled, snap, inv, j0):
        return False
    n = rhs.size
    x[:] = rhs
    resolve(R, inv, x)
    xf = face_residual(rows, fixed, rhs, x)
    resolve(R, inv, xf)
    for i in range(n):
        x[i] += xf[i]
    return True
