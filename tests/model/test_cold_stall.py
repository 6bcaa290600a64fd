"""The solve kernel's stall rule: a cold solve whose line searches keep cutting the step
stops early (compiled_kernel.BAIL_STALL) and is refused, so the loading path answers.

The oracles: the energy minimisation (:mod:`lcpbench.reference.energy`, no
linearisation, no driver) for the answers after the stop, beam theory for the
cantilever, and the rule's own definition on the step records (every short step is
one the line search cut to STALL_STEP or less). A cold start with a link past the
vertical cannot converge in the node heights: the height step's linearisation divides
by cos α_i, which changes sign there (eq. 20; model/compiled_kernel.assemble_into).
"""

import numpy as np
import pytest
from known_answers import CANTILEVER_THEORY_FORCE, PAPER_SCENE

from lcpbench import ActuatorScene, CantileverScene, SectionedScene, solve, solve_many
from lcpbench.model import compiled
from lcpbench.model.kernel_call import BAIL_REASONS, call_kernel, solve_kernel
from lcpbench.reference.energy import minimise_energy
from lcpbench.thresholds import STALL_RUN, STALL_STEP

#: the solve kernel's outcome codes (its module through numba_cache, as the package loads it)
BAIL_STALL, CONVERGED = solve_kernel().BAIL_STALL, solve_kernel().CONVERGED

#: cold starts with a link past the vertical (the rest shape's largest |α|: 91.2° for
#: the rows of θ = 185°, 99.3° for the single section of θ = 200°)
PAST_VERTICAL = [SectionedScene(sections=[(185.0, 15.0), (-185.0, 15.0)], height=h, links=140)
                 for h in (2.0, 3.0)] + [ActuatorScene(theta=200, height=3.0, links=140)]
#: the rule stops such a solve within this many outer steps (measured: 2-4)
WITHIN = 6


def _cold(scene, tol=1e-9, start=None):
    got, _, _ = call_kernel(scene.chain(), tol=tol, max_outer=200, start=start,
                            settings="default", args=None, newton=False)
    code, count, rec = got[0], got[7], got[6]
    return code, rec[:, :count]


@pytest.mark.parametrize("scene", PAST_VERTICAL, ids=["row-185-h2", "row-185-h3", "one-200"])
def test_a_cold_start_past_the_vertical_stops_early(scene):
    assert np.degrees(np.abs(scene.chain().rest_alpha).max()) > 90.0
    code, rec = _cold(scene)
    assert code == BAIL_STALL
    assert STALL_RUN <= rec.shape[1] <= WITHIN
    assert np.all(rec[1, -STALL_RUN:] <= STALL_STEP)  # the rule's definition
    assert np.all(rec[1] > 0)  # each step was taken (a line search that found no decrease
    # ends otherwise: LINE_SEARCH)


@pytest.mark.parametrize("scene", PAST_VERTICAL, ids=["row-185-h2", "row-185-h3", "one-200"])
def test_the_stopped_solve_is_answered_by_the_loading_path(scene):
    """solve() refuses the stopped cold solve and escalates; its answer is the exact
    energy minimum (SLSQP polished by Newton on the KKT system)."""
    ref = minimise_energy(scene)
    assert ref.success and ref.polished, ref.message
    res = solve(scene, tol=1e-9)
    assert res.converged, res.reason
    assert "ramped" in [r.name for r in res.retries]
    assert res.total_force == pytest.approx(ref.total_force, rel=1e-6)


def test_solve_many_answers_the_stopped_rows_by_the_loading_path():
    """Two rows in one batch: the line kernel stops their cold solves by the same rule,
    and the batch's answers are the exact energy minima."""
    rows = PAST_VERTICAL[:2]
    for res, scene in zip(solve_many(rows, tol=1e-9), rows, strict=True):
        assert res.converged, res.reason
        assert res.total_force == pytest.approx(minimise_energy(scene).total_force, rel=1e-6)


def test_the_stop_is_a_refusal_that_the_plan_escalates():
    """The fall-back of a stall is the not-converged arc (no rerun in node heights), as
    for the refused steps the stall would have gone on to."""
    why = BAIL_REASONS[BAIL_STALL]
    assert why in compiled.REFUSED_STEPS and why in compiled.ROUNDOFF_BAILS
    chain = PAST_VERTICAL[0].chain()
    out = compiled.stopped(chain, why)
    assert not out.converged and why in out.reason
    assert np.array_equal(out.alpha, chain.rest_alpha)


def test_a_warm_start_is_not_stopped_by_the_rule():
    """The rule is the cold start's: the same shape given as a start is solved on
    (the same steps up to the stop, then on until the kernel's own refusal)."""
    from lcpbench.model.outer import DriverStart

    scene = PAST_VERTICAL[0]
    code, rec = _cold(scene)
    warm_code, warm_rec = _cold(scene, start=DriverStart(scene.chain().rest_alpha.copy()))
    assert code == BAIL_STALL and warm_code not in (BAIL_STALL, CONVERGED)
    assert warm_rec.shape[1] > rec.shape[1]
    assert np.array_equal(warm_rec[:, :rec.shape[1]], rec)


@pytest.mark.parametrize("scene", [ActuatorScene(**PAPER_SCENE),
                                   ActuatorScene(theta=180, height=1.0, channel=True),
                                   ActuatorScene(theta=90, height=5.0), CantileverScene()],
                         ids=["paper", "channel-180", "grazing", "cantilever"])
@pytest.mark.parametrize("tol", [1e-3, 1e-9])
def test_the_rule_does_not_fire_where_the_cold_solve_converges(scene, tol):
    """The paper's scenes and the cantilever converge cold, with no step the line search
    cut anywhere near STALL_STEP (the measured margin: 1/32 at worst, on 1773 cold
    solves that converged)."""
    code, rec = _cold(scene, tol)
    assert code == CONVERGED
    assert rec[1].min() >= 32 * STALL_STEP


def test_the_cantilever_is_still_beam_theory():
    """Eqs. (34)-(37): the wall's reaction on the tip at the paper's load."""
    res = solve(CantileverScene(), tol=1e-8)
    assert res.converged
    assert res.total_force == pytest.approx(CANTILEVER_THEORY_FORCE, rel=2e-2)
