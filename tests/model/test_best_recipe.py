"""formulation="best" is the measured recipe: the form, its equilibration and, at
`default` for OSQP and SCS, the tolerance ε the back-end is handed
(src/lcpbench/model/best_formulations.json, "eps"; docs/formulations.md).

Checked here: the result's typed field ``eps`` says which ε the back-end was handed
(the recipe's through "best", none otherwise at `default`), the step is still judged at
`default`, and the answers agree with an oracle independent of every back-end: the
direct minimisation of the exact energy (reference.energy, SLSQP with a Newton
polish of its KKT system).
"""

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.errors import ProblemError
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.formulations import (
    Formulation,
    best_eps,
    best_formulations,
    parse_formulation,
    resolve_formulation,
)
from lcpbench.model.step_solver import solve_step
from lcpbench.reference.energy import minimise_energy
from lcpbench.solvers.base import Settings
from lcpbench.solvers.judge import accept_tol
from lcpbench.solvers.registry import available_backends, get_backend, get_settings

RECIPE = ("osqp", "qpsolvers-scs")  # the back-ends whose `default` recipe carries an ε
#: paper scenes (θ °, h mm; N = 140) that touch the wall, where `default` without the
#: recipe's ε was refused (results/formulations/targets-best-default.md before it)
SCENES = [(150, 3), (120, 2), (180, 5)]
#: scenes whose answer at the recipe is accepted on one host and refused by the judge on
#: another: whether a first-order back-end's iterations reach the judge's residual is its
#: build's (BLAS kernels, SIMD width). SCS on (150°, 3 mm): accepted on the hosts of the
#: committed runs, refused ("inaccurate by lcpbench's residuals") on an AMD Zen 5 host
HOST_REFUSALS = {("qpsolvers-scs", 150, 3)}


def _needs(backend):
    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")


@pytest.fixture(scope="module")
def oracle():
    out = {}
    for theta, height in SCENES:
        ref = minimise_energy(ActuatorScene(theta=theta, height=height, links=140))
        assert ref.success and ref.polished, ref.message
        out[theta, height] = ref
    return out


def test_the_recipe_gives_eps_at_default_only():
    """The table's ε is read into the resolved form at `default`; `high` hands its own
    ε (none from the recipe), and settings that carry an ε keep theirs."""
    eps = best_eps("default")
    for name in RECIPE:
        assert 0.0 < eps[name] < 1e-4  # tighter than their own (OSQP 1e-3, SCS 1e-4)
        form = resolve_formulation(get_backend(name), "best", "default")
        assert form is not None and form.eps == eps[name]
        # written NAME@E: the store's method and the result's "formulation" say the ε
        assert str(form) == f"{best_formulations('default')[name]}@{eps[name]:g}"
        assert parse_formulation(str(form)) == form
        high = resolve_formulation(get_backend(name), "best", "high")
        assert high is None or high.eps is None
        own = resolve_formulation(get_backend(name), "best", Settings("default", 1e-8))
        assert own is None or own.eps is None
    assert best_eps("high") == {}
    # a named form is that form, with the profile's ε, or the one written after '@'
    osqp = get_backend("osqp")
    assert resolve_formulation(osqp, "angles", "default") == Formulation("angles")
    assert resolve_formulation(osqp, "F5r@1e-5", "high") == Formulation("angles", True, 1e-5)
    assert resolve_formulation(osqp, "heights@1e-6", "default") == Formulation("heights",
                                                                               False, 1e-6)
    for bad in ("angles@", "angles@2", "angles@x", "angles@-1e-6"):
        with pytest.raises(ProblemError, match="formulation"):
            parse_formulation(bad)


@pytest.mark.parametrize("backend", RECIPE)
def test_a_step_is_handed_the_recipe_eps_and_judged_at_default(backend):
    _needs(backend)
    scene = ActuatorScene(theta=150, height=3, links=140)
    ref = lcpbench.solve(scene, settings="high", tol=1e-10)
    step = assemble_step(scene.chain(), ref.alpha)
    sol = solve_step(step, backend, "default", formulation="best")
    assert sol.eps == best_eps("default")[backend] and sol.settings == "default"
    want = parse_formulation(best_formulations("default")[backend])
    assert parse_formulation(sol.formulation) == Formulation(want.name, want.equilibrated,
                                                             sol.eps)
    assert sol.solved, sol.message
    # the judge's own test, at `default`'s accuracy (not loosened by the recipe's ε)
    bound = accept_tol(get_settings("default"), sol.residuals["term_size"])
    assert sol.residuals["natural"] <= bound
    plain = solve_step(step, backend, "default")  # no recipe: the back-end's own ε
    assert plain.eps is None


