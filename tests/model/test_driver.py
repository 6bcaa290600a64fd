"""The nonlinear driver: the arc without contact, certificates, symmetry, the paper's trends,
hard cases, and agreement between independent solvers and schemes."""

import math

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import ActuatorScene, solve
from lcpbench.reference.energy import minimise_energy


def assert_certified(res, rel_torque=1e-6):
    c = res.certificate
    assert res.converged, res.reason
    assert c.min_gap >= -1e-9
    assert c.min_force >= 0
    assert c.complementarity <= 1e-9 * max(res.total_force, 1e-3)
    assert c.closure <= 1e-9
    assert c.relative_torque_residual <= rel_torque


def test_no_contact_no_weight_is_the_circular_arc_without_any_step():
    scene = ActuatorScene(theta=90, height=10, links=60, weight=0)
    res = solve(scene)
    assert res.converged and res.outer_iterations == 0 and res.total_force == 0
    # Nodes on a circle; the chord a = 2 r' sin(θ/2N) fixes its radius (eq. 2 as N → ∞).
    th = math.radians(90)
    r_chain = (scene.length / 60) / (2 * math.sin(th / 120))
    xc, yc = res.x[-1] / 2, res.y.min() - 0  # centre below the chord midpoint
    yc = -math.sqrt(r_chain**2 - xc**2)
    assert np.allclose(np.hypot(res.x - xc, res.y - yc), r_chain, rtol=1e-12)
    assert r_chain == pytest.approx(scene.length / th, rel=1e-4)


def test_self_weight_sags_the_free_arc_linearly_in_w():
    base = ActuatorScene(theta=90, height=10, links=60, weight=0)
    arc = solve(base)
    dev = [solve(ActuatorScene(theta=90, height=10, links=60, weight=w), tol=1e-12).y - arc.y
           for w in (1e-6, 2e-6)]
    assert np.all(dev[0][1:-1] < 0)  # sags away from the wall (gravity points away from it)
    assert np.allclose(dev[1], 2 * dev[0], rtol=1e-4, atol=1e-12)
    assert np.max(np.abs(dev[0])) < 0.01 * base.length


@pytest.mark.parametrize("theta,height", [(150, 3.0), (120, 2.0), (180, 4.0)])
def test_converged_solution_is_certified_on_exact_geometry(theta, height):
    res = solve(ActuatorScene(theta=theta, height=height, links=140), tol=1e-10)
    assert_certified(res)
    assert res.total_force == pytest.approx(res.forces.sum())
    assert np.all(res.gaps[res.forces > 0] < 1e-9)


def test_weightless_solution_is_mirror_symmetric():
    res = solve(ActuatorScene(theta=150, height=3, links=100, weight=0), tol=1e-11)
    assert np.allclose(res.forces, res.forces[::-1], atol=1e-9 * res.total_force)
    assert np.allclose(res.y, res.y[::-1], atol=1e-9)


def test_weightless_force_scales_exactly_with_EI():
    """With w = 0 the energy is proportional to EI, so the reactions are too."""
    f1 = solve(ActuatorScene(EI=10, weight=0, links=80), tol=1e-11).total_force
    f3 = solve(ActuatorScene(EI=30, weight=0, links=80), tol=1e-11).total_force
    assert f3 == pytest.approx(3 * f1, rel=1e-8)


def test_paper_trends_force_rises_with_theta_and_EI_falls_with_h():
    force = lambda **kw: solve(ActuatorScene(links=80, **kw), tol=1e-8).total_force  # noqa: E731
    by_theta = [force(theta=t, height=3) for t in (100, 120, 140, 160, 180)]
    assert np.all(np.diff(by_theta) > 0)
    by_EI = [force(EI=e, height=3) for e in (10, 40, 70, 100)]
    assert np.all(np.diff(by_EI) > 0)
    by_h = [force(theta=150, height=h) for h in (2, 3, 4, 5, 6, 7)]
    assert np.all(np.diff(by_h) < 0)


def test_contact_widens_and_span_grows_as_the_chain_flattens():
    res = [solve(ActuatorScene(theta=150, height=h, links=100, weight=0), tol=1e-9)
           for h in (6, 4, 3, 2, 1)]
    touching = [np.flatnonzero(r.gaps < 1e-9) + 1 for r in res]  # node indices at the wall
    width = [r.x[t.max()] - r.x[t.min()] for r, t in zip(res, touching)]
    spans = [r.span for r in res]
    assert width[0] == 0 and np.all(np.diff(width) >= 0) and width[-1] > width[1]
    assert np.all(np.diff(spans) > 0)
    # the force sits at the ends of the flat region, not inside it (Fig. 27, Sec. III-E)
    flat = res[-1]
    inner = touching[-1][3:-3] - 1
    assert np.all(flat.forces[inner] < 1e-9 * flat.total_force)
    free_span = solve(ActuatorScene(theta=150, height=20, links=100, weight=0)).span
    assert spans[0] > free_span


HARD = [
    # (theta, height, links, weight)
    pytest.param(180, 0.6, 140, 2.45e-4, id="theta180-h0.02l"),
    pytest.param(175, 0.6, 10, 2.45e-4, id="N10"),
    pytest.param(180, 0.6, 2000, 2.45e-4, id="N2000"),
    pytest.param(170, 1.0, 300, 2.45e-4, id="theta170"),
    pytest.param(150, 3.0, 140, 0.05, id="heavy"),
    pytest.param(60, 3.0, 140, 2.45e-4, id="no-contact"),
]


@pytest.mark.parametrize("theta,height,links,weight", HARD)
def test_globalised_driver_converges_on_hard_cases(theta, height, links, weight):
    res = solve(ActuatorScene(theta=theta, height=height, links=links, weight=weight), tol=1e-8)
    assert_certified(res, rel_torque=1e-5)


