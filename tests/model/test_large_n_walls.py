"""Elastic walls and wall profiles in the large-N increment path (issue 35, target 5).

Oracles: at small N, the same path (a chain marked ``increments``) against first
principles (elastic walls: the Winkler law and central differences of the exact
energy, tests/energy_oracle.py) and the energy minimisation (SLSQP, a profile); at
N = 10⁴ the discretisation: the same scene at N = 2000 solved in node heights by
the compiled kernels (a different formulation, step and driver), O(N⁻²) apart; the
rigid limit: elastic walls of k = 1e9 N/mm² against the rigid wall at the same N;
and lcpbench's judge, which must accept the answers and refuse perturbed ones.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from energy_oracle import assert_equilibrium
from known_answers import stenosis

from lcpbench import ActuatorScene, solve
from lcpbench.model.judge import force_tol, judge
from lcpbench.model.large_driver import run_large
from lcpbench.model.result import certify
from lcpbench.model.step_solver import make_step_solver
from lcpbench.reference.energy import minimise_energy

N = 10_000
#: the discretisation error of F at N = 2000, O(N⁻²): the chain's nodes on a curve
#: of curvature κ sit a² κ / 8 off it, a = ℓ/N; 1e-7–1e-6 of F at N = 2000 (the
#: same order as the rigid flat wall's, results/large-n.md), N = 10⁴ 25x closer
DISCRETISATION = 2e-6


def _increments(scene, tol, backend="auto"):
    """The scene's chain solved by the large-N driver whatever N (``increments``)."""
    chain = replace(scene.chain(), increments=True)
    out = run_large(chain, make_step_solver(backend), tol=tol)
    assert out.converged, out.reason
    return out


def test_elastic_walls_in_increments_are_the_equilibrium_from_first_principles():
    # R = k (y − h)₊ at every node and E + springs stationary, by central differences
    scene = ActuatorScene(150, 3.0, links=60, wall_stiffness=0.1)
    out = _increments(scene, 1e-10)
    assert float(np.sum(out.forces_upper)) > 0.0  # the chain indents the wall
    assert_equilibrium(scene, out.alpha, out.forces_upper, out.forces_lower,
                       stationarity=1e-6, wall_tol=1e-8)


@pytest.mark.parametrize("backend", ["lemke", "pgs"])
def test_an_lcp_back_end_takes_elastic_walls_in_increments(backend):
    # the elastic step handed to an LCP back-end (the LCP in the reactions with the
    # compliances) from a step in increments: R = k (y − h)₊ and E + springs stationary
    scene = ActuatorScene(150, 3.0, links=60, wall_stiffness=0.1)
    out = _increments(scene, 1e-8, backend)
    assert float(np.sum(out.forces_upper)) > 0.0
    assert_equilibrium(scene, out.alpha, out.forces_upper, out.forces_lower,
                       stationarity=1e-5, wall_tol=1e-6)


def test_a_profile_in_increments_matches_the_energy_minimisation():
    scene = ActuatorScene(theta=150, height=3.0, links=40, wall_profile=stenosis())
    ref = minimise_energy(scene)
    assert ref.success, ref.message
    out = _increments(scene, 1e-10)
    F0 = max(abs(ref.total_force), scene.EI / scene.length**2)
    assert abs(float(np.sum(out.forces_upper)) - ref.total_force) <= 1e-6 * F0


@pytest.fixture(scope="module")
def elastic():
    return solve(ActuatorScene(150, 3.0, links=N, wall_stiffness=0.1), tol=1e-8)


@pytest.fixture(scope="module")
def profiled():
    return solve(ActuatorScene(theta=150, height=3.0, links=N, wall_profile=stenosis()),
                 tol=1e-8)


@pytest.mark.parametrize("kind", ["elastic", "profiled"])
def test_large_n_walls_converge_to_the_n_2000_answer_in_heights(kind, elastic, profiled):
    """Route against route: at N = 10⁴ central differences of the energy cost ~20 s
    per answer and SLSQP is out of reach, so the expectation is the N = 2000 answer
    in node heights (another formulation, step and driver), O(N⁻²) apart. (At N = 2000
    the elastic answer's Winkler law holds by forward kinematics only to ~1e-6 F₀, no
    sharper than this comparison; the oracles at small N are the tests above.)"""
    res = {"elastic": elastic, "profiled": profiled}[kind]
    assert res.converged, res.reason
    assert res.route == "large N" and res.judge == "increments"  # increments, judged there
    coarse_scene = replace(res.scene, links=2000)
    coarse = solve(coarse_scene, tol=1e-8)
    assert coarse.converged and coarse.route != "large N"  # node heights, compiled
    F0 = max(abs(coarse.total_force), res.scene.EI / res.scene.length**2)
    assert abs(res.total_force - coarse.total_force) <= DISCRETISATION * F0


