"""Face solves with H = Jᵀ diag(k) J that never form H (the tridiagonal factor).

The contact step's Hessian is H = Jᵀ diag(k) J with J square and tridiagonal
(joint j bends at node j: φ̂_j touches the free nodes j − 1, j, j + 1). Forming
H squares the conditioning of J: cond(H) grows as N⁴ and passes 1/ε near
N = 3·10⁴, where the banded Cholesky of the rounded H fails.

Here the Cholesky factor R of H (RᵀR = H, upper triangular, two bands above
the diagonal) is computed as the R of the QR factorisation of A = diag(√k) J,
by Givens rotations, row by row, in O(n) (:mod:`.givens_kernel`). The
rotations' backward error is a small perturbation of A itself, so RᵀR is
always positive definite, and for the smooth right-hand sides of a chain the
error of x = H⁻¹ r grows like cond(J) ~ N², not N⁴. (An LU of the augmented
system [[1/k, −J], [Jᵀ, 0]] does not do this: its backward error reaches the
zero block, which is a perturbation of H itself, and at N = 3·10⁴ its face
solves were off by 0.4 % of the terms.)

A *face* holds the ``fixed`` nodes (those on a wall): their columns leave A
and the unit rows e_iᵀ join it, so RᵀR is H with the identity on the fixed
rows and columns, as the dual walk's faces are
(:func:`lcpbench.solvers.dual_kernel.face_factor`).
"""

from __future__ import annotations

import numpy as np


def _kernel():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.linalg.givens_kernel")


def _face_kernel():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.linalg.face_kernel")


class TridiagonalFactor:
    """Face solves of H = Jᵀ diag(k) J from the three diagonals of J.

    Parameters
    ----------
    coef : ndarray (n, 3)
        Row j of J: ``coef[j] = (J[j, j−1], J[j, j], J[j, j+1])`` (entries outside
        0..n−1 are ignored).
    stiffness : ndarray (n,)
        k, one per row of J (N·mm/rad).

    Face solves of a face's ``fixed`` nodes: ``face_solve(fixed, rhs)``,
    ``solve(rhs)``, ``resolve(rhs)`` (the last factor again) and ``matvec(x)``.

    ``restart=True`` (default): each face is refactored from its first change
    against the last face, in one compiled call (:mod:`.face_kernel`: the same
    R bit for bit); ``False``: the reference, a full factorisation per face
    (:mod:`.givens_kernel`) and the refinement in numpy.
    """

    def __init__(self, coef: np.ndarray, stiffness: np.ndarray, *, restart: bool = True):
        coef = np.asarray(coef, dtype=float)
        n = coef.shape[0]
        if coef.shape != (n, 3) or np.shape(stiffness) != (n,):
            raise ValueError("J must be square: coef (n, 3) and one stiffness per row")
        self.n = n
        self.rows = np.ascontiguousarray(coef * np.sqrt(np.asarray(stiffness, float))[:, None])
        self.rows[0, 0] = 0.0
        self.rows[-1, 2] = 0.0
        self.R = np.zeros((3, n))
        self.restart = restart
        self._fixed: np.ndarray | None = None  # the face of the last factorisation
        if restart:
            self._filled = np.zeros(n, np.bool_)
            self._snap = np.zeros((n, 4))
            self._inv = np.zeros(n)

    def matvec(self, x: np.ndarray) -> np.ndarray:
        if self.restart:
            return _face_kernel().matvec(self.rows, np.ascontiguousarray(x, dtype=float),
                                         np.empty(self.n))
        return self.matvec_reference(x)

    def matvec_reference(self, x: np.ndarray) -> np.ndarray:
        """H x as Aᵀ(A x), never with the rounded H: a face solve undoes an increment
        H_FS d_S of the dual walk only if both use the same matrix (with the rounded
        H, at N = 3·10⁴, the walk's heights were off by millimetres)."""
        A = self.rows
        y = A[:, 1] * x
        y[1:] += A[1:, 0] * x[:-1]
        y[:-1] += A[:-1, 2] * x[1:]
        out = A[:, 1] * y
        out[:-1] += A[1:, 0] * y[1:]
        out[1:] += A[:-1, 2] * y[:-1]
        return out

    def face_solve(self, fixed: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        """x with H_face x = rhs (H with the fixed rows and columns the identity)."""
        fixed = np.ascontiguousarray(fixed, dtype=np.bool_)
        if self.restart:
            j0 = 0
            if self._fixed is not None:
                changed = np.flatnonzero(fixed != self._fixed)
                j0 = int(changed[0]) - 1 if changed.size else self.n
            x = np.empty(self.n)
            self._fixed = None  # invalid until the factorisation succeeds
            ok = _face_kernel().face_solve(self.rows, fixed, self.R, self._filled, self._snap,
                                           self._inv, j0, np.ascontiguousarray(rhs, float), x)
            if not ok:
                raise np.linalg.LinAlgError("a face of H is singular (zero pivot of R)")
            self._fixed = fixed.copy()
            return x
        ok = _kernel().factor(self.rows, np.ascontiguousarray(fixed, dtype=np.bool_), self.R)
        if not ok:
            raise np.linalg.LinAlgError("a face of H is singular (zero pivot of R)")
        fixed = np.asarray(fixed, bool)
        rhs = np.asarray(rhs, dtype=float)
        x = self.resolve(rhs)
        # the corrected seminormal equations: one refinement with the residual of the
        # face, H_face x = P_F Aᵀ A P_F x + P_S x (Björck): as accurate as QR itself
        # while cond(J) ε < 1, also for the spiky right-hand sides H_FS d_S of the walk
        xf = np.where(fixed, 0.0, x)
        res = rhs - np.where(fixed, x, self.matvec(xf))
        return x + self.resolve(res)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return self.face_solve(np.zeros(self.n, bool), rhs)

    def resolve(self, rhs: np.ndarray) -> np.ndarray:
        if self.restart:
            return _face_kernel().resolve(self.R, self._inv, np.array(rhs, dtype=float))
        return _kernel().solve(self.R, np.array(rhs, dtype=float))
