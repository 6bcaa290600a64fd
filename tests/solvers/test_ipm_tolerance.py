"""The interior points' tolerance at `high` (qp_clarabel.GAP_FACTOR, qp_qpsolvers._FACTORS).

At eps itself their duality gap left the contact step's near-degenerate rows (nodes
1e-9 ℓ from the wall with no reaction) carrying 1e-2 of a node's force, and lcpbench's
residuals refused the step (docs/formulations.md, "Interior points"). Checked here
against an independent exact method, Lemke's pivots, on the paper's step at N = 140.
"""

from __future__ import annotations

import numpy as np
import pytest
from energy_oracle import assert_step_kkt

from lcpbench.solvers.base import Status
from lcpbench.solvers.registry import available_backends


@pytest.fixture(scope="module")
def paper_step():
    import lcpbench
    from lcpbench.model.compiled_driver import assemble_step

    scene = lcpbench.ActuatorScene(theta=150, height=3.0, links=140)
    res = lcpbench.solve(scene, settings="high", tol=1e-10)
    return assemble_step(scene.chain(), np.asarray(res.alpha))


@pytest.mark.parametrize("backend", ["clarabel", "qpsolvers-piqp"])
def test_interior_point_step_at_high_solves_the_steps_kkt_conditions(paper_step, backend):
    """The heights solve the step's QP by its KKT conditions (tests/energy_oracle.py; H
    positive definite: one answer) and the node forces are the ones those conditions
    give at them, R = −(H u + f), to 1e-7 of the largest (cond K · eps ~1e-8 at
    N = 140; measured 2e-10)."""
    from lcpbench.model.step_solver import solve_step

    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")
    sol = solve_step(paper_step, backend, "high", formulation="heights+ruiz")
    assert sol.status is Status.SOLVED, sol.message  # lcpbench's residuals accept it
    R0 = assert_step_kkt(paper_step, sol.u)
    assert np.max(np.abs(sol.forces_net - R0)) <= 1e-7 * np.max(np.abs(R0))


def test_piqp_asks_again_at_the_second_factor_where_the_first_falls_short(monkeypatch):
    # the retry's logic (qp_qpsolvers.solve_qp), with the solver replaced by a stub that
    # runs out of iterations at the first request and solves at the second
    from lcpbench.solvers import qp_qpsolvers as Q
    from lcpbench.solvers.base import PROFILES, BoxQP, QPResult

    asked = []

    def stub(qp, settings, warm=None, *, first=True, solver=None, **kw):
        asked.append(Q.translate(settings, solver, first).get("eps_abs"))
        status = Status.MAX_ITER if first else Status.SOLVED
        return QPResult(np.zeros(2), np.zeros(2), status, iterations=7, solve_time=0.5,
                        setup_time=0.25, extra={"solver": solver})

    monkeypatch.setattr(Q, "_solve_qp", stub)
    qp = BoxQP(np.eye(2), np.ones(2), np.zeros(2), np.ones(2))
    res = Q.solve_qp(qp, PROFILES["high"], solver="piqp")
    assert asked == pytest.approx([1e-12, 1e-11])
    assert res.status is Status.SOLVED
    assert (res.iterations, res.solve_time, res.setup_time) == (14, 1.0, 0.5)  # both runs
    asked.clear()
    Q.solve_qp(qp, PROFILES["high"], solver="daqp")  # no second request: one run
    Q.solve_qp(qp, PROFILES["default"], solver="piqp")  # no tolerance asked: one run
    assert len(asked) == 2


@pytest.mark.parametrize("theta, height", [(160, 3.0), (180, 3.0)])
def test_piqp_at_high_settles_the_near_degenerate_rows(theta, height):
    # the two paper scenes PIQP missed at 1e-2 eps in heights+ruiz (results/formulations/
    # success-high.md): a node 2-3e-8 ℓ from the wall carrying 2-3e-8 F₀. Against the
    # direct minimisation of the exact energy (no contact step, no judge).
    import lcpbench
    from lcpbench.reference.energy import minimise_energy

    if "qpsolvers-piqp" not in available_backends():
        pytest.skip("qpsolvers-piqp not installed")
    scene = lcpbench.ActuatorScene(theta=theta, height=height, links=140)
    res = lcpbench.solve(scene, solver="qpsolvers-piqp", settings="high", tol=1e-9,
                         formulation="heights+ruiz")
    assert res.converged, res.reason
    start = lcpbench.solve(scene, settings="high", tol=1e-11)
    ref = minimise_energy(scene, start=start.alpha)
    F_ref = float(ref.total_force)
    F0 = max(abs(F_ref), scene.EI / scene.length ** 2)
    assert abs(float(res.total_force) - F_ref) <= 1e-7 * F0  # τ at tol 1e-9
