"""Banded LDLᵀ of a face, without square roots: the dual walk's face solves.

H is symmetric positive definite with two sub-diagonals, in lower band storage
(``bands[p, i] = H[i + p, i]``). A *face* of H is H with the rows and columns of
the ``fixed`` nodes replaced by the identity. It is factored as L D Lᵀ, with L
unit lower triangular (two sub-diagonals) and D diagonal, into ``fac`` (4, n):

- ``fac[0, j] = 1 / D_j`` (the solves multiply, they do not divide);
- ``fac[1, j] = L[j+1, j]``, ``fac[2, j] = L[j+2, j]``;
- ``fac[3, j]``: the entry (j+1, j) of the Schur complement before it is scaled
  by 1 / D_j, kept so that a refactorisation can restart at any column with the
  same operations, and so the same bits, as a factorisation from the start.

The factorisation is a recurrence from column to column, so its cost is the
latency of one column's dependent chain: here one division, one multiply and
one subtraction (D_{j+1} = S_{j+1,j+1} − L_{j+1,j} S_{j+1,j}); the Cholesky
factor (LAPACK's dpbtf2) puts a square root
and a division and two multiplies on it, about twice the time. The two agree
to round-off, not bit for bit: both are backward stable for a positive
definite H. The entries of the next columns are carried in registers.

A fixed node's column is the identity's: D = 1 and its L entries are zero (in
exact arithmetic and in floating point, but for the sign of a zero), so it is
written without the division and cuts the dependent chain.

A node held by an elastic wall of compliance c > 0 (``shift[j] = c``; mm/N) keeps
its row with the wall's spring 1/c on the diagonal: D_j = S_jj + 1/c, stored as
1 / D_j = c / (1 + c S_jj), so that nothing grows with the stiffness 1/c. As
c → 0 the column tends to a fixed node's (1 / D_j and its L entries → 0): the
rigid wall is the limit, not a special case (issue 35, item 4).
Loaded only through :func:`lcpbench.numba_cache.kernel_module` (the kernels' cache).
"""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def refactor(fac, bands, fixed, shift, c0, c1):
    """Factor the face ``fixed`` of H (``bands``) into ``fac``, columns ``c0`` to
    ``c1`` (0, n: all of it); ``shift``: the compliance c_j of the nodes held by an
    elastic wall (0 elsewhere), or empty where no wall yields. ``fac`` holds the factor of a face that differs from
    ``fixed`` only at nodes in [c0 + 2, c1 − 2): its columns before c0 stand (a
    column reads the nodes up to two below it), and those from c1 on as well when
    nodes c1 − 2 and c1 − 1 are fixed in both (the identity there cuts H in two).
    False when the face is not positive definite (a pivot D_j <= 0). A change of a
    node's ``shift`` is a change of the face as one of ``fixed``."""
    n = fixed.size
    if c0 >= c1:
        return True
    j = c0
    # the Schur complement's entries of column c0 (and the next diagonal) from the
    # factored columns c0 − 2, c0 − 1: the loop's own updates, replayed
    cur0 = 1.0 if fixed[j] else bands[0, j]
    if j >= 2 and not (fixed[j - 2] or fixed[j]):
        cur0 = cur0 - fac[2, j - 2] * bands[2, j - 2]
    cur1 = nxt0 = 0.0
    if j + 1 < n:
        cur1 = 0.0 if (fixed[j] or fixed[j + 1]) else bands[1, j]
        nxt0 = 1.0 if fixed[j + 1] else bands[0, j + 1]
    if j >= 1:
        cur0 = cur0 - fac[1, j - 1] * fac[3, j - 1]
        if j + 1 < n:
            cur1 = cur1 - fac[2, j - 1] * fac[3, j - 1]
            if not (fixed[j - 1] or fixed[j + 1]):
                nxt0 = nxt0 - fac[2, j - 1] * bands[2, j - 1]
    for j in range(c0, c1):
        if fixed[j]:  # an identity column: no division, and the chain is cut
            fac[0, j] = 1.0
            fac[1, j] = 0.0
            fac[2, j] = 0.0
            fac[3, j] = 0.0
            new0, new1 = nxt0, 0.0
            if j + 2 < n:
                new1 = 0.0 if (fixed[j + 1] or fixed[j + 2]) else bands[1, j + 1]
                nxt0 = 1.0 if fixed[j + 2] else bands[0, j + 2]
        else:
            if shift.size and shift[j] > 0.0:  # held by a spring: D = S_jj + 1/c
                den = 1.0 + shift[j] * cur0
                if not den > 0.0:
                    return False
                r = shift[j] / den
            else:
                if not cur0 > 0.0:
                    return False
                r = 1.0 / cur0
            l1 = cur1 * r
            fac[0, j] = r
            fac[1, j] = l1
            fac[3, j] = cur1
            new0, new1 = nxt0 - l1 * cur1, 0.0
            if j + 2 < n:
                if fixed[j + 2]:
                    fac[2, j] = 0.0
                    new1 = 0.0
                    nxt0 = 1.0
                else:
                    a2 = bands[2, j]
                    l2 = a2 * r
                    fac[2, j] = l2
                    new1 = (0.0 if fixed[j + 1] else bands[1, j + 1]) - l2 * cur1
                    nxt0 = bands[0, j + 2] - l2 * a2
            else:
                fac[2, j] = 0.0
        cur0, cur1 = new0, new1
    return True


@njit(cache=True)
def resolve(fac, x):
    """Overwrites x with the solution of L D Lᵀ x = x (the last two entries carried
    in registers)."""
    n = x.size
    y1 = y2 = 0.0  # x[j − 1], x[j − 2] of the forward pass
    for j in range(n):
        t = x[j]
        if j >= 2:
            t -= fac[2, j - 2] * y2
        if j >= 1:
            t -= fac[1, j - 1] * y1
        x[j] = t
        y2, y1 = y1, t
    b1 = b2 = 0.0  # x[j + 1], x[j + 2] of the backward pass
    for j in range(n - 1, -1, -1):
        t = x[j] * fac[0, j]
        if j + 2 < n:
            t -= fac[2, j] * b2
        if j + 1 < n:
            t -= fac[1, j] * b1
        x[j] = t
        b2, b1 = b1, t
    return x


@njit(cache=True)
def resolve_columns(fac, X, ny):
    """Overwrites the first ``ny`` rows of X (ny × cols, row-major) with L D Lᵀ's
    solution, each column by the operations of
    :func:`resolve` in its order (the same bits), the columns
    side by side (the inner loop runs along a row: contiguous, vectorised)."""
    cols = X.shape[1]
    for j in range(1, ny):  # forward: x_j −= L_(j,j−2) x_(j−2), then L_(j,j−1) x_(j−1)
        for c in range(cols):
            t = X[j, c]
            if j >= 2:
                t -= fac[2, j - 2] * X[j - 2, c]
            X[j, c] = t - fac[1, j - 1] * X[j - 1, c]
    for j in range(ny - 1, -1, -1):  # backward: x_j = x_j / D_j − L_(j+2,j) x_(j+2) − …
        for c in range(cols):
            t = X[j, c] * fac[0, j]
            if j + 2 < ny:
                t -= fac[2, j] * X[j + 2, c]
            if j + 1 < ny:
                t -= fac[1, j] * X[j + 1, c]
            X[j, c] = t
