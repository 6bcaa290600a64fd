"""The banded LDLᵀ of a face (linalg/ldl_kernel.py), the dual walk's face solves.

Checked against independent computations: a dense solve of the same face
(numpy), the face's definiteness from its eigenvalues, and, for a factorisation
restarted at a later column, the factorisation of the same face from the start
(the restart replays the loop's own updates, so the two agree bit for bit, but
for the sign of a zero, which ``==`` does not see).
"""

from __future__ import annotations

import numpy as np
import pytest

from lcpbench.numba_cache import kernel_module

ldl = kernel_module("lcpbench.linalg.ldl_kernel")


def spd_bands(rng, n, shift=0.0):
    """A random symmetric pentadiagonal H (lower band storage), positive definite
    (diagonally dominant by at least 0.5) unless ``shift`` moves its spectrum down;
    and H dense."""
    bands = rng.standard_normal((3, n))
    bands[1, -1:] = 0.0
    bands[2, -2:] = 0.0
    off = np.abs(bands[1:])
    row = off.sum(axis=0) + np.concatenate([[0.0], off[0, :-1]]) + np.concatenate(
        [[0.0, 0.0], off[1, :-2]])[:n]
    bands[0] = row + 0.5 + np.abs(bands[0]) - shift
    H = np.zeros((n, n))
    for p in range(3):
        for i in range(n - p):
            H[i + p, i] = H[i, i + p] = bands[p, i]
    return bands, H


def face(H, fixed):
    F = H.copy()
    F[fixed, :] = 0.0
    F[:, fixed] = 0.0
    F[fixed, fixed] = 1.0
    return F


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_face_solves_match_dense_solves(seed):
    rng = np.random.default_rng(seed)
    for _ in range(40):
        n = int(rng.integers(1, 60))
        bands, H = spd_bands(rng, n)
        fixed = rng.random(n) < 0.3
        F = face(H, fixed)
        fac = np.zeros((4, n))
        assert ldl.refactor(fac, bands, fixed, 0, n)
        rhs = rng.standard_normal(n)
        x = ldl.resolve(fac, rhs.copy())
        exact = np.linalg.solve(F, rhs)
        assert np.allclose(x, exact, rtol=0, atol=1e-12 * np.linalg.cond(F) * np.max(np.abs(exact)))


@pytest.mark.parametrize("seed", [3, 4])
def test_a_restarted_factor_is_the_factor_from_the_start(seed):
    rng = np.random.default_rng(seed)
    for _ in range(60):
        n = int(rng.integers(3, 50))
        bands, _ = spd_bands(rng, n)
        fixed = rng.random(n) < 0.3
        fac = np.zeros((4, n))
        assert ldl.refactor(fac, bands, fixed, 0, n)
        for _ in range(5):  # a walk of faces, each refactored two columns before its first change
            new = fixed.copy()
            flip = rng.integers(0, n, size=int(rng.integers(1, 3)))
            new[flip] = ~new[flip]
            changed = np.flatnonzero(new != fixed)
            c0 = max(0, int(changed[0]) - 2) if changed.size else n
            assert ldl.refactor(fac, bands, new, c0, n)
            full = np.zeros((4, n))
            assert ldl.refactor(full, bands, new, 0, n)
            assert np.array_equal(fac, full)
            fixed = new


def test_the_columns_after_two_fixed_nodes_stand():
    """Nodes c1 − 2 and c1 − 1 fixed in both faces cut H in two: refactoring up to
    c1 leaves a factor equal to the new face's (its columns from c1 on unchanged)."""
    rng = np.random.default_rng(5)
    n = 30
    bands, _ = spd_bands(rng, n)
    fixed = np.zeros(n, bool)
    fixed[[15, 16]] = True
    fac = np.zeros((4, n))
    assert ldl.refactor(fac, bands, fixed, 0, n)
    new = fixed.copy()
    new[8] = True
    assert ldl.refactor(fac, bands, new, 6, 17)
    full = np.zeros((4, n))
    assert ldl.refactor(full, bands, new, 0, n)
    assert np.array_equal(fac, full)


def test_an_indefinite_face_is_reported():
    rng = np.random.default_rng(6)
    for _ in range(40):
        n = int(rng.integers(2, 30))
        bands, H = spd_bands(rng, n, shift=float(rng.uniform(0.0, 2.5)))
        fixed = rng.random(n) < 0.2
        definite = np.linalg.eigvalsh(face(H, fixed)).min() > 1e-9
        indefinite = np.linalg.eigvalsh(face(H, fixed)).min() < -1e-9
        ok = ldl.refactor(np.zeros((4, n)), bands, fixed, 0, n)
        if definite:
            assert ok
        if indefinite:
            assert not ok
