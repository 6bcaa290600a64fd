"""solve_lcp refuses what it cannot solve faithfully, before any back-end runs."""

import numpy as np
import pytest
import scipy.sparse as sp

from lcpbench import ProblemError
from lcpbench.solvers import solve_lcp


@pytest.mark.parametrize("backend", ["lemke", "pgs"])
def test_empty_problem_is_refused(backend):
    with pytest.raises(ProblemError, match=r"^M must be at least 1x1"):
        solve_lcp(np.zeros((0, 0)), np.zeros(0), backend)


@pytest.mark.parametrize("M,q,name,kind", [
    (np.eye(2) * (1 + 1j), -np.ones(2), "M", "complex"),
    (np.eye(2), -np.ones(2) + 0j, "q", "complex"),  # a zero imaginary part is still complex
    (np.eye(2, dtype=bool), -np.ones(2), "M", "bool"),
    (np.eye(2), np.array([True, False]), "q", "bool"),
    (np.array([["1", "0"], ["0", "1"]]), -np.ones(2), "M", "<U1"),
    (np.eye(2), [None, -1.0], "q", "object"),
])
def test_non_real_data_is_refused_not_cast(M, q, name, kind):
    with pytest.raises(ProblemError, match=rf"^{name} must be a real numeric array .*{kind}"):
        solve_lcp(M, q, "lemke")


def test_integer_and_sparse_input_still_accepted():
    # z = max(0, -q / diag): diagonal M, known answer
    sol = solve_lcp(sp.csr_matrix(np.diag([2, 4])), np.array([-2, 4]), "lemke")
    assert sol.solved
    np.testing.assert_allclose(sol.z, [1.0, 0.0])


def test_shape_mismatch_named():
    with pytest.raises(ProblemError, match=r"M must be square of size len\(q\) = 3"):
        solve_lcp(np.eye(2), np.ones(3), "lemke")


# -- the default back-end of `lcpbench lcp` (issue 36) -------------------------------------
@pytest.mark.parametrize("M, name, why", [
    ([[2.0, 1.0], [1.0, 2.0]], "active-set", "M is symmetric positive definite"),
    ([[1.0, 2.0], [2.0, 1.0]], "lemke", "M is symmetric but not positive definite"),  # -1, 3
    ([[1.0, 1.0], [1.0, 1.0]], "lemke", "M is symmetric but not positive definite"),  # 0, 2
    ([[1.0, 2.0], [0.0, 1.0]], "lemke", "M is not symmetric"),
])
def test_default_lcp_solver_by_the_kind_of_m(M, name, why):
    from lcpbench.solvers.runner import default_lcp_solver

    assert default_lcp_solver(np.array(M)) == (name, why)


def test_default_lcp_solver_refuses_lemke_above_its_size_limit():
    from lcpbench.solvers import runner

    n = runner.LEMKE_DEFAULT_MAX_SIZE + 1
    M = np.eye(n) + np.triu(np.ones((n, n)), 1)  # Murty's kind: upper triangular
    with pytest.raises(ProblemError) as info:
        runner.default_lcp_solver(M)
    msg = str(info.value)
    assert msg.startswith("solver: M is not symmetric") and "\n" not in msg
    assert f"up to n = {runner.LEMKE_DEFAULT_MAX_SIZE}" in msg and f"n = {n}" in msg
    assert "--solver" in msg and "pgs" in msg
    # a symmetric positive definite M of any size goes to the active set
    assert runner.default_lcp_solver(np.eye(n) * 2.0)[0] == "active-set"
