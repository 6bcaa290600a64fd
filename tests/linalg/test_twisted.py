"""The twisted QR of the large-N face solves (:mod:`lcpbench.linalg.twisted`).

Properties: every face solve equals a dense solve of the same face (H with the
fixed rows and columns the identity), along walks of faces that restart from
the last factor; a face change refactors only the rows between its first and
last change and the last twist, however long the chain.
"""

from __future__ import annotations

import numpy as np
import pytest

from lcpbench.linalg.twisted import TwistedFactor


def _dense(coef, k):
    n = coef.shape[0]
    A = np.zeros((n, n))
    for j in range(n):
        for m in range(3):
            c = j - 1 + m
            if 0 <= c < n:
                A[j, c] = coef[j, m] * np.sqrt(k[j])
    return A.T @ A


def _face(H, fixed):
    F = H.copy()
    F[fixed, :] = 0.0
    F[:, fixed] = 0.0
    F[fixed, fixed] = 1.0
    return F


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_twisted_face_solves_match_dense_solves_along_a_walk(seed):
    rng = np.random.default_rng(seed)
    for _ in range(40):
        n = int(rng.integers(3, 50))
        coef = rng.standard_normal((n, 3))
        coef[:, 1] += 3.0
        k = rng.uniform(0.5, 2.0, n)
        H = _dense(coef, k)
        fac = TwistedFactor(coef, k)
        fixed = rng.random(n) < 0.3
        for _ in range(8):  # each face restarts from the last one's factor
            flip = rng.integers(0, n, size=int(rng.integers(0, 3)))
            fixed[flip] = ~fixed[flip]
            rhs = rng.standard_normal(n)
            expected = np.linalg.solve(_face(H, fixed), rhs)
            scale = np.max(np.abs(expected))
            assert np.max(np.abs(fac.face_solve(fixed, rhs) - expected)) <= 1e-9 * scale
            # resolve(): the same face's factor again (no refinement)
            assert np.max(np.abs(fac.resolve(rhs) - expected)) <= 1e-7 * scale


@pytest.mark.parametrize("seed", [0, 1])
def test_faces_with_springs_match_dense_solves_along_a_walk(seed):
    # an elastic wall's spring k on a node it holds: (H + diag(k))_face, springs from
    # 1e-3 to 1e12 of H's entries, changing node by node as a walk's sets do
    rng = np.random.default_rng(seed)
    for _ in range(30):
        n = int(rng.integers(5, 50))
        coef = rng.standard_normal((n, 3))
        coef[:, 1] += 3.0
        k = rng.uniform(0.5, 2.0, n)
        H = _dense(coef, k)
        fac = TwistedFactor(coef, k)
        fixed = rng.random(n) < 0.2
        spring = np.where(rng.random(n) < 0.4, 10.0 ** rng.uniform(-3, 12, n), 0.0)
        for _ in range(8):
            flip = rng.integers(0, n, size=int(rng.integers(0, 3)))
            spring[flip] = np.where(spring[flip] > 0, 0.0, 10.0 ** rng.uniform(-3, 12))
            rhs = rng.standard_normal(n)
            face = _face(H + np.diag(np.where(fixed, 0.0, spring)), fixed)
            expected = np.linalg.solve(face, rhs)
            got = fac.face_solve(fixed, rhs, np.where(fixed, 0.0, spring))
            assert np.max(np.abs(got - expected)) <= 1e-8 * np.max(np.abs(expected))


def test_a_stiff_spring_is_the_fixed_node_in_the_limit():
    # the rigid wall as k → ∞: the free nodes' solution tends to that of the face with
    # the node fixed (rhs 0 there), at the rate 1/k
    rng = np.random.default_rng(3)
    n = 40
    coef = rng.standard_normal((n, 3))
    coef[:, 1] += 3.0
    k = rng.uniform(0.5, 2.0, n)
    fac = TwistedFactor(coef, k)
    held = np.zeros(n, bool)
    held[[7, 8, 21]] = True
    rhs = rng.standard_normal(n)
    rhs[held] = 0.0
    rigid = fac.face_solve(held, rhs)
    prev = np.inf
    for stiff in (1e4, 1e8, 1e12, 1e16):
        x = fac.face_solve(np.zeros(n, bool), rhs, np.where(held, stiff, 0.0))
        err = float(np.max(np.abs(x - rigid)))
        assert err <= 1e2 / stiff + 1e-13 and err <= prev + 1e-15
        prev = err


@pytest.mark.parametrize("n", [2_000, 20_000])
def test_a_face_change_refactors_locally(n):
    rng = np.random.default_rng(5)
    coef = rng.standard_normal((n, 3))
    coef[:, 1] += 3.0
    k = np.ones(n)
    fac = TwistedFactor(coef, k)
    fixed = np.zeros(n, bool)
    fixed[[n // 2 - 300, n // 2 + 300]] = True  # two contacts near the middle
    fac.face_solve(fixed, np.ones(n))
    assert fac.rows_touched == n  # the first face: every row once
    for node in (n // 2 - 300, n // 2 - 301, n // 2 + 302, n // 2 - 299):
        fixed[node] = ~fixed[node]
        fac.face_solve(fixed, np.ones(n))
        # between the change and the last twist (the middle), not the chain's end
        assert fac.rows_touched <= 2 * 310
    # and the answer is still the face's (against a fresh factorisation)
    rhs = rng.standard_normal(n)
    fresh = TwistedFactor(coef, k)
    np.testing.assert_allclose(fac.face_solve(fixed, rhs), fresh.face_solve(fixed, rhs),
                               rtol=0, atol=1e-10 * np.max(np.abs(fresh.face_solve(fixed, rhs))))
