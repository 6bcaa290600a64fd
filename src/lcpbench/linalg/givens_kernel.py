"""Compiled kernels of :mod:`.saddle`: the banded QR of diag(√k) J by Givens rotations.

``R`` is stored by diagonals: ``R[p, i] = R_{i, i+p}`` (p = 0, 1, 2). Rows of
A are rotated into R one at a time, in order (row j of J starts at column
j − 1), so R keeps two bands above the diagonal. A fixed node contributes the
unit row e_i instead of its column of J (which is zero), so R_ii = 1 there.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _rotate_in(R, filled, w, c):
    """Rotate the row ``w`` (4 entries from column c on) into R."""
    n = R.shape[1]
    while c < n:
        if w[0] == 0.0:
            w[0], w[1], w[2], w[3] = w[1], w[2], w[3], 0.0
            c += 1
            if w[0] == 0.0 and w[1] == 0.0 and w[2] == 0.0:
                return
            continue
        if not filled[c]:
            R[0, c] = w[0]
            if c + 1 < n:
                R[1, c] = w[1]
            if c + 2 < n:
                R[2, c] = w[2]
            filled[c] = True
            return
        a, b = R[0, c], w[0]
        r = np.sqrt(a * a + b * b)  # entries ~ √k/a: far from overflow
        cs, sn = a / r, b / r
        R[0, c] = r
        for p in range(1, 3):
            if c + p < n:
                x = R[p, c]
                R[p, c] = cs * x + sn * w[p]
                w[p] = cs * w[p] - sn * x
        w[0], w[1], w[2], w[3] = w[1], w[2], w[3], 0.0
        c += 1


@njit(cache=True)
def factor(rows, fixed, R):
    """R with RᵀR = Aᵀ A, A = rows of diag(√k) J (fixed columns zeroed) and the unit
    rows of the fixed nodes. False on a zero pivot."""
    n = rows.shape[0]
    R[:, :] = 0.0
    filled = np.zeros(n, np.bool_)
    w = np.zeros(4)
    for j in range(n):
        # the unit row of a fixed node c = j − 1, before the first row that starts there
        if j >= 1 and fixed[j - 1]:
            w[:] = 0.0
            w[0] = 1.0
            _rotate_in(R, filled, w, j - 1)
        w[:] = 0.0
        for m in range(3):
            c = j - 1 + m
            if 0 <= c < n and not fixed[c]:
                w[m] = rows[j, m]
        if j == 0:  # row 0 starts at column 0
            w[0], w[1], w[2], w[3] = w[1], w[2], 0.0, 0.0
            _rotate_in(R, filled, w, 0)
        else:
            _rotate_in(R, filled, w, j - 1)
    if fixed[n - 1]:
        w[:] = 0.0
        w[0] = 1.0
        _rotate_in(R, filled, w, n - 1)
    for i in range(n):
        if not (filled[i] and R[0, i] != 0.0):
            return False
    return True


@njit(cache=True)
def solve(R, x):
    """Overwrites x with (RᵀR)⁻¹ x."""
    n = x.size
    for i in range(n):  # Rᵀ y = x
        s = x[i]
        if i >= 1:
            s -= R[1, i - 1] * x[i - 1]
        if i >= 2:
            s -= R[2, i - 2] * x[i - 2]
        x[i] = s / R[0, i]
    for i in range(n - 1, -1, -1):  # R x = y
        s = x[i]
        if i + 1 < n:
            s -= R[1, i] * x[i + 1]
        if i + 2 < n:
            s -= R[2, i] * x[i + 2]
        x[i] = s / R[0, i]
    return x
