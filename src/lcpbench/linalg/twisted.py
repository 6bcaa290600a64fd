"""Face solves of H = Jᵀ diag(k) J on a twisted QR (:mod:`.twisted_kernel`): a face
change refactors the rows between its first and last change only.

The interface of :class:`lcpbench.linalg.saddle.TridiagonalFactor` (``face_solve``,
``solve``, ``resolve``, ``matvec``), built from the same rows of A = diag(√k) J.
"""

from __future__ import annotations

import numpy as np

from .saddle import TridiagonalFactor


def _kernel():
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    return kernel_module("lcpbench.linalg.twisted_kernel")


#: no springs on a face (the kernels read an empty array as none)
NO_SPRING = np.zeros(0)


def _springs(root: np.ndarray, n: int) -> np.ndarray:
    return root if root.size else np.zeros(n)


class TwistedFactor(TridiagonalFactor):
    """:class:`TridiagonalFactor` with rows rotated in from both ends (see the kernel).

    ``rows_touched``: the rows of A rotated in by the last factorisation (both passes).
    """

    def __init__(self, coef: np.ndarray, stiffness: np.ndarray):
        super().__init__(coef, stiffness, restart=True)
        self._state(np.ascontiguousarray(self.rows[::-1, ::-1]))

    @classmethod
    def from_rows(cls, rows: np.ndarray, rrows: np.ndarray, state: dict | None = None
                  ) -> TwistedFactor:
        """The factor of the rows A = diag(√k) J given (C order, their first and last
        outer entries zero) and their mirror ``rrows = rows[::-1, ::-1]`` (the compiled
        assembly writes both: :mod:`lcpbench.model.large_kernel`). ``state``: a dict
        whose arrays the factor takes for its own (made there at first use, not
        zeroed: a factor from scratch writes every entry before it reads it, as
        :func:`~.twisted_kernel._pass` assigns what it reaches), for a caller that
        factors step after step (:class:`lcpbench.model.large_n.StepWork`); no two
        live factors may share one."""
        self = cls.__new__(cls)
        self.n = rows.shape[0]
        self.rows = rows
        self.restart = True
        self._fixed = None
        if state is None:
            state = {}
        if not state:
            n = self.n
            state.update(R=np.empty((3, n)), filled=np.empty(n, np.bool_),
                         snap=np.empty((n, 4)), inv=np.empty(n))
        self.R, self._filled = state["R"], state["filled"]
        self._snap, self._inv = state["snap"], state["inv"]
        self._state(rrows, state)
        return self

    def _state(self, rrows: np.ndarray, state: dict | None = None) -> None:
        n = self.n
        self.rrows = rrows
        if state is None:
            state = {}
        if "B" not in state:
            state.update(B=np.empty((3, n)), bfilled=np.empty(n, np.bool_),
                         bsnap=np.empty((n, 4)), invB=np.empty(n), tri=np.zeros(3),
                         walk_work=None)
        self.B, self._bfilled, self._bsnap = state["B"], state["bfilled"], state["bsnap"]
        self._invB, self._tri = state["invB"], state["tri"]
        self._m = n // 2
        self._spring = NO_SPRING  # √k of the springs of the face factored last (none)
        self.rows_touched = 0
        self._walk_work: tuple | None = state["walk_work"]  # walk's (made at first use)
        self._shared = state

    def _twist(self, fixed: np.ndarray, spring: np.ndarray) -> tuple[int, int, int]:
        """(j0, k0, m): where the two passes restart for the face ``fixed``, and the twist."""
        n = self.n
        if self._fixed is None:
            j0, k0, m = 0, 0, n // 2
        else:
            differ = fixed != self._fixed
            if spring.size or self._spring.size:  # a spring changed is a face changed
                differ |= _springs(spring, self.n) != _springs(self._spring, self.n)
            changed = np.flatnonzero(differ)
            first, last = (int(changed[0]), int(changed[-1])) if changed.size else (0, -1)
            j0, k0, m = _kernel().twist(first, last, self._m, n)
        return int(j0), int(k0), int(m)

    def face_solve(self, fixed: np.ndarray, rhs: np.ndarray,
                   spring: np.ndarray | None = None) -> np.ndarray:
        """x with (H + diag(k))_face x = rhs: the ``fixed`` nodes held (identity rows),
        ``spring`` (N/mm, 0 where none; None: no springs) the stiffness k_i of the
        elastic walls' springs on the nodes they hold, rotated in as rows √k e_i
        (:func:`~.twisted_kernel.factor`: nothing grows with k)."""
        n = self.n
        fixed = np.ascontiguousarray(fixed, dtype=np.bool_)
        if n < 5:  # no room for a twist
            if spring is not None and np.any(spring > 0):
                raise ValueError("springs on a face need n >= 5 nodes")
            return super().face_solve(fixed, rhs)
        root = (NO_SPRING if spring is None or not np.any(spring)
                else np.sqrt(np.ascontiguousarray(spring, dtype=float)))
        j0, k0, m = self._twist(fixed, root)
        self._fixed = None  # invalid until the factorisation succeeds
        x = np.empty(n)
        ok = _kernel().face_solve(self.rows, self.rrows, fixed, np.ascontiguousarray(fixed[::-1]),
                                  root, np.ascontiguousarray(root[::-1]) if root.size
                                  else root, self.R, self._filled, self._snap, self.B, self._bfilled,
                                  self._bsnap, self._tri, self._inv, self._invB, j0, k0, m,
                                  np.ascontiguousarray(rhs, float), x)
        if not ok:
            raise np.linalg.LinAlgError("a face of H is singular (zero pivot)")
        self._fixed, self._m, self._spring = fixed.copy(), m, root
        self.rows_touched = (m - j0) + (n - m - k0)
        return x

    def walk(self, ctl: np.ndarray, step, slack, u, g, sigma, wall, warm_up, warm_lo,
             has_lo: bool, tie: float, max_iter: int, seen: np.ndarray) -> int:
        """The dual walk's moves up to its next unviolated point, compiled
        (:func:`lcpbench.linalg.twisted_walk_kernel.walk`, its return code), after a face
        solve (the walk starts at the unconstrained minimiser); the factor is left on
        the walk's last face (``resolve`` solves with it)."""
        from ..numba_cache import kernel_module  # numba: loads or compiles at first use

        if self._fixed is None or self._spring.size:
            raise ValueError("the compiled walk starts after a face solve without springs")
        n = self.n
        ctl[0] = self._m
        prev, self._fixed = self._fixed, None  # invalid until the walk returns
        if self._walk_work is None:
            self._walk_work = (np.empty((3, n)), np.empty((2, n), np.bool_),
                               np.empty(7 * n, np.int64))  # (written before read)
            self._shared["walk_work"] = self._walk_work
        f, b, i = self._walk_work
        head = (self.rows, self.rrows, self.R, self._filled, self._snap, self.B, self._bfilled,
                self._bsnap, self._tri, self._inv, self._invB, prev, ctl, step.lower,
                step.upper, has_lo, slack, u, g, sigma, wall, warm_up, warm_lo, tie, max_iter,
                seen)
        code = kernel_module("lcpbench.linalg.twisted_walk_kernel").walk(
            *head, f[0], f[1], b[0], b[1], i[:2 * n], i[2 * n:5 * n], i[5 * n:6 * n], f[2],
            i[6 * n:])
        if code != 3:
            self._fixed, self._m, self._spring = prev, int(ctl[0]), NO_SPRING
        return int(code)

    def resolve(self, rhs: np.ndarray) -> np.ndarray:
        if self.n < 5:
            return super().resolve(rhs)
        return _kernel().resolve(self.R, self.B, self._tri, self._inv, self._invB, self._m,
                                 np.array(rhs, dtype=float))
