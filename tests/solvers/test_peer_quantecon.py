"""QuantEcon's Lemke as a peer back-end: registered, judged like every back-end, optional."""

import numpy as np
import pytest

from lcpbench.errors import SolverNotFound
from lcpbench.solvers import registry, solve_lcp
from lcpbench.solvers.base import Status

quantecon = pytest.importorskip("quantecon")


def test_registered_as_an_exact_dense_lcp_peer():
    b = registry.backends()["quantecon-lemke"]
    assert (b.form, b.storage, b.method, b.exact, b.extra) == ("lcp", "dense", "pivoting",
                                                               True, "peer")
    assert b.available() and b.version() == quantecon.__version__


def test_murty_example_and_agreement_with_lcpbench_lemke():
    # the docstring example of lcp_lemke, worked by hand: z = (8, 0, 0), w = (0, 4, 2)
    M = np.array([[1.0, 0, 0], [2, 1, 0], [2, 2, 1]])
    q = np.array([-8.0, -12, -14])
    sol = solve_lcp(M, q, "quantecon-lemke")
    assert sol.status is Status.SOLVED
    np.testing.assert_allclose(sol.z, [8, 0, 0], atol=1e-12)
    np.testing.assert_allclose(sol.w, [0, 4, 2], atol=1e-12)
    # a P-matrix LCP has one solution: both Lemkes must find it
    rng = np.random.default_rng(3)
    for n in (5, 20, 60):
        A = rng.standard_normal((n, n))
        M = A @ A.T + n * np.eye(n)
        q = rng.standard_normal(n)
        a, b = solve_lcp(M, q, "quantecon-lemke"), solve_lcp(M, q, "lemke")
        assert a.status is Status.SOLVED and b.status is Status.SOLVED
        np.testing.assert_allclose(a.z, b.z, atol=1e-9 * max(1.0, np.abs(b.z).max()))


def test_a_wrong_answer_it_calls_solved_is_demoted_by_lcpbench(monkeypatch):
    import quantecon.optimize as qo

    real = qo.lcp_lemke

    def lying(M, q, **kw):
        res = real(M, q, **kw)
        return res._replace(z=res.z + 0.5, status=0, success=True)  # wrong, "found"

    monkeypatch.setattr(qo, "lcp_lemke", lying)
    M = np.eye(3) * 2.0
    q = np.array([-1.0, 1.0, -3.0])
    sol = solve_lcp(M, q, "quantecon-lemke")
    assert sol.status is Status.INACCURATE and "natural residual" in sol.message


def test_ray_and_budget_statuses():
    # no solution: z >= 0, w = -z - 1 >= 0 is infeasible; Lemke ends on a ray
    sol = solve_lcp(np.array([[-1.0]]), np.array([-1.0]), "quantecon-lemke")
    assert sol.status is Status.RAY
    # the pivot budget is max(100, 50 n) unless the settings give one
    from lcpbench.solvers.base import Settings

    rng = np.random.default_rng(0)
    A = rng.standard_normal((30, 30))
    M, q = A @ A.T + np.eye(30), -np.abs(rng.standard_normal(30)) - 1
    sol = solve_lcp(M, q, "quantecon-lemke", Settings("tight", None, max_iter=2))
    assert sol.status is Status.MAX_ITER and sol.iterations == 2


def test_missing_quantecon_is_a_clean_skip(monkeypatch):
    real = registry._has_module
    monkeypatch.setattr(registry, "_has_module", lambda m: m != "quantecon" and real(m))
    assert "quantecon-lemke" not in registry.available_backends()
    assert not registry.backends()["quantecon-lemke"].capabilities()["available"]
    with pytest.raises(SolverNotFound, match=r"lcpbench\[peer\]"):
        registry.get_backend("quantecon-lemke")
