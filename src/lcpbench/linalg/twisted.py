"""Face solves of H = Jᵀ diag(k) J on a twisted QR (:mod:`.twisted_kernel`): a face
change refactors the rows between its first and last change only.

The interface of :class:`lcpbench.linalg.saddle.TridiagonalFactor` (``face_solve``,
``solve``, ``resolve``, ``matvec``), built from the same rows of A = diag(√k) J.
"""

from __future__ import annotations

import numpy as np

from .saddle import TridiagonalFactor


def _kernel():
    from . import twisted_kernel  # numba: loads or compiles at the first face solve

    return twisted_kernel


class TwistedFactor(TridiagonalFactor):
    """:class:`TridiagonalFactor` with rows rotated in from both ends (see the kernel).

    ``rows_touched``: the rows of A rotated in by the last factorisation (both passes).
    """

    def __init__(self, coef: np.ndarray, stiffness: np.ndarray):
        super().__init__(coef, stiffness, restart=True)
        n = self.n
        self.rrows = np.ascontiguousarray(self.rows[::-1, ::-1])
        self.B = np.zeros((3, n))
        self._bfilled = np.zeros(n, np.bool_)
        self._bsnap = np.zeros((n, 4))
        self._invB = np.zeros(n)
        self._tri = np.zeros(3)
        self._m = n // 2
        self.rows_touched = 0

    def face_solve(self, fixed: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        n = self.n
        fixed = np.ascontiguousarray(fixed, dtype=np.bool_)
        if n < 5:  # no room for a twist
            return super().face_solve(fixed, rhs)
        if self._fixed is None:
            j0, k0, m = 0, 0, n // 2
        else:
            changed = np.flatnonzero(fixed != self._fixed)
            if changed.size:
                j0 = min(int(changed[0]) - 1, self._m)  # the top pass: from its first row
                k0 = min(n - 2 - int(changed[-1]), n - self._m)  # the bottom's, mirrored
                j0, k0 = max(j0, 0), max(k0, 0)
                m = min(max((j0 + n - k0) // 2, 2), n - 2)
            else:
                j0, k0, m = self._m, n - self._m, self._m
        self._fixed = None  # invalid until the factorisation succeeds
        x = np.empty(n)
        ok = _kernel().face_solve(self.rows, self.rrows, fixed, np.ascontiguousarray(fixed[::-1]),
                                  self.R, self._filled, self._snap, self.B, self._bfilled,
                                  self._bsnap, self._tri, self._inv, self._invB, j0, k0, m,
                                  np.ascontiguousarray(rhs, float), x)
        if not ok:
            raise np.linalg.LinAlgError("a face of H is singular (zero pivot)")
        self._fixed, self._m = fixed.copy(), m
        self.rows_touched = (m - j0) + (n - m - k0)
        return x

    def resolve(self, rhs: np.ndarray) -> np.ndarray:
        if self.n < 5:
            return super().resolve(rhs)
        return _kernel().resolve(self.R, self.B, self._tri, self._inv, self._invB, self._m,
                                 np.array(rhs, dtype=float))
