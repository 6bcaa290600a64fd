"""Brute-force reference for tiny LCPs: every complementary basis, tried in turn.

Solves ``M_SS z_S = −q_S`` for each of the 2^n index sets S and keeps the
feasible ones. Exponential, so only for n <= ~16: it is the independent
reference the tests compare every back-end with, and it says whether a small
problem has a solution at all.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator

import numpy as np


def complementary_solutions(M, q, eps: float = 1e-9) -> Iterator[np.ndarray]:
    """Yield every solution z found among the complementary bases (feasible to eps)."""
    M = np.asarray(M, dtype=float)
    q = np.asarray(q, dtype=float).ravel()
    n = q.size
    scale = max(1.0, float(np.abs(q).max(initial=0.0)))
    for mask in itertools.product([False, True], repeat=n):
        a = np.flatnonzero(mask)
        z = np.zeros(n)
        if a.size:
            try:
                z[a] = np.linalg.solve(M[np.ix_(a, a)], -q[a])
            except np.linalg.LinAlgError:
                continue
        w = M @ z + q
        if z.min(initial=0.0) >= -eps * scale and w.min(initial=0.0) >= -eps * scale:
            yield z


def enumerate_lcp(M, q, eps: float = 1e-9) -> list[np.ndarray]:
    """All solutions found among the 2^n complementary bases."""
    return list(complementary_solutions(M, q, eps))


def has_solution(M, q, eps: float = 1e-9, max_size: int = 16) -> bool | None:
    """Whether the LCP has a solution; None when n > max_size (too many bases)."""
    if np.asarray(q).size > max_size:
        return None
    return next(complementary_solutions(M, q, eps), None) is not None
