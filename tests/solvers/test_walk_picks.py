"""The dual walks' pick rule (linalg/walk_picks), against its definition written here.

Both walks add, at a face minimiser, the warm contact set's violated nodes first, then
every local maximum (v_i ≥ v_{i−1}, v_i > v_{i+1}) of the violations v beyond the
slack (a slack per node: the walk in heights has the same for every node, the walk at
large N its own). The oracle is that definition, evaluated here with numpy on random
violations with ties, NaN, held nodes, infinite walls and a slack per node, over the
whole chain and over a range that holds every node violated beyond its slack (the
range the large-N walk scans).
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lcpbench.numba_cache import kernel_module

KERN = kernel_module("lcpbench.linalg.walk_picks", "picks_in")


def violations(u, wall, held, side):
    """v = u − wall (upper, side +1) or wall − u (lower), −∞ on held nodes."""
    with np.errstate(invalid="ignore"):
        v = (u - wall) if side > 0 else (wall - u)
    return np.where(held, -np.inf, v)


def local_maxima(v, slack):
    """The definition: nodes with v_i > slack_i, v_i ≥ v_{i−1}, v_i > v_{i+1} (−∞ beyond
    the ends)."""
    padded = np.concatenate(([-np.inf], v, [-np.inf]))
    mid = padded[1:-1]
    with np.errstate(invalid="ignore"):
        return np.flatnonzero((mid > slack) & (mid >= padded[:-2]) & (mid > padded[2:]))


LEVELS = [-1.0, -0.25, 0.0, 1e-17, 0.3, 0.3, 0.7, 1.0, np.nan]
cases = st.integers(1, 40).flatmap(lambda n: st.tuples(
    st.lists(st.sampled_from(LEVELS), min_size=n, max_size=n),
    st.lists(st.booleans(), min_size=n, max_size=n),
    st.lists(st.sampled_from([0.0, 0.5, 2.0, np.inf]), min_size=n, max_size=n),
    st.lists(st.sampled_from([0.0, 1e-16, 0.3, 0.5]), min_size=n, max_size=n)))


@settings(max_examples=300, deadline=None)
@given(case=cases, side=st.sampled_from([1, -1]), before=st.integers(0, 3))
def test_picks_are_the_local_maxima_beyond_the_slack(case, side, before):
    levels, held, wall, slack = (np.asarray(x, dtype=float) for x in case)
    held = held.astype(bool)
    wall = side * wall  # an upper wall at +inf, a lower one at -inf: never violated
    u = np.where(np.isfinite(wall), wall + side * levels, 0.0)
    n = u.size
    v = violations(u, wall, held, side)
    want = list(side * (local_maxima(v, slack) + 1))
    picks = np.zeros(2 * n + 4, np.int64)
    picks[:before] = 99  # picks of the other wall, kept: the new ones are appended
    count = KERN.picks_in(u, wall, side, slack, held, 0, picks, before, 0, n - 1)
    assert list(picks[:before]) == [99] * before
    assert list(picks[before:count]) == want
    with np.errstate(invalid="ignore"):
        over = np.flatnonzero(v > slack)  # the large-N walk scans the violated range only
    first, last = (over[0], over[-1]) if over.size else (0, -1)
    count = KERN.picks_in(u, wall, side, slack, held, 0, picks, before, first, last)
    assert list(picks[before:count]) == want


def test_per_node_slack_is_read_per_node():
    v = np.array([0.5, 0.4, 0.1, 0.3, 0.2])
    slacks = np.array([1.0, 0.0, 0.0, 0.0, 0.0])  # node 0 is not violated beyond its own
    held = np.zeros(5, bool)
    picks = np.zeros(10, np.int64)
    count = KERN.picks_in(v, np.zeros(5), 1, slacks, held, 0, picks, 0, 0, 4)
    assert list(picks[:count]) == list(local_maxima(v, slacks) + 1) == [4]
    count = KERN.picks_in(v, np.zeros(5), 1, np.zeros(5), held, 0, picks, 0, 0, 4)
    assert list(picks[:count]) == [1, 4]  # a slack of 0 at every node: node 0 too
    # node 0, outside a range 1 .. 4, still bounds node 1 from the left
    count = KERN.picks_in(v, np.zeros(5), 1, slacks, held, 0, picks, 0, 1, 4)
    assert list(picks[:count]) == [4]
    assert KERN.picks_in(v, np.zeros(5), 1, slacks, held, 0, picks, 0, 5, 4) == 0  # empty


def test_warm_picks_take_the_violated_warm_nodes_in_order():
    hi = np.zeros(7)
    lo = np.full(7, -1.0)
    u = np.array([0.5, 0.0, -2.0, 0.2, 0.9, -1.5, 0.4])
    warm_up = np.array([True, True, False, True, False, False, True])
    warm_lo = np.array([False, False, True, False, False, True, True])
    held = np.array([False, False, False, True, False, False, False])
    picks = np.zeros(14, np.int64)
    count = KERN.warm_picks(u, hi, lo, True, held, np.full(7, 0.1), warm_up, warm_lo, picks)
    # node 0 and 6 above their upper wall (6 is in both warm sets: its upper wall, the one
    # violated), 2 and 5 below the lower one; 1 within the slack, 3 held, 4 not warm
    assert list(picks[:count]) == [1, -3, -6, 7]
    count = KERN.warm_picks(u, hi, lo, False, held, np.full(7, 0.1), warm_up, warm_lo,
                            picks)
    assert list(picks[:count]) == [1, 7]  # no lower wall: its warm nodes are not picked
    u[6] = -1.5  # in both warm sets, below its lower wall: the lower wall's pick
    count = KERN.warm_picks(u, hi, lo, True, held, np.full(7, 0.1), warm_up, warm_lo, picks)
    assert list(picks[:count]) == [1, -3, -6, -7]
    lo[6] = 0.5  # walls crossed at node 6 (both violated): a node joins one wall, the upper
    u[6] = 0.3
    count = KERN.warm_picks(u, hi, lo, True, held, np.full(7, 0.1), warm_up, warm_lo, picks)
    assert list(picks[:count]) == [1, -3, -6, 7]