@pytest.mark.parametrize("kind", [
    "elastic",
    pytest.param("profiled", marks=pytest.mark.xfail(strict=True, reason=(
        "open: the stenosis' discrete answers fall in two families, N = 4000–2.3·10⁴ "
        "(contact at x = 14.0645, F = 0.4420013) and N = 5·10⁴–10⁵ (x = 14.06504, "
        "F = 0.4419899, the two within 1e-10), with a two-node contact between "
        "(0.441984 at 3·10⁴, reached from the 2·10⁴ shape too); each accepted by the "
        "judge at tol 1e-8. N = 2000 in heights is in the first family"))),
])
def test_large_n_walls_at_3e4_are_the_n_2000_answer_in_heights(kind):
    """Route against route, as above: at N = 3·10⁴ no oracle is in reach; the N = 2000
    answer in heights is the expectation."""
    # tol 1e-7 (τ = 1e-5): at 1e-8 the judge's round-off floor, a sum over the elastic
    # contact's ~17,000 nodes, is 7e-6 F₀ at N = 3·10⁴, above τ = 1e-6
    kw = ({"wall_stiffness": 0.1} if kind == "elastic" else {"wall_profile": stenosis()})
    res = solve(ActuatorScene(theta=150, height=3.0, links=30_000, **kw), tol=1e-7)
    assert res.converged and res.route == "large N", res.reason
    coarse = solve(ActuatorScene(theta=150, height=3.0, links=2000, **kw), tol=1e-8)
    assert coarse.converged and coarse.route != "large N"
    F0 = max(abs(coarse.total_force), res.scene.EI / res.scene.length**2)
    bound = DISCRETISATION + force_tol(1e-7)  # the discretisation and the answer's τ
    assert abs(res.total_force - coarse.total_force) <= bound * F0


def test_stiff_elastic_walls_give_the_rigid_wall_at_large_n():
    """Route against route: the rigid limit at N = 10⁴, where central differences of the
    energy cost ~20 s per answer; at N = 140 the same limit is checked against the
    rigid wall's energy minimum (test_elastic.py::test_the_rigid_limit_is_continuous)."""
    # the rigid limit: springs of 1e9 N/mm² indent by R/k ~ 1e-11 mm; issue 35's bound
    stiff = solve(ActuatorScene(150, 3.0, links=N, wall_stiffness=1e9), tol=1e-8)
    rigid = solve(ActuatorScene(150, 3.0, links=N), tol=1e-8)
    assert stiff.converged and rigid.converged, (stiff.reason, rigid.reason)
    assert stiff.route == rigid.route == "large N"
    assert abs(stiff.total_force - rigid.total_force) <= 1e-6 * rigid.total_force


def _judged(res, upper):
    chain = res.scene.chain()
    lower = np.zeros_like(upper)
    return judge(chain, res.alpha, upper, lower, tol=res.tol, driver_converged=True,
                 driver_reason="converged", step_statuses=["solved"] * len(res.steps),
                 step_sizes=[s.max_dalpha for s in res.steps],
                 certificate=lambda up, lo: certify(chain, res.alpha, up, lo))


@pytest.mark.parametrize("kind", ["elastic", "profiled"])
@pytest.mark.parametrize("defect", ["exact", "scaled", "moved"])
def test_the_large_n_judge_refuses_perturbed_wall_answers(kind, defect, elastic, profiled):
    res = {"elastic": elastic, "profiled": profiled}[kind]
    f = res.forces.copy()
    top = int(np.argmax(f))
    if defect == "scaled":  # every node 2 τ too large
        f *= 1.0 + 2 * force_tol(res.tol)
    elif defect == "moved":  # a tenth of the largest reaction moved 50 nodes over
        f[top] -= 0.1 * f[top]
        f[top + 50] += 0.1 * res.forces[top]
    verdict = _judged(res, f)
    if defect == "exact":
        assert verdict.converged, verdict.reason
    else:
        assert not verdict.converged
