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
