"""Compiled face solves on a twisted QR of A = diag(√k) J: a face change refactors locally.

:mod:`.face_kernel` rotates the rows of A into R from the top and restarts a
face from its first change, so each face costs the rows from the contacts to
the chain's end. Here the rows are rotated in from both ends and meet at a
*twist* row m (a "burn at both ends" factorisation):

- the **top** pass rotates rows 0..m−1 of A (and the unit rows of fixed nodes
  ≤ m − 2) into R, in order, as :mod:`.face_kernel` does;
- the **bottom** pass does the same on the reversed chain (node i ↔ n − 1 − i)
  for rows n − 1 .. m (unit rows of nodes ≥ m + 1), into B;
- both leave two partial rows on the columns m − 1, m; those, and the unit
  rows of nodes m − 1, m, are rotated into a 2 × 2 triangle T.

The rows of R above m − 1, of T and of B are M = QᵀA for an orthogonal Q, so
MᵀM = AᵀA = H_face, with the rounding of a Givens QR (the same bound as
:mod:`.face_kernel`). Each pass keeps its state before every row (``snap``):
a face that changes nodes p..q restarts the top pass at row p − 1 (or the last
twist, if earlier) and the bottom pass at the mirror of q + 1 (or the last
twist), and they meet in between: a face costs the rows between its first and
last change (and the last twist), not the rows to the end. The solves
Mᵀy = b, Mx = y run from both ends to the twist and back.

``R[p, i] = R_{i, i+p}``; B likewise in reversed indices; ``tri = (T00, T01, T11)``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .face_kernel import face_residual, rotate_in, save_snapshot
from .face_kernel import restore_before as _restore  # columns beyond: see _pass


@njit(cache=True)
def _pass(rows, fixed, spring, R, filled, snap, j0, m):
    """Rotate rows j0..m−1 (and the unit rows of fixed nodes ≤ m − 2, the spring rows
    √k_i e_i of nodes ≤ m − 2 held by an elastic wall: ``spring`` = √k per node, 0 or
    empty where none) into R from the state before row j0 (``snap[j0]``; j0 = 0: from
    scratch); keeps the state before every row up to m. Only columns < m + 1 are
    touched."""
    n = rows.shape[0]
    if j0 <= 0:
        j0 = 0
        for c in range(min(m + 2, n)):
            R[0, c] = 0.0
            R[1, c] = 0.0
            R[2, c] = 0.0
            filled[c] = False
    else:
        _restore(R, filled, snap, j0)
    for c in range(j0 + 1, min(m + 2, n)):  # what this pass may reach: assigned, not added
        filled[c] = False
    for j in range(j0, m):
        save_snapshot(R, filled, snap, j)
        if j >= 1 and fixed[j - 1]:
            rotate_in(R, filled, 1.0, 0.0, 0.0, j - 1)
        elif j >= 1 and spring.size and spring[j - 1] > 0.0:  # a wall's spring row
            rotate_in(R, filled, spring[j - 1], 0.0, 0.0, j - 1)
        w0 = rows[j, 0] if (j >= 1 and not fixed[j - 1]) else 0.0
        w1 = rows[j, 1] if not fixed[j] else 0.0
        w2 = rows[j, 2] if (j + 1 < n and not fixed[j + 1]) else 0.0
        if j == 0:
            rotate_in(R, filled, w1, w2, 0.0, 0)
        else:
            rotate_in(R, filled, w0, w1, w2, j - 1)
    save_snapshot(R, filled, snap, m)


@njit(cache=True)
def _rot2(T, filled2, a, b):
    """Rotate the row (a, b) on the two middle columns into the triangle T (3,)."""
    if a != 0.0:
        if not filled2[0]:
            T[0], T[1] = a, b
            filled2[0] = True
            return
        r = np.sqrt(T[0] * T[0] + a * a)
        cs, sn = T[0] / r, a / r
        T[0] = r
        x = T[1]
        T[1] = cs * x + sn * b
        b = cs * b - sn * x
    if b != 0.0:
        if not filled2[1]:
            T[2] = b
            filled2[1] = True
            return
        T[2] = np.sqrt(T[2] * T[2] + b * b)


@njit(cache=True)
def factor(rows, rrows, fixed, rfixed, spring, rspring, R, filled, snap, B, bfilled, bsnap,
           tri, invR, invB, j0, k0, m):
    """The twisted factor of the face ``fixed`` (``rfixed`` = fixed reversed, ``rrows``
    = the reversed rows) of H + diag(spring²) (``spring``: √k of the elastic walls'
    springs on the nodes they hold, ``rspring`` reversed; empty: none): top pass from
    row j0 to the twist m, bottom pass from reversed row k0 to n − m, the middle
    triangle. False on a zero pivot.

    A spring is a row √k e_i of A, so its stiffness never forms a sum with H's entries:
    as k → ∞ the Givens rotations take node i's column out of the other rows, the
    fixed node's limit (the rigid wall), whatever k."""
    n = rows.shape[0]
    mb = n - m
    _pass(rows, fixed, spring, R, filled, snap, j0, m)
    _pass(rrows, rfixed, rspring, B, bfilled, bsnap, k0, mb)
    for i in range(max(j0 - 1, 0), m - 1):
        if not (filled[i] and R[0, i] != 0.0):
            return False
        invR[i] = 1.0 / R[0, i]
    for i in range(max(k0 - 1, 0), mb - 1):
        if not (bfilled[i] and B[0, i] != 0.0):
            return False
        invB[i] = 1.0 / B[0, i]
    # the middle: columns (m − 1, m); the top pass's partial rows, the bottom's (its
    # columns mb − 1, mb are the original m, m − 1) and the unit rows of nodes m − 1, m
    tri[0] = tri[1] = tri[2] = 0.0
    f2 = np.zeros(2, np.bool_)
    if filled[m - 1]:
        _rot2(tri, f2, R[0, m - 1], R[1, m - 1])
    if filled[m]:
        _rot2(tri, f2, 0.0, R[0, m])
    if bfilled[mb - 1]:
        _rot2(tri, f2, B[1, mb - 1], B[0, mb - 1])
    if bfilled[mb]:
        _rot2(tri, f2, B[0, mb], 0.0)
    if fixed[m - 1]:
        _rot2(tri, f2, 1.0, 0.0)
    elif spring.size and spring[m - 1] > 0.0:
        _rot2(tri, f2, spring[m - 1], 0.0)
    if fixed[m]:
        _rot2(tri, f2, 0.0, 1.0)
    elif spring.size and spring[m] > 0.0:
        _rot2(tri, f2, 0.0, spring[m])
    return bool(f2[0] and f2[1] and tri[0] != 0.0 and tri[2] != 0.0)


