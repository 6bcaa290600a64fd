"""solve_many's rows of sections: a row the kernel refuses cold starts from a
neighbouring row's answer (the escalation ``from_neighbour``, SQP steps in the link
angles) before the loading path.

The oracle is first principles (``energy_oracle.assert_solved``: forward kinematics,
the walls, the reactions' signs and complementarity, stationarity by central
differences of the exact energy). Which of several stable states a row should be in has
no oracle outside lcpbench: the loading path defines it (the state the pressurised
actuator reaches), so ``test_the_loading_paths_state`` compares the batch's answer with
``lcpbench.solve``'s, the loading path's, by their wall forces: a route-against-route
check kept because no independent method picks the state.
"""

import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import SectionedScene
from lcpbench.escalations import same_state
from lcpbench.studies.batch import NEIGHBOUR_DEG, NEIGHBOUR_MM, neighbouring_row, row_shape


def _row(theta: float, height: float, links: int = 140) -> SectionedScene:
    return SectionedScene(sections=[(theta, 15.0), (-theta, 15.0)], height=height, links=links)


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


def test_the_loading_paths_state(batch):
    alone = lcpbench.solve(_row(*ROWS[1]))  # the loading path (its retries say so)
    assert alone.converged and [r.name for r in alone.retries] == ["ramped"]
    assert same_state(batch[1], alone)


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
