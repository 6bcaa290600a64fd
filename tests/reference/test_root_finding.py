"""The paper's single-reaction root-finding baseline (Appendix A, eqs. 44-45, Table I)."""

import math

import numpy as np
import pytest
from energy_oracle import energy_minimum
from scipy.optimize import fsolve

from lcpbench import ActuatorScene, CantileverScene, ProblemError, solve
from lcpbench.model.chain import node_positions, torque_residual
from lcpbench.reference.root_finding import BaselineSystem, solve_baseline

PAPER = {"theta": 150.0, "links": 140}  # Fig. 26 / 27: l = 30 mm, EI = 32.01 N mm^2, N = 140


@pytest.mark.parametrize("links", [8, 9])
def test_analytic_jacobian_matches_central_differences(links):
    scene = ActuatorScene(theta=150, height=4, links=links, weight=0.01)
    chain = scene.chain()
    system = BaselineSystem(chain, scene.height)
    assert system.size == 3 * links + 2  # Table I
    rng = np.random.default_rng(1)
    z = system.initial(chain.rest_alpha + 0.1 * rng.standard_normal(links), 0.3)
    z += 0.05 * rng.standard_normal(system.size)
    step = 1e-7
    numeric = np.column_stack([
        (system.residual(z + step * e) - system.residual(z - step * e)) / (2 * step)
        for e in np.eye(system.size)
    ])
    assert np.abs(system.jacobian(z) - numeric).max() < 1e-6


def test_four_link_chain_matches_hand_derived_symmetric_statics():
    """N = 4, no weight: by symmetry α = (α1, α2, −α2, −α1), pins carry R/2 each.

    Three equations, independent of the module: midspan height (eq. 45) and the
    spring torques (EI/a)(φ − φ*) at nodes 2 and 3 equal to the moments of the
    left pin reaction R/2 about them.
    """
    theta, ell, ei, h = math.radians(150), 30.0, 32.01, 5.0
    a, rest = ell / 4, -theta / 4
    k = ei / a

    def equations(v):
        a1, a2, r = v
        return [
            a * (math.sin(a1) + math.sin(a2)) - h,
            k * (a2 - a1 - rest) - r / 2 * a * math.cos(a1),
            k * (-2 * a2 - rest) - r / 2 * a * (math.cos(a1) + math.cos(a2)),
        ]

    a1, a2, r = fsolve(equations, [3 * theta / 8, theta / 8, 0.0], xtol=1e-13)
    res = solve_baseline(ActuatorScene(theta=150, height=h, links=4, weight=0.0))
    assert res.converged and res.valid and res.status == "solved"
    np.testing.assert_allclose(res.alpha, [a1, a2, -a2, -a1], atol=1e-9)
    assert res.reaction == pytest.approx(r, rel=1e-9)
    np.testing.assert_allclose(res.forces, [0.0, r, 0.0], atol=1e-9 * r)


@pytest.mark.parametrize("weight", [0.0, 2.45e-4])
def test_answer_satisfies_the_exact_statics_of_the_chain(weight):
    """Independent check with lcpbench.model.chain: torque balance, closure, height, forces."""
    scene = ActuatorScene(height=5.0, weight=weight, **PAPER)
    res = solve_baseline(scene)
    assert res.converged and res.valid
    chain = scene.chain()
    # the wall pushes the midspan node down: nodal force −R there
    tr = torque_residual(chain, res.alpha, -res.forces)
    assert np.max(np.abs(tr)) < 1e-8 * scene.EI / scene.length
    x, y = node_positions(chain, res.alpha)
    assert abs(y[-1]) < 1e-9 and y[70] == pytest.approx(5.0, abs=1e-9)  # eqs. (44), (45)
    assert np.max(y) <= 5.0 + 1e-9
    np.testing.assert_allclose(res.x, x)
    np.testing.assert_allclose(res.y, y)
    # vertical force balance: the pins carry R plus the weight w*l, symmetrically
    q1, qn = res.support
    assert q1 + qn == pytest.approx(res.reaction + weight * scene.length, rel=1e-9)
    assert q1 == pytest.approx(qn, rel=1e-7)
    np.testing.assert_allclose(res.alpha, -res.alpha[::-1], atol=1e-8)  # symmetric scene
    assert np.count_nonzero(res.forces) == 1 and res.forces[69] == res.total_force > 0


@pytest.mark.parametrize("height", [4.0, 5.0, 6.0])
def test_total_force_agrees_with_the_lcp_model_within_0p1_percent(height):
    """Fig. 26 / Appendix: disagreement below 0.1 % for h >= 4 mm at θ = 150°, N = 140.

    Why they agree: at these heights the LCP answer touches the wall at the
    midspan node only, which is exactly the single-reaction model.
    """
    scene = ActuatorScene(height=height, **PAPER)
    lcp = solve(scene, tol=1e-8)
    assert lcp.converged
    assert np.flatnonzero(lcp.forces > 0).tolist() == [69]  # node 71 of 141: midspan only
    res = solve_baseline(scene)
    assert res.converged and res.valid
    assert abs(res.total_force - lcp.total_force) <= 1e-3 * lcp.total_force
    assert np.max(np.abs(res.alpha - lcp.alpha)) < 1e-6  # same shape (LCP tol 1e-8 rad)