@pytest.mark.parametrize("backend", RECIPE)
@pytest.mark.parametrize("theta,height", SCENES)
def test_best_at_default_agrees_with_the_energy_minimum(backend, theta, height, oracle):
    """An answer the judge accepts agrees with the energy minimum, and every scene here is
    accepted but those listed in :data:`HOST_REFUSALS` (the recipe promises >= 95 % of
    the grid, SCS 96 %, measured in results/formulations/, not every scene), where a
    refusal must be the judge's, never an answer."""
    _needs(backend)
    scene = ActuatorScene(theta=theta, height=height, links=140)
    res = lcpbench.solve(scene, solver=backend, settings="default", tol=1e-3,
                         formulation="best")
    assert res.eps == best_eps("default")[backend]  # the typed field: what it was handed
    assert res.to_dict()["eps"] == res.eps
    assert parse_formulation(res.extra["formulation"]).eps == res.eps
    if not res.converged and (backend, theta, height) in HOST_REFUSALS:
        assert res.reason.startswith("not accepted by lcpbench's judge"), res.reason
        return
    assert res.converged, res.reason
    ref = oracle[theta, height]
    err = abs(res.total_force - ref.total_force) / ref.total_force
    assert err <= 1e-3  # target 1's rule at tol 1e-3: min(1e-3, 100·tol)
    assert err <= res.force_error_bound  # the judge's bound holds against the oracle
    # per node, to the same relative accuracy of the load cell
    assert np.max(np.abs(res.forces - ref.forces)) <= 1e-3 * ref.total_force


def test_without_best_default_hands_no_eps():
    """`default` keeps its meaning for every call that does not ask for "best": the
    back-end's own tolerance (no ε), and the built-in's answer is its own path's."""
    scene = ActuatorScene(theta=150, height=3, links=40)
    if "osqp" in available_backends():
        assert lcpbench.solve(scene, solver="osqp").eps is None
        assert lcpbench.solve(scene, solver="osqp", formulation="angles+ruiz").eps is None
        assert lcpbench.solve(scene, solver="osqp", settings="high").eps == 1e-9
    a = lcpbench.solve(scene)
    b = lcpbench.solve(scene, formulation="best")
    assert a.eps is None and b.eps is None
    assert np.array_equal(a.forces, b.forces)


def test_elastic_walls_report_no_recipe_eps():
    # elastic walls keep their own forms (step_solver), so the result names neither
    # the recipe's form nor its ε: every step was handed the profile's (none at default)
    _needs("osqp")
    res = lcpbench.solve(ActuatorScene(theta=150, height=3, links=30, wall_stiffness=50.0),
                         solver="osqp", settings="default", formulation="best")
    assert res.eps is None and "formulation" not in res.extra


def test_the_built_in_active_set_takes_no_eps():
    # it solves each contact step exactly: an ε would be reported and never used
    with pytest.raises(ProblemError, match="takes no tolerance"):
        resolve_formulation(get_backend("active-set"), "heights@1e-6", "default")


def test_an_lcp_file_form_hands_its_eps(monkeypatch):
    # the LCP path (lcpbench lcp --formulation NAME@E) hands the back-end the form's ε,
    # and judges at the profile's accuracy
    _needs("osqp")
    from lcpbench.model.formulations import solve_lcp_in
    from lcpbench.solvers import runner

    handed_eps = []
    real = runner.solve_lcp

    def spy(M, q, solver, settings, *a, **k):
        handed_eps.append(get_settings(settings).eps)
        return real(M, q, solver, settings, *a, **k)

    monkeypatch.setattr(runner, "solve_lcp", spy)
    M = np.array([[2.0, 1.0], [1.0, 2.0]])
    q = np.array([-1.0, -1.0])
    sol = solve_lcp_in(M, q, "osqp", "default", "gaps+ruiz@1e-9")
    assert handed_eps == [1e-9]
    # the LCP's answer by hand: both rows active, M z = -q gives z = (1/3, 1/3)
    assert np.allclose(sol.z, [1 / 3, 1 / 3], atol=1e-6)
    assert sol.extra["formulation"] == "gaps+ruiz@1e-09"
