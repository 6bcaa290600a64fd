"""The result judge's numbers, from the judge kernel, against independent oracles.

Every number of :func:`lcpbench.model.judge.judge` comes from compiled functions
(:mod:`lcpbench.model.judge_kernel`, :mod:`lcpbench.model.judge_bound`,
:mod:`lcpbench.model.stability_kernel`). No test here compares two judges: the answers
judged come from the direct minimisation of the exact energy
(:func:`lcpbench.reference.energy.minimise_energy`: SLSQP and a Newton polish,
no contact step, no lcpbench driver), which the judge must accept, and the same
answers with a planted defect, which it must refuse by the check the defect breaks.
The cantilever's answer is beam theory's too (eqs. 34-37).
"""

from __future__ import annotations

import numpy as np
import pytest
from known_answers import CANTILEVER_THEORY_FORCE

from lcpbench import ActuatorScene, CantileverScene
from lcpbench.model.judge import judge, judged_in
from lcpbench.model.result import certify
from lcpbench.reference.energy import minimise_energy

#: the driver tolerance the energy answers are judged at: τ = 100 tol = 1e-4, well
#: above the energy reference's own accuracy (its KKT check, 1e-9 dimensionless)
TOL = 1e-6

SCENES = {
    "one wall": ActuatorScene(theta=150, height=3.0, links=40),
    "channel": ActuatorScene(theta=170, height=2.5, links=40, channel=True),
    "heavy channel": ActuatorScene(theta=60, height=0.3, links=30, channel=True,
                                   weight=0.04),
    "cantilever": CantileverScene(links=40),
}


@pytest.fixture(scope="module", params=list(SCENES))
def energy_answer(request):
    scene = SCENES[request.param]
    ref = minimise_energy(scene)
    assert ref.success, ref.message
    lower = ref.forces_lower if ref.forces_lower is not None else np.zeros_like(ref.forces)
    return request.param, scene.chain(), ref.alpha, ref.forces.copy(), lower.copy()


def _judge(chain, alpha, upper, lower, *, converged=True, statuses=("solved",)):
    return judge(chain, alpha, upper, lower, tol=TOL, driver_converged=converged,
                 driver_reason="converged", step_statuses=list(statuses), step_sizes=[],
                 certificate=lambda up, lo: certify(chain, alpha, up, lo))


def test_the_energy_minimiser_is_accepted_by_the_judge_kernel(energy_answer):
    name, chain, alpha, upper, lower = energy_answer
    assert judged_in(chain) == "heights"
    v = _judge(chain, alpha, upper, lower)
    assert v.converged, (name, v.reason)
    assert v.force_error_bound <= v.force_tol and v.unstable_directions == 0
    # the judge's own exact step at the minimiser moves its total force by less than τ
    F = float(np.sum(upper))
    assert abs(v.judge_total_force - F) <= v.force_tol * v.force_unit


def test_the_cantilevers_minimiser_is_beam_theory_and_accepted():
    ref = minimise_energy(CantileverScene())
    assert ref.success and ref.total_force == pytest.approx(CANTILEVER_THEORY_FORCE, rel=2e-2)
    chain = CantileverScene().chain()
    v = _judge(chain, ref.alpha, ref.forces, np.zeros_like(ref.forces))
    assert v.converged, v.reason
    assert np.argmax(v.forces_upper) == ref.forces.size - 1  # the tip carries it


def _loaded(upper, lower):
    """The wall and node that carry the largest reaction."""
    on_lower = float(np.max(lower)) > float(np.max(upper))
    forces = lower if on_lower else upper
    return on_lower, int(np.argmax(forces))


def _planted(upper, lower, defect, chain, alpha):
    up, lo = upper.copy(), lower.copy()
    on_lower, top = _loaded(upper, lower)
    f = lo if on_lower else up
    F = float(f[top])
    if defect == "pulling wall":  # a wall that pulls, 1 % of the largest reaction
        free = np.flatnonzero(f == 0.0)
        f[free[len(free) // 2]] = -1e-2 * F
    elif defect == "reaction off the wall":  # a node far from every wall carries force
        from lcpbench.model.chain import heights

        u = heights(chain, alpha)
        gap = np.minimum(chain.upper - u, u - chain.lower)
        f[int(np.argmax(np.where(np.isfinite(gap), gap, -np.inf)))] += 1e-2 * F
    elif defect == "scaled":  # every reaction 1 % too large
        f *= 1.01
    elif defect == "force moved between nodes":  # 13 % of the largest to a neighbour
        other = top - 1 if top > 0 else top + 1
        f[top] -= 0.13 * F
        f[other] += 0.13 * F
    return up, lo


#: the check each defect breaks (the judge may name others too)
DEFECTS = {"pulling wall": "sign", "reaction off the wall": "complementarity",
           "scaled": "force error bound", "force moved between nodes": "force error bound"}


@pytest.mark.parametrize("defect", list(DEFECTS))
def test_a_planted_wrong_answer_is_refused(energy_answer, defect):
    name, chain, alpha, upper, lower = energy_answer
    up, lo = _planted(upper, lower, defect, chain, alpha)
    v = _judge(chain, alpha, up, lo)
    assert not v.converged, (name, defect)
    assert DEFECTS[defect] in v.failed, (name, defect, v.reason)


def test_an_inaccurate_last_step_is_refused_whatever_the_numbers(energy_answer):
    name, chain, alpha, upper, lower = energy_answer
    v = _judge(chain, alpha, upper, lower, statuses=("solved", "inaccurate"))
    assert not v.converged and v.failed == ["last step"], (name, v.reason)


@pytest.mark.parametrize("wall", ["upper", "lower"])
@pytest.mark.parametrize("node", ["loaded", "free"])
def test_a_nan_reaction_is_refused(energy_answer, wall, node):
    """Property: a reaction that is not a number is no answer, on either wall, at a node
    the wall presses or not (max and min drop a NaN that is not their first argument,
    so a check built on them alone would pass it)."""
    name, chain, alpha, upper, lower = energy_answer
    forces = {"upper": upper.copy(), "lower": lower.copy()}
    f = forces[wall]
    f[int(np.argmax(f)) if node == "loaded" else int(np.argmin(np.abs(f)))] = np.nan
    v = _judge(chain, alpha, forces["upper"], forces["lower"])
    assert not v.converged and v.failed, (name, wall, node)


def test_a_driver_that_did_not_converge_fails_that_check_alone(energy_answer):
    name, chain, alpha, upper, lower = energy_answer
    v = _judge(chain, alpha, upper, lower, converged=False)
    assert not v.converged and v.failed == ["driver"] and v.reason == "converged"
    assert v.certificate is not None and np.isnan(v.force_error_bound)