def test_heavy_chain_sags_off_the_wall():
    light = solve(ActuatorScene(theta=150, height=3, links=100), tol=1e-9)
    heavy = solve(ActuatorScene(theta=150, height=3, links=100, weight=0.05), tol=1e-9)
    assert heavy.total_force < light.total_force
    assert heavy.converged and heavy.total_force == 0 and heavy.certificate.min_gap > 0
    # 4000x the paper's weight (wℓ³/EI = 843): the chain hangs with links past the
    # vertical. Solved by steps in the link angles (issue 19, target 8), it is the
    # independent energy minimum's shape, clear of the wall
    scene = ActuatorScene(theta=150, height=3, links=100, weight=1.0)
    absurd = solve(scene, tol=1e-9)
    assert absurd.converged and absurd.total_force == 0 and absurd.certificate.min_gap > 0
    ref = minimise_energy(scene)
    assert ref.success and ref.total_force == 0
    assert np.max(np.abs(absurd.y - ref.y)) < 1e-6 * scene.length


@pytest.mark.parametrize("side", [-1, 1])
def test_grazing_contact(side):
    """A wall 1e-9 mm above or below the top of the weightless chain."""
    scene = ActuatorScene(theta=120, height=5, links=60, weight=0)
    top = solve(ActuatorScene(theta=120, height=50, links=60, weight=0)).y.max()
    res = solve(ActuatorScene(theta=120, height=top + side * 1e-9, links=60, weight=0), tol=1e-10)
    assert_certified(res)
    if side > 0:
        assert res.total_force == 0
    else:
        assert 0 <= res.total_force < 1e-6
    del scene


def test_undamped_paper_iteration_fails_cleanly_where_the_linearisation_breaks():
    res = solve(ActuatorScene(theta=180, height=0.6, links=140), method="undamped")
    assert not res.converged
    assert "vertical" in res.reason or "outer iterations" in res.reason
    good = solve(ActuatorScene(theta=180, height=0.6, links=140))
    assert good.converged


def test_undamped_and_globalised_agree_where_both_converge():
    scene = ActuatorScene(theta=150, height=3, links=80)
    a = solve(scene, tol=1e-11, method="undamped")
    b = solve(scene, tol=1e-11)
    assert a.converged and b.converged
    assert a.total_force == pytest.approx(b.total_force, rel=1e-8)
    assert np.allclose(a.y, b.y, atol=1e-8)
    assert_solved(a)  # each the equilibrium (tests/energy_oracle.py)
    assert_solved(b)


def test_lemke_and_active_set_back_ends_agree():
    scene = ActuatorScene(theta=160, height=2, links=60)
    a = solve(scene, solver="lemke", tol=1e-10)
    b = solve(scene, solver="active-set", tol=1e-10)
    assert a.converged and b.converged and a.solver == "lemke"
    assert np.allclose(a.forces, b.forces, atol=1e-8 * b.total_force)
    assert_solved(a)  # each the equilibrium (tests/energy_oracle.py)
    assert_solved(b)


def test_channel_reduces_to_one_wall_when_the_lower_wall_is_untouched():
    one = solve(ActuatorScene(theta=150, height=3, links=80), tol=1e-10)
    two = solve(ActuatorScene(theta=150, height=3, links=80, channel=True), tol=1e-10)
    assert two.forces_lower is not None and np.all(two.forces_lower == 0)
    assert two.total_force == pytest.approx(one.total_force, rel=1e-9)
    assert_solved(two)  # the equilibrium of the channel (tests/energy_oracle.py)


def test_channel_holds_a_heavy_chain_from_below():
    res = solve(ActuatorScene(theta=60, height=1, links=80, weight=0.5, channel=True), tol=1e-9)
    assert_certified(res)
    assert res.forces_lower.sum() > 0
    assert res.certificate.min_gap >= -1e-9


def test_non_convergence_is_reported_not_raised():
    res = solve(ActuatorScene(theta=180, height=0.6, links=140), max_outer=1, tol=1e-12)
    assert not res.converged and "outer iterations" in res.reason
    assert res.total_force == 0  # no half-made reactions reported as an answer


def test_public_names():
    assert lcpbench.ActuatorScene(theta=150, height=3.0, links=140, length=30.0, EI=32.01,
                                  weight=2.45e-4, channel=False)


def test_large_N_flat_contact_region_is_not_mistaken_for_contact():
    """N = 2000: the reactions in the flat region are ~μ = 4e-6 N, near round-off of |H u|.

    Regression: a loose round-off test once kept nodes that should sag off the
    wall in contact and called it converged. Each scheme's answer is the equilibrium
    by first principles (tests/energy_oracle.py: no reaction off the wall, stationary;
    ~1.5 s each at N = 2000), passes the exact-geometry certificate, and they agree.
    """
    scene = ActuatorScene(theta=150, height=3, links=2000)
    a = solve(scene, tol=1e-8)
    b = solve(scene, tol=1e-8, method="undamped")
    assert_certified(a, rel_torque=1e-6)
    assert_solved(a)
    assert_solved(b)
    assert a.total_force == pytest.approx(b.total_force, rel=1e-7)


def test_bad_driver_input_is_a_problem_error():
    from lcpbench.errors import ProblemError
    from lcpbench.model import compiled_driver
    from lcpbench.model.outer import DriverStart

    chain = ActuatorScene(theta=150, height=3, links=20).chain()
    with pytest.raises(ProblemError, match="method must be one of"):
        solve(ActuatorScene(theta=150, height=3, links=20), method="newtonian")
    with pytest.raises(ProblemError, match="continuation start"):
        compiled_driver.run(chain, None, method="undamped", start=DriverStart(np.zeros(20)))
