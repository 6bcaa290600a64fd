"""Large N at tol 1e-3 (issue 19, item 3): accepted by the unchanged judge, and wrong answers still rejected.

At N >= 10⁴ a point contact is shared by two neighbouring nodes, and their split
moves by ~4 EI δφ / a² per joint-angle error δφ: after max|Δα| < 1e-3 the nodes
were 0.1–1 F₀ off while the total force was within τ. The judge's rules are
unchanged; the large-N driver (:mod:`lcpbench.model.large_driver`) goes on past
max|Δα| < tol until its prediction of the judge's per-node bound holds. These
tests check that such answers are accepted, that they are right (against a
tight-tol solve), and that answers with a known defect are still rejected.
"""

from __future__ import annotations

import numpy as np
import pytest

from lcpbench import ActuatorScene, solve
from lcpbench.model import large_driver, nested_start
from lcpbench.model.judge import force_tol, judge
from lcpbench.model.result import certify
from lcpbench.thresholds import NODE_GROSS

N = 10_000


@pytest.fixture(scope="module")
def answer():
    res = solve(ActuatorScene(150, 3.0, links=N), tol=1e-3)
    assert res.judge == "increments"  # the judge in increments (large N)
    return res


def _judged(res, upper):
    chain = res.scene.chain()
    lower = np.zeros_like(upper)
    return judge(chain, res.alpha, upper, lower, tol=res.tol, driver_converged=True,
                 driver_reason="converged", step_statuses=["solved"] * len(res.steps),
                 step_sizes=[s.max_dalpha for s in res.steps],
                 certificate=lambda up, lo: certify(chain, res.alpha, up, lo))


def test_a_large_n_answer_at_tol_1e3_is_accepted_by_the_per_node_rule(answer):
    assert answer.converged, answer.reason
    j = answer.judgement
    assert j.node_error_bound <= NODE_GROSS  # per node, not a looser measure
    assert j.force_error_bound <= force_tol(1e-3)


def test_the_accepted_nodes_are_within_their_bound_of_a_tight_solve(answer):
    """Route against route: at N = 10⁴ central differences of the energy cost ~20 s per
    answer and SLSQP is out of reach; the tight solve is the same equilibrium to ~1e-6
    F₀, far inside the tol-1e-3 bound checked."""
    # an independent reference: the same scene solved to tol 1e-8 (nodes ~1e-6 F₀ apart)
    tight = solve(ActuatorScene(150, 3.0, links=N), tol=1e-8)
    assert tight.converged, tight.reason
    F0 = answer.judgement.force_unit
    err = float(np.max(np.abs(answer.forces - tight.forces))) / F0
    assert err <= answer.judgement.node_error_bound + 1e-6
    assert abs(answer.total_force - tight.total_force) / F0 <= force_tol(1e-3)


def test_without_the_extra_steps_the_same_judge_rejects_the_unsettled_split(monkeypatch,
                                                                           skip_escalations):
    # what the driver returned before: max|Δα| < tol, nodes not settled. The judge must
    # reject it (the extra steps make the answer right, the judge is not loosened). From
    # the cold start: a nested start (:mod:`lcpbench.model.nested_start`) begins within
    # the discretisation error of the answer, and its first step may settle already
    monkeypatch.setattr(large_driver, "EXTRA_STEPS", 0)
    monkeypatch.setattr(nested_start, "COARSE_LINKS", 0)
    # the driver's answer as it is: lcpbench.solve would continue a refusal on the force
    # bound alone at a tighter tolerance (escalations.tightened; the next test)
    skip_escalations("tightened", "ramped")  # (nor the load path)
    res = solve(ActuatorScene(150, 3.0, links=N), tol=1e-3)
    assert not res.converged
    assert "force error bound" in res.judgement.failed
    assert res.judgement.node_error_bound > NODE_GROSS


def test_without_the_extra_steps_solve_continues_to_the_same_answer(monkeypatch, answer):
    """Route against route: N = 10⁴, where no oracle is in reach (see above)."""
    # the same unsettled answer, continued by lcpbench.solve at a tenth of the driver's
    # tolerance: certified, and within tau of the answer with the extra steps (another
    # route to the same equilibrium)
    monkeypatch.setattr(large_driver, "EXTRA_STEPS", 0)
    monkeypatch.setattr(nested_start, "COARSE_LINKS", 0)
    res = solve(ActuatorScene(150, 3.0, links=N), tol=1e-3)
    assert res.converged, res.reason
    assert "force error bound alone" in res.retried("tightened")
    F0 = max(answer.total_force, answer.scene.EI / answer.scene.length**2)
    assert abs(res.total_force - answer.total_force) <= force_tol(1e-3) * F0


def _top(res):
    top = int(np.argmax(res.forces))
    nb = top + 1 if res.forces[top + 1] >= res.forces[top - 1] else top - 1
    return top, nb  # the contact's two nodes


@pytest.mark.parametrize("defect", ["split", "to the other contact", "scaled", "exact"])
def test_perturbed_large_n_answers_are_rejected(answer, defect):
    f = answer.forces.copy()
    top, nb = _top(answer)
    other = int(np.argmax(np.where(np.abs(np.arange(f.size) - top) > 10, f, 0.0)))
    if defect == "split":  # 13 % of the contact's force moved to its partner node
        share = 0.13 * f[top]
        f[top] -= share
        f[nb] += share
    elif defect == "to the other contact":  # the total kept, 13 % moved across the chain
        share = 0.13 * f[top]
        f[top] -= share
        f[other] += share
    elif defect == "scaled":  # every node 2 τ too large
        f *= 1.0 + 2 * force_tol(1e-3)
    verdict = _judged(answer, f)
    if defect == "exact":
        assert verdict.converged, verdict.reason
    else:
        assert not verdict.converged
        assert "force error bound" in verdict.failed

