"""The frictional step by a back-end's name (issue 39, item 3): the registry says which
back-end takes the step in which form, ``solve_path(..., solver=NAME)`` and
``lcpbench solve --friction ... --solver NAME`` reach them, and their answers agree with
Lemke's (an independent method: complementary pivoting on the step's LCP)."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.cli import main
from lcpbench.errors import ProblemError, SolverNotFound
from lcpbench.model.friction_driver import FrictionState, frictional_step
from lcpbench.model.friction_solvers import fc2d_contacts, judged, lcp_z, step_runner
from lcpbench.solvers.base import LCPSolution, Status
from lcpbench.solvers.registry import backends
from lcpbench.solvers.siconos_fc2d import coulomb_residual

SCENE = ActuatorScene(theta=150, height=3.0, links=30, friction=0.3, left_end="slider",
                      right_end="slider")
PATH = [{}, {"pull": 0.05}, {"pull": 0.0}]


def test_the_registry_says_how_each_backend_takes_the_frictional_step():
    b = backends()
    assert b["lemke"].friction_form == "lcp"
    assert b["active-set"].friction_form == "fc2d"
    assert b["siconos-lemke"].friction_form == "fc2d"
    assert b["osqp"].friction_form == "tresca" and b["clarabel"].friction_form == "tresca"
    assert b["pgs"].friction_form is None  # its diagonal has zeros (the λ rows)
    assert b["osqp"].capabilities()["friction"] == "tresca"


def test_a_backend_without_friction_or_two_solvers_is_one_clear_error():
    with pytest.raises(ProblemError, match="does not take the frictional step"):
        lcpbench.solve_path(SCENE, solver="pgs")
    with pytest.raises(SolverNotFound, match="unknown solver"):
        lcpbench.solve_path(SCENE, solver="nosuch")
    with pytest.raises(ProblemError, match="not both"):
        lcpbench.solve_path(SCENE, solver="lemke", lcp=lambda M, q: None)


def contact_runs(res):
    """Runs of consecutive nodes within 1e-3 a of the wall (a horizontal force moves
    between them at no cost the step sees: T per node is not an answer there)."""
    a = res.scene.length / res.links
    idx = np.flatnonzero(res.scene.height - res.y[1:-1] <= 1e-3 * a)
    return np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []


@pytest.mark.parametrize("name", ["active-set", "proxsuite-dense", "qpsolvers-piqp"])
def test_solve_path_by_name_agrees_with_lemke(name):
    if not backends()[name].available():
        pytest.skip(f"{name} not installed")
    ref = lcpbench.solve_path(SCENE, PATH, tol=1e-9)
    mine = lcpbench.solve_path(SCENE, PATH, tol=1e-9, solver=name)
    for a, b in zip(ref, mine):
        assert a.converged and b.converged, (a.reason, b.reason)
        F = max(a.forces.max(), abs(a.pull))
        np.testing.assert_allclose(b.forces, a.forces, rtol=0, atol=1e-6 * F)
        for run in contact_runs(a):
            assert abs(b.tangential_forces[run].sum() - a.tangential_forces[run].sum()) \
                <= 1e-6 * F
        limit = SCENE.friction * b.forces
        assert np.all(np.abs(b.tangential_forces) <= limit + 1e-9 * F)  # the cone
        assert b.tangential_forces.sum() == pytest.approx(-b.pull, abs=1e-9 * F)


def _step(pull=0.05, seed=2):
    scene = replace(SCENE, pull=pull)
    placed = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                    right_end="pinned", pull=0.0), tol=1e-10)
    rng = np.random.default_rng(seed)
    return frictional_step(scene, scene.chain(), FrictionState(placed.alpha.copy()),
                           placed.x + rng.normal(0.0, 0.02, placed.x.size),
                           pressed=np.ones(scene.chain().free_nodes.size, bool))


def test_the_fc2d_form_is_the_step_lemke_solves():
    """Lemke's z, mapped to (N, T) per wall row, satisfies Coulomb in the fc2d form, and
    the map back (lcp_z) gives z again."""
    fs = _step()
    sol = step_runner("lemke")(fs)
    assert sol.solved
    W, q, mu = fc2d_contacts(fs)
    mn = fs.normal_node.size
    r = np.empty(2 * mn)
    r[0::2] = sol.z[:mn]
    r[1::2] = (sol.z[mn:2 * mn] - sol.z[2 * mn:3 * mn])[fs.pair]
    assert coulomb_residual(W, q, mu, r) <= 1e-9
    z = lcp_z(fs, r)
    np.testing.assert_allclose(z[:3 * mn], sol.z[:3 * mn], rtol=0, atol=1e-9)


def test_judged_never_calls_a_wrong_answer_solved():
    fs = _step()
    sol = step_runner("lemke")(fs)
    z = sol.z.copy()
    z[0] += 1e-3 * max(1.0, np.abs(z).max())  # a normal force off by 1e-3
    bad = judged(fs, LCPSolution(z, fs.M @ z + fs.q, Status.SOLVED))
    assert bad.status is Status.INACCURATE and "natural residual" in bad.message
    nan = judged(fs, LCPSolution(np.full(z.size, np.nan), z, Status.SOLVED))
    assert nan.status is Status.FAILED


def test_cli_solver_reaches_the_frictional_step(capsys):
    args = ["solve", "--theta", "150", "--height", "3", "--links", "30", "--friction",
            "0.3", "--left-end", "slider", "--right-end", "slider", "--pull", "0.05",
            "--json"]
    code = main([*args, "--solver", "active-set"])
    d = json.loads(capsys.readouterr().out)
    (ref,) = lcpbench.solve_path(replace(SCENE, pull=0.05), solver="active-set")
    assert code == 0 and d["converged"]
    np.testing.assert_allclose(d["forces"], ref.forces, rtol=0, atol=1e-15)
    code = main([*args, "--solver", "pgs"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "does not take the frictional step" in err[0]


def test_siconos_fc2d_enumeration_is_refused_on_a_large_step():
    if not backends()["siconos-enum"].available():
        pytest.skip("siconos not installed")
    fs = _step()
    assert fs.normal_node.size > 6
    sol = step_runner("siconos-enum")(fs)
    assert sol.status is Status.FAILED and "up to 6 contacts" in sol.message
