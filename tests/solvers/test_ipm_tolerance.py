"""The interior points' tolerance at `high` (qp_clarabel.GAP_FACTOR, qp_qpsolvers._FACTORS).

At eps itself their duality gap left the contact step's near-degenerate rows (nodes
1e-9 ℓ from the wall with no reaction) carrying 1e-2 of a node's force, and lcpbench's
residuals refused the step (docs/formulations.md, "Interior points"). Checked here
against an independent exact method, Lemke's pivots, on the paper's step at N = 140.
"""

from __future__ import annotations

import numpy as np
import pytest

from lcpbench.solvers.base import Status
from lcpbench.solvers.registry import available_backends


@pytest.fixture(scope="module")
def paper_step():
    import lcpbench
    from lcpbench.model.step import assemble_step

    scene = lcpbench.ActuatorScene(theta=150, height=3.0, links=140)
    res = lcpbench.solve(scene, settings="high", tol=1e-10)
    return assemble_step(scene.chain(), np.asarray(res.alpha))


@pytest.mark.parametrize("backend", ["clarabel", "qpsolvers-piqp"])
def test_interior_point_step_at_high_matches_lemke(paper_step, backend):
    from lcpbench.model.step_solver import solve_step

    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")
    R0 = solve_step(paper_step, "lemke", "high").forces_net
    sol = solve_step(paper_step, backend, "high", formulation="heights+ruiz")
    assert sol.status is Status.SOLVED, sol.message  # lcpbench's residuals accept it
    # node forces: Lemke and the active set agree to ~9e-9 here (cond K · eps)
    assert np.max(np.abs(sol.forces_net - R0)) <= 1e-7 * np.max(np.abs(R0))