def test_odd_links_split_the_reaction_between_the_two_middle_nodes():
    """N odd: the paper sums the reactions of the two nodes either side of midspan."""
    scene = ActuatorScene(theta=150, height=5.0, links=21)
    res = solve_baseline(scene)
    lcp = solve(scene, tol=1e-10)
    assert res.converged and res.valid
    assert np.flatnonzero(res.forces).tolist() == [9, 10]  # nodes 11 and 12 of 22
    assert res.forces[9] == res.forces[10] == pytest.approx(res.reaction / 2)
    np.testing.assert_allclose(lcp.forces, res.forces, atol=1e-7)  # LCP: the same two nodes


@pytest.mark.parametrize("method", ["hybr", "lm"])
@pytest.mark.parametrize("height", [1.0, 2.0])
def test_breakdown_at_small_height_is_not_reported_as_a_valid_answer(method, height):
    """Fig. 27b (h = 1 mm): the single-reaction shape bows out beyond the wall."""
    scene = ActuatorScene(height=height, **PAPER)
    res = solve_baseline(scene, method=method)
    assert not res.valid
    if res.converged:
        assert res.status.startswith("bad solution: penetrates the wall")
        assert res.max_penetration > 1e-6
        assert np.max(res.y) > height  # beyond the wall, either side of midspan
        assert res.y[70] == pytest.approx(height, abs=1e-8)
    # the LCP model stays inside (and touches in two patches, not at midspan)
    lcp = solve(scene)
    assert lcp.certificate.min_gap > -1e-6 and lcp.forces[69] == 0


def test_wall_above_the_arc_needs_a_pulling_wall_and_is_not_valid():
    """The unconstrained arc of θ = 150° rises r(1 − cos 75°) = 8.49 mm: a wall at 9 mm
    cannot touch it, and the single-reaction model can only hold it there by pulling."""
    scene = ActuatorScene(height=9.0, weight=0.0, **PAPER)
    assert scene.arc_height < 9.0
    res = solve_baseline(scene)
    assert res.converged and not res.valid
    assert res.reaction < 0 and "pulls" in res.status


def test_levenberg_marquardt_and_warm_start_find_the_energy_minimum():
    """At h = 5 mm the equilibrium touches at midspan only, the single-reaction model's
    case: hybr, LM and a warm start each give the energy minimum's force (the direct
    minimisation, tests/energy_oracle.py; they agree to ~1e-12 here, 1e-8 asked: the
    root finders' xtol)."""
    scene = ActuatorScene(height=5.0, **PAPER)
    ref = energy_minimum(scene)
    assert np.flatnonzero(ref.forces).tolist() == [69]  # midspan only
    hybr = solve_baseline(scene)
    lm = solve_baseline(scene, method="lm")
    assert hybr.converged and hybr.valid
    assert lm.converged and lm.valid and lm.method == "lm"
    warm = solve_baseline(scene, x0=hybr)
    assert warm.converged and warm.iterations < hybr.iterations
    for res in (hybr, lm, warm):
        assert res.total_force == pytest.approx(ref.total_force, rel=1e-8)


def test_failures_are_recorded_not_raised():
    scene = ActuatorScene(height=5.0, **PAPER)
    few = solve_baseline(scene, max_nfev=3)
    assert not few.converged and not few.valid and few.status == "max evaluations"
    late = solve_baseline(scene, time_limit=1e-9)
    assert not late.converged and late.status == "time limit"
    assert late.alpha.shape == (140,)


@pytest.mark.parametrize(
    "scene, kwargs, match",
    [
        (CantileverScene(), {}, "ActuatorScene"),
        (ActuatorScene(), {"method": "broyden1"}, "method must be one of hybr, lm"),
        (ActuatorScene(), {"tol": 0.0}, "tol"),
        (ActuatorScene(), {"tol": "tight"}, "tol"),
        (ActuatorScene(), {"max_nfev": 0}, "max_nfev"),
        (ActuatorScene(), {"time_limit": -1}, "time_limit"),
        (ActuatorScene(), {"x0": np.zeros(3)}, "x0"),
        ("not a scene", {}, "ActuatorScene"),
    ],
)
def test_bad_input_raises_problem_error(scene, kwargs, match):
    with pytest.raises(ProblemError, match=match):
        solve_baseline(scene, **kwargs)


def test_the_baseline_picks_its_own_n_by_the_sec_iii_d_rule():
    """links='auto' in the baseline: the first N (steps of 10) whose baseline
    force differs from N - 10's by < 0.01 %, checked on the baseline's own
    answers at N and N - 10 (and N - 10 failing the rule against N - 20)."""
    from lcpbench.reference.root_finding import baseline_links

    scene = ActuatorScene(theta=150.0, height=5.0)
    n = baseline_links(scene)
    f = {k: solve_baseline(scene.with_links(k)).total_force for k in (n - 20, n - 10, n)
         if k >= 10}

    def change(a, b):
        return abs(f[a] - f[b]) / max(abs(f[a]), abs(f[b]))

    assert change(n, n - 10) < 1e-4
    if n - 20 in f:
        assert change(n - 10, n - 20) >= 1e-4
    assert solve_baseline(scene.with_links("auto")).links == n
