"""Kernel bails caused by round-off below LARGE_N, and the dense fallback (issue 19, item 3): O(N) steps.

Near N = 4000 the compiled kernel in node heights sometimes stops because a step
judge rejected its own step (cond H ~ N⁴). The numpy reference in heights met the
same round-off, its step solver fell back to a dense Lemke step, and one solve at
N = 3999 took 97 s. :func:`lcpbench.model.compiled.reference` now solves such a
chain in increments on the tridiagonal factor, as from ``LARGE_N`` links. Whether
a given scene bails depends on round-off, so on the machine: these tests call the
route with the bail reason given, and check the property that holds everywhere
(no dense step at N = 3999).
"""

from __future__ import annotations

import pytest
from energy_oracle import assert_solved

from lcpbench import ActuatorScene, solve
from lcpbench.api import solve_internal
from lcpbench.model import compiled, large_n, step_solver
from lcpbench.model.judge import force_tol
from lcpbench.model.kernel_call import BAIL_REASONS
from lcpbench.model.step_solver import make_step_solver

STEP_REJECTED = BAIL_REASONS[15]


def _make_step():
    return make_step_solver("active-set", "default", True)


def test_a_round_off_bail_at_n_3999_is_solved_in_increments(monkeypatch):
    scene = ActuatorScene(90, 2.0, links=3999)
    chain = scene.chain()
    out, used = compiled.reference(chain, _make_step, STEP_REJECTED, tol=1e-9,
                                   max_outer=200, method="globalised")
    assert out.converged and "increments" in used and STEP_REJECTED in used
    # the same scene solved in increments from the rest shape (LARGE_N lowered)
    monkeypatch.setattr(large_n, "LARGE_N", 10)
    cold = solve(scene, tol=1e-9)
    assert cold.converged and "increments" in cold.engine
    assert_solved(cold)  # the equilibrium by first principles (tests/energy_oracle.py), ~6 s
    F = float(out.forces_upper.sum())
    assert abs(F - cold.total_force) / cold.judgement.force_unit <= force_tol(1e-9)


def test_a_refused_step_at_small_n_is_reported_with_its_reason():
    # N = 140: cond H · ε ≈ 1.4e-8, below the step's accuracy: no increments; the kernel's
    # own step was refused, so no numpy rerun of its scheme either: not converged, the
    # kernel's reason said, for the escalations to take over
    chain = ActuatorScene(150, 3.0, links=140).chain()
    out, used = compiled.reference(chain, _make_step, STEP_REJECTED, tol=1e-3,
                                   max_outer=200, method="globalised")
    assert not out.converged and STEP_REJECTED in out.reason and STEP_REJECTED in used
    assert not out.steps


def test_the_route_asks_the_steps_accuracy_of_the_settings():
    # N = 140: cond H · ε = (2N/π)⁴ ε ≈ 1.4e-8 lies between settings "high" (1e-9) and the
    # default (1e-6): heights may keep a step from 1e-9, not from 1e-6
    assert compiled.step_request("default") == 1e-6 and compiled.step_request("high") == 1e-9
    chain = ActuatorScene(150, 3.0, links=140).chain()
    cond_eps = large_n.heights_condition(chain.links) * 2.0**-52
    assert 1e-9 < cond_eps < 1e-6
    out, used = compiled.reference(chain, lambda: make_step_solver("active-set", "high", True),
                                   STEP_REJECTED, tol=1e-3, max_outer=200,
                                   method="globalised", settings="high")
    assert out.converged and "increments" in used


@pytest.fixture
def dense_steps(monkeypatch):
    """The (back-end, free nodes) of every step a dense back-end is run on, as solved."""
    seen = []
    run = step_solver._run_step

    def watched(backend, step, s, scaled, warm):
        if backend.storage == "dense":
            seen.append((backend.name, step.size))
        return run(backend, step, s, scaled, warm)

    monkeypatch.setattr(step_solver, "_run_step", watched)
    return seen


def test_no_solve_at_n_3999_goes_to_the_reference_in_heights():
    # whichever of these scenes bails on this machine, none may go to a driver in node
    # heights (where the active set met the same round-off and fell back to dense
    # Lemke, 97 s): the route of a round-off bail is increments
    for theta, h in ((90, 2.0), (170, 5.0), (150, 3.0), (120, 1.0)):
        for tol in (1e-3, 1e-9):
            res = solve(ActuatorScene(theta, h, links=3999), tol=tol)
            assert res.converged, res.reason
            bailed = "the compiled kernel stopped" in res.engine
            assert not bailed or "increments" in res.engine


def test_the_dense_fallback_is_refused_above_its_size():
    assert step_solver.dense_fallback_refused("lemke", step_solver.MAX_DENSE_FALLBACK) is None
    why = step_solver.dense_fallback_refused("lemke", step_solver.MAX_DENSE_FALLBACK + 1)
    assert why is not None and f"n = {step_solver.MAX_DENSE_FALLBACK + 1}" in why
    assert step_solver.dense_fallback_refused("active-set", 10**5) is None  # banded


def test_past_the_vertical_at_n_3000_the_cold_start_fails_without_a_dense_step(dense_steps):
    # θ > 180°: the linearisation is singular at the end links and the cold start fails
    # (documented; the answer then comes by the loading path); before, each uncertified
    # step fell back to dense Lemke, minutes
    for engine in ("auto",):
        res = solve_internal(ActuatorScene(200, 3.0, links=3000), tol=1e-3, engine=engine)
        assert "theta > 180 deg" in res.retried("ramped")
    assert all(n <= step_solver.MAX_DENSE_FALLBACK for _, n in dense_steps)


def test_a_roundoff_stop_past_large_n_without_increments_is_a_reason_not_minutes(monkeypatch):
    """From LARGE_N links a kernel stop for round-off on a chain no increment formulation
    takes (a joint layout other than large_n.layout_fits) ends the solve with a reason
    naming the limit, instead of the numpy reference in heights (the same round-off,
    and O(N³) Lemke fallbacks); flat rigid, elastic and profiled walls keep their
    increments (every wall model is a parameter of the increment assembly)."""
    n = large_n.LARGE_N
    soft = ActuatorScene(theta=150, height=3.0, links=n, wall_stiffness=10.0).chain()
    rigid = ActuatorScene(theta=150, height=3.0, links=n).chain()
    for chain in (soft, rigid):
        assert not compiled.beyond_heights(chain, BAIL_REASONS[12])  # increments take it
    monkeypatch.setattr(large_n, "layout_fits", lambda chain: False)  # another layout
    assert compiled.beyond_heights(soft, BAIL_REASONS[12])
    assert compiled.beyond_heights(soft, BAIL_REASONS[11])
    assert not compiled.beyond_heights(soft, BAIL_REASONS[10])  # crossed walls: not round-off
    small = ActuatorScene(theta=150, height=3.0, links=n - 1, wall_stiffness=10.0).chain()
    assert not compiled.beyond_heights(small, BAIL_REASONS[12])
    out = compiled.out_of_reach(soft, BAIL_REASONS[12])
    assert not out.converged and f"N = {n}" in out.reason and "increment" in out.reason
