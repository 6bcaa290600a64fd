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
NONE = np.zeros(0)  # no node held by a spring


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
        assert ldl.refactor(fac, bands, fixed, NONE, 0, n)
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
        assert ldl.refactor(fac, bands, fixed, NONE, 0, n)
        for _ in range(5):  # a walk of faces, each refactored two columns before its first change
            new = fixed.copy()
            flip = rng.integers(0, n, size=int(rng.integers(1, 3)))
            new[flip] = ~new[flip]
            changed = np.flatnonzero(new != fixed)
            c0 = max(0, int(changed[0]) - 2) if changed.size else n
            assert ldl.refactor(fac, bands, new, NONE, c0, n)
            full = np.zeros((4, n))
            assert ldl.refactor(full, bands, new, NONE, 0, n)
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
    assert ldl.refactor(fac, bands, fixed, NONE, 0, n)
    new = fixed.copy()
    new[8] = True
    assert ldl.refactor(fac, bands, new, NONE, 6, 17)
    full = np.zeros((4, n))
    assert ldl.refactor(full, bands, new, NONE, 0, n)
    assert np.array_equal(fac, full)


def test_an_indefinite_face_is_reported():
    rng = np.random.default_rng(6)
    for _ in range(40):
        n = int(rng.integers(2, 30))
        bands, H = spd_bands(rng, n, shift=float(rng.uniform(0.0, 2.5)))
        fixed = rng.random(n) < 0.2
        definite = np.linalg.eigvalsh(face(H, fixed)).min() > 1e-9
        indefinite = np.linalg.eigvalsh(face(H, fixed)).min() < -1e-9
        ok = ldl.refactor(np.zeros((4, n)), bands, fixed, NONE, 0, n)
        if definite:
            assert ok
        if indefinite:
            assert not ok


def spring_face(H, fixed, shift):
    """The face with the nodes of ``shift`` > 0 kept, their spring 1/shift added."""
    F = face(H, fixed)
    soft = shift > 0
    F[soft, soft] += 1.0 / shift[soft]
    return F


@pytest.mark.parametrize("seed", [7, 8])
def test_spring_columns_solve_the_face_with_the_springs(seed):
    """A node held by a spring of compliance c keeps its row with 1/c on the diagonal
    (elastic walls): the factor solves that matrix as a dense solve does, from soft
    springs to stiff ones."""
    rng = np.random.default_rng(seed)
    for _ in range(40):
        n = int(rng.integers(2, 50))
        bands, H = spd_bands(rng, n)
        fixed = rng.random(n) < 0.2
        shift = np.where(~fixed & (rng.random(n) < 0.3), 10.0 ** rng.uniform(-9, 2, n), 0.0)
        F = spring_face(H, fixed, shift)
        fac = np.zeros((4, n))
        assert ldl.refactor(fac, bands, fixed, shift, 0, n)
        rhs = rng.standard_normal(n)
        x = ldl.resolve(fac, rhs.copy())
        exact = np.linalg.solve(F, rhs)
        assert np.allclose(x, exact, rtol=0, atol=1e-12 * np.max(np.abs(exact)) * np.linalg.cond(F))


def test_the_rigid_wall_is_the_limit_of_stiff_springs():
    """As c → 0 a spring's column tends to a fixed node's: the solutions of right-hand
    sides that vanish on the held nodes (as the walk's do) converge to the fixed face's,
    with an error of order c (no loss of accuracy as the stiffness 1/c grows)."""
    rng = np.random.default_rng(9)
    n = 40
    bands, H = spd_bands(rng, n)
    held = rng.random(n) < 0.3
    rhs = np.where(held, 0.0, rng.standard_normal(n))
    fixed_fac = np.zeros((4, n))
    assert ldl.refactor(fixed_fac, bands, held, NONE, 0, n)
    rigid = ldl.resolve(fixed_fac, rhs.copy())
    errors = []
    for c in (1e-4, 1e-8, 1e-12, 1e-16):
        fac = np.zeros((4, n))
        assert ldl.refactor(fac, bands, np.zeros(n, bool), np.where(held, c, 0.0), 0, n)
        errors.append(np.max(np.abs(ldl.resolve(fac, rhs.copy()) - rigid)))
    scale = np.max(np.abs(rigid)) * np.max(np.abs(bands))
    for c, err in zip((1e-4, 1e-8, 1e-12, 1e-16), errors):
        assert err <= 10 * c * scale + 1e-13 * np.max(np.abs(rigid))


def test_a_restart_after_a_spring_changes_is_the_factor_from_the_start():
    """A change of a node's spring is a change of the face: refactored from two columns
    before it, the factor is the one from the start."""
    rng = np.random.default_rng(10)
    n = 30
    bands, _ = spd_bands(rng, n)
    fixed = rng.random(n) < 0.2
    shift = np.where(~fixed & (rng.random(n) < 0.3), 1e-3, 0.0)
    fac = np.zeros((4, n))
    assert ldl.refactor(fac, bands, fixed, shift, 0, n)
    new = shift.copy()
    j = int(np.flatnonzero(~fixed)[len(np.flatnonzero(~fixed)) // 2])
    new[j] = 0.5 if new[j] == 0 else 0.0
    assert ldl.refactor(fac, bands, fixed, new, max(0, j - 2), n)
    full = np.zeros((4, n))
    assert ldl.refactor(full, bands, fixed, new, 0, n)
    assert np.array_equal(fac, full)
