"""Projected Gauss–Seidel with subspace minimisation (PGS-SM), the back-end ``pgs-sm``.

Morales, Nocedal & Smelyanskiy, Numer. Math. 111 (2008) 251–266: PGS sweeps identify
the active set, a reduced Newton step on the free rows with a projected search
finishes it (:mod:`.pgs_sm_kernel`, compiled by numba). It takes a symmetric LCP
``0 <= z ⟂ M z + q >= 0`` with a positive diagonal (the QP min ½zᵀMz + qᵀz over
z >= 0); in the contact step that is F1 (the gaps) or F4 (the reactions), either
Ruiz-scaled (docs/formulations.md). It stops on lcpbench's natural residual
(:mod:`.judge`'s units and round-off floor), at ``eps``.
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import ProblemError
from ..numba_cache import kept
from .base import LCPSolution, Settings, Status
from .judge import FLOOR_ULPS
from .pgs import DEFAULT_EPS, check_inputs

#: cycles (a PGS phase and a subspace phase each) when ``Settings.max_iter`` is None
DEFAULT_MAX_CYCLES = 1000
#: PGS sweeps per cycle, and subspace steps per cycle at most
K_GS, K_SM = 2, 5
#: keyword options :func:`solve_lcp` takes
OPTIONS = ("k_gs", "k_sm")
_STATUS = {0: Status.SOLVED, 1: Status.MAX_ITER, 2: Status.FAILED}
_KERNEL: list = []  # the compiled module, once loaded


def _kernel():
    return kept(_KERNEL, "lcpbench.solvers.pgs_sm_kernel", "pgs_sm")


def _count(name, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ProblemError(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def pgs_sm(M, q, *, eps: float = 1e-10, max_cycles: int = DEFAULT_MAX_CYCLES,
           k_gs: int = K_GS, k_sm: int = K_SM, z0=None) -> LCPSolution:
    """Solve a symmetric LCP by PGS-SM.

    Parameters
    ----------
    M, q : the LCP (M symmetric, positive diagonal; dense, a sparse M is densified).
    eps : the natural residual max |min(z, w)| / max(1, |q|∞) to stop at (or its
        round-off floor, :data:`.judge.FLOOR_ULPS` · eps · max_i Σ_j |M_ij z_j| + |q_i|).
    max_cycles : cycles budget (MAX_ITER when spent).
    k_gs, k_sm : PGS sweeps per cycle; subspace steps per cycle at most.
    z0 : a start (projected onto z >= 0); default 0.

    Returns
    -------
    LCPSolution
        ``iterations`` counts cycles; ``extra`` holds ``sweeps``, ``subspace_steps``
        and ``residual`` (the stopping test's). A non-symmetric M or a non-positive
        diagonal is FAILED with the reason (the method minimises ½zᵀMz + qᵀz).
    """
    t0 = time.perf_counter()
    M, q, _, eps, max_cycles, z = check_inputs(M, q, 1.0, eps, max_cycles, z0, None)
    k_gs, k_sm = _count("k_gs", k_gs), _count("k_sm", k_sm)
    n = q.size
    nan = np.full(n, np.nan)
    asym = float(np.max(np.abs(M - M.T), initial=0.0))
    if asym > 1e-12 * max(float(np.max(np.abs(M))), 1e-300):
        return LCPSolution(nan, nan.copy(), Status.FAILED, setup_time=time.perf_counter() - t0,
                           message=f"pgs-sm needs symmetric M (max |M - Mᵀ| = {asym:.2g})")
    diag = M.diagonal()
    if not np.all(diag > 0.0):
        i = int(np.flatnonzero(~(diag > 0.0))[0])
        return LCPSolution(nan, nan.copy(), Status.FAILED, setup_time=time.perf_counter() - t0,
                           message=f"pgs-sm needs M_ii > 0; M[{i}, {i}] = {diag[i]:g}")
    M = np.ascontiguousarray(0.5 * (M + M.T))
    kernel = _kernel()
    setup = time.perf_counter() - t0
    t1 = time.perf_counter()
    code, cycles, sweeps, steps, res, w = kernel.pgs_sm(M, q, z, eps, max_cycles, k_gs, k_sm,
                                                        float(FLOOR_ULPS))
    solve = time.perf_counter() - t1
    status = _STATUS[int(code)]
    message = "" if status is Status.SOLVED else (
        f"cycle budget {max_cycles} exhausted (relative residual {res:.3g} > eps {eps:g})"
        if status is Status.MAX_ITER else f"non-finite iterate after {cycles} cycles")
    return LCPSolution(z, M @ z + q, status, int(cycles), solve, setup, message,
                       extra={"sweeps": int(sweeps), "subspace_steps": int(steps),
                              "residual": float(res), "eps": eps})


def solve_lcp(M, q, settings: Settings, warm=None, **options) -> LCPSolution:
    """Adapter of :func:`pgs_sm` to :class:`Settings`: ``eps`` (None: 1e-8) is the
    stopping test's tolerance, ``max_iter`` (None: 1000) the cycle budget; options
    ``k_gs``, ``k_sm``."""
    unknown = sorted(set(options) - set(OPTIONS))
    if unknown:
        raise ProblemError(f"unknown pgs-sm option(s) {', '.join(unknown)}; allowed: "
                           f"{', '.join(OPTIONS)}")
    eps = DEFAULT_EPS if settings.eps is None else settings.eps
    cycles = DEFAULT_MAX_CYCLES if settings.max_iter is None else settings.max_iter
    return pgs_sm(M, q, eps=eps, max_cycles=cycles, z0=warm, **options)