@njit(cache=True)
def twist_middle(R, B, tri, m, mb, r1, r2, x):
    """The twist's 2×2 block: x[m − 1] and x[m] (the bottom's mb and mb − 1) from their
    right-hand sides r1, r2 and the swept neighbours x[m − 3 .. m − 2], x[m + 1 .. m + 2]
    (Mᵀy there, then M x back)."""
    s1 = r1
    if m >= 2:
        s1 -= R[1, m - 2] * x[m - 2]
    if m >= 3:
        s1 -= R[2, m - 3] * x[m - 3]
    if mb >= 2:
        s1 -= B[2, mb - 2] * x[m + 1]
    s2 = r2
    if m >= 2:
        s2 -= R[2, m - 2] * x[m - 2]
    if mb >= 2:
        s2 -= B[1, mb - 2] * x[m + 1]
    if mb >= 3:
        s2 -= B[2, mb - 3] * x[m + 2]
    y1 = s1 / tri[0]
    y2 = (s2 - tri[1] * y1) / tri[2]
    x[m] = y2 / tri[2]
    x[m - 1] = (y1 - tri[1] * x[m]) / tri[0]


@njit(cache=True)
def resolve(R, B, tri, invR, invB, m, x):
    """Overwrites x with (MᵀM)⁻¹ x: Mᵀy = x from both ends to the twist, then M x = y back."""
    n = x.size
    mb = n - m
    # the top and the bottom sweeps are independent recurrences: one loop runs both
    # (two dependency chains in flight instead of one)
    x[0] *= invR[0]
    x[n - 1] *= invB[0]
    if m - 1 > 1:
        x[1] = (x[1] - R[1, 0] * x[0]) * invR[1]
    if mb - 1 > 1:
        x[n - 2] = (x[n - 2] - B[1, 0] * x[n - 1]) * invB[1]
    for i in range(2, max(m - 1, mb - 1)):
        if i < m - 1:  # top row i
            x[i] = (x[i] - R[1, i - 1] * x[i - 1] - R[2, i - 2] * x[i - 2]) * invR[i]
        if i < mb - 1:  # bottom row i: original index n − 1 − i
            j = n - 1 - i
            x[j] = (x[j] - B[1, i - 1] * x[j + 1] - B[2, i - 2] * x[j + 2]) * invB[i]
    twist_middle(R, B, tri, m, mb, x[m - 1], x[m], x)
    # M x = y from the twist outwards: top row m − 2 − s and bottom row mb − 2 − s
    for s in range(max(m - 1, mb - 1)):
        i = m - 2 - s
        if i >= 0:
            x[i] = (x[i] - R[1, i] * x[i + 1] - R[2, i] * x[i + 2]) * invR[i]
        k = mb - 2 - s
        if k >= 0:
            j = n - 1 - k
            x[j] = (x[j] - B[1, k] * x[j - 1] - B[2, k] * x[j - 2]) * invB[k]
    return x


@njit(cache=True)
def twist(first, last, m0, n):
    """(j0, k0, m): where the top pass and the bottom pass restart, and the new twist,
    for a face whose nodes ``first``..``last`` changed against the face factored last
    (twisted at ``m0``; ``last`` < 0: none changed): the top pass from the row before
    the first change (or the last twist, if earlier), the bottom pass from the mirror
    of the row after the last change (or the last twist), and the twist between."""
    if last < 0:
        return m0, n - m0, m0
    j0 = max(min(first - 1, m0), 0)
    k0 = max(min(n - 2 - last, n - m0), 0)
    return j0, k0, min(max((j0 + n - k0) // 2, 2), n - 2)


@njit(cache=True)
def face_solve(rows, rrows, fixed, rfixed, spring, rspring, R, filled, snap, B, bfilled,
               bsnap, tri, invR, invB, j0, k0, m, rhs, x):
    """x with H_face x = rhs (+ the springs, :func:`factor`), refined once with the
    face's residual (H = AᵀA, never the rounded H: the corrected seminormal equations,
    as :mod:`.face_kernel`)."""
    if not factor(rows, rrows, fixed, rfixed, spring, rspring, R, filled, snap, B, bfilled,
                  bsnap, tri, invR, invB, j0, k0, m):
        return False
    n = rhs.size
    x[:] = rhs
    resolve(R, B, tri, invR, invB, m, x)
    xf = face_residual(rows, fixed, rhs, x)
    if spring.size:  # the springs' part of the residual: −k x on the nodes they hold
        for i in range(n):
            if spring[i] > 0.0 and not fixed[i]:
                xf[i] -= (spring[i] * spring[i]) * x[i]
    resolve(R, B, tri, invR, invB, m, xf)
    for i in range(n):
        x[i] += xf[i]
    return True
