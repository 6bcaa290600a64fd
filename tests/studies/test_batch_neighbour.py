"""solve_many's rows of sections: a row the kernel refuses cold starts from a
neighbouring row's answer (the escalation ``from_neighbour``, SQP steps in the link
angles) before the loading path; only rows the loading path solved serve as neighbours.

Oracles: first principles (``energy_oracle.assert_solved``: forward kinematics, the
walls, the reactions' signs and complementarity, stationarity by central differences of
the exact energy), and for the state, the minimum of the exact energy followed along the
load (:func:`_along_load`: SLSQP and a Newton polish, ``reference.energy.minimise_energy``,
at the bend angles s·θ in 4° steps, each started from the last), the state the
pressurised actuator reaches, which the loading path is meant to find.
"""

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import SectionedScene
from lcpbench.reference.energy import minimise_energy
from lcpbench.studies.batch import NEIGHBOUR_DEG, NEIGHBOUR_MM, neighbouring_row, row_shape


def _row(theta: float, height: float, links: int = 140) -> SectionedScene:
    return SectionedScene(sections=[(theta, 15.0), (-theta, 15.0)], height=height, links=links)


def _along_load(scene, deg: float = 4.0):
    """The energy minimum of ``scene`` followed along the load: each section's θ scaled
    by s = 1/m, 2/m, …, 1 (steps of at most ``deg``), each minimisation started from the
    last answer."""
    m = int(np.ceil(max(abs(a.theta) for a in scene.sections) / deg))
    alpha = None
    for k in range(1, m + 1):
        ref = minimise_energy(scene.chain_at(k / m), start=alpha)
        assert ref.success, ref.message
        alpha = ref.alpha
    return ref


def _same_force(res, ref) -> bool:
    """The answer's total force is the oracle's to the judge's own accuracy τ·F₀."""
    j = res.judgement
    return abs(res.total_force - ref.total_force) <= j.force_tol * j.force_unit


#: two rows (θ, −θ) that the solve kernel refuses cold (links near the vertical at the
#: answer), 5.4° apart at one h: the first has no certified neighbour when it is refused
#: (the loading path), the second then has the first
ROWS = ((168.6, 2.02), (174.0, 2.02))


@pytest.fixture(scope="module")
def batch():
    return lcpbench.solve_many([_row(*r) for r in ROWS], tol=1e-3)


def test_cold_refusal_then_loading_path_then_neighbour(batch):
    first, second = batch
    assert [r.name for r in first.retries] == ["ramped"]  # refused cold, no neighbour yet
    assert [r.name for r in second.retries] == ["from_neighbour"]


@pytest.mark.parametrize("k", range(len(ROWS)))
def test_each_answer_is_an_equilibrium(batch, k):
    assert_solved(batch[k])


def test_the_state_reached_along_the_load(batch):
    assert _same_force(batch[1], _along_load(batch[1].scene))


def test_only_the_loading_paths_answers_are_neighbours():
    """A sweep of rows (θ, θ, −θ), 12° apart, in one batch: past ~180° some rows are
    certified cold clear of the wall (0 N) and others pressed on it; a continuation from a
    row certified cold certified 0 N at 220°, where the loading path and the energy
    minimum followed along the load give 1.67 N (found by review). Every row that takes
    ``from_neighbour`` is in the state of the energy minimum followed along the load."""
    rows = [SectionedScene(sections=[(t, 15.0), (t, 15.0), (-t, 15.0)], height=2.6, links=90)
            for t in np.arange(256.0, 99.0, -12.0)]
    got = lcpbench.solve_many(rows, tol=1e-3)
    took = [r for r in got if r.retries and r.retries[-1].name == "from_neighbour"]
    assert len(took) >= 3
    for res in took:
        assert res.converged
        assert _same_force(res, _along_load(res.scene)), res.scene.sections[0].theta


def test_a_row_too_far_gets_no_neighbour():
    near, far_theta, far_h = (_row(150.0, 2.0), _row(150.0 + 1.5 * NEIGHBOUR_DEG, 2.0),
                              _row(150.0, 2.0 + 1.5 * NEIGHBOUR_MM))
    solved = lcpbench.solve(near)
    assert neighbouring_row(_row(150.0 + 0.5 * NEIGHBOUR_DEG, 2.0), [(row_shape(near), near, solved)]) is solved
    assert neighbouring_row(far_theta, [(row_shape(near), near, solved)]) is None
    assert neighbouring_row(far_h, [(row_shape(near), near, solved)]) is None
    # another sign of a bend angle, or another section count, is another row
    flipped = SectionedScene(sections=[(-150.0, 15.0), (150.0, 15.0)], height=2.0, links=140)
    assert neighbouring_row(flipped, [(row_shape(near), near, solved)]) is None
