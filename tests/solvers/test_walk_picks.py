"""The dual walks' pick rule (linalg/walk_picks), against its definition written here.

Both walks add, at a face minimiser, the warm contact set's violated nodes first, then
every local maximum (v_i ≥ v_{i−1}, v_i > v_{i+1}) of the violations v beyond the
slack (a slack per node: the walk in heights has the same for every node, the walk at
large N its own). The oracle is that definition, evaluated here with numpy on random
violations with ties, held nodes and a lower wall, over the whole chain and over a
range that holds every violated node.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from lcpbench.numba_cache import kernel_module

KERN = kernel_module("lcpbench.linalg.walk_picks", "picks_in")


def violations(u, wall, held, side):
    """v = u − wall (upper, side +1) or wall − u (lower), −∞ on held nodes."""
    v = (u - wall) if side > 0 else (wall - u)
    return np.where(held, -np.inf, v)


def local_maxima(v, slack):
    """The definition: nodes with v_i > slack_i, v_i ≥ v_{i−1}, v_i > v_{i+1} (−∞ beyond
    the ends)."""
    padded = np.concatenate(([-np.inf], v, [-np.inf]))
    mid = padded[1:-1]
    return np.flatnonzero((mid > slack) & (mid >= padded[:-2]) & (mid > padded[2:]))


cases = st.integers(1, 40).flatmap(lambda n: st.tuples(
    st.lists(st.sampled_from([-1.0, -0.25, 0.0, 1e-17, 0.3, 0.3, 0.7, 1.0]), min_size=n,
             max_size=n),
    st.lists(st.booleans(), min_size=n, max_size=n),
    st.lists(st.sampled_from([0.0, 0.5, 2.0]), min_size=n, max_size=n)))


@settings(max_examples=150, deadline=None)
@given(case=cases, side=st.sampled_from([1, -1]), slack=st.sampled_from([0.0, 1e-16, 0.3]))
def test_picks_are_the_local_maxima_beyond_the_slack(case, side, slack):
    levels, held, wall = (np.asarray(x) for x in case)
    held = held.astype(bool)
    u = wall + side * levels  # v = levels off the held nodes
    n = u.size
    v = violations(u, wall, held, side)
    want = local_maxima(v, slack)
    picks = np.zeros(2 * n, np.int64)
    count = KERN.picks_in(u, wall, side, np.full(n, slack), held, 0, picks, 0, 0, n - 1)
    assert np.array_equal(picks[:count], side * (want + 1))
    over = np.flatnonzero(v > slack)  # the large-N walk scans the violated range only
    if over.size:
        count = KERN.picks_in(u, wall, side, np.full(n, slack), held, 0, picks, 0,
                              over[0], over[-1])
        assert np.array_equal(picks[:count], side * (want + 1))


def test_per_node_slack_is_read_per_node():
    v = np.array([0.5, 0.4, 0.1, 0.3, 0.2])
    slacks = np.array([1.0, 0.0, 0.0, 0.0, 0.0])  # node 0 is not violated beyond its own
    held = np.zeros(5, bool)
    picks = np.zeros(10, np.int64)
    count = KERN.picks_in(v, np.zeros(5), 1, slacks, held, 0, picks, 0, 0, 4)
    assert list(picks[:count]) == list(local_maxima(v, slacks) + 1) == [4]
    count = KERN.picks_in(v, np.zeros(5), 1, np.zeros(5), held, 0, picks, 0, 0, 4)
    assert list(picks[:count]) == [1, 4]  # a slack of 0 at every node: node 0 too


def test_warm_picks_take_the_violated_warm_nodes_in_order():
    hi = np.zeros(6)
    lo = np.full(6, -1.0)
    u = np.array([0.5, 0.0, -2.0, 0.2, 0.9, -1.5])
    warm_up = np.array([True, True, False, True, False, False])
    warm_lo = np.array([False, False, True, False, False, True])
    held = np.array([False, False, False, True, False, False])
    picks = np.zeros(12, np.int64)
    count = KERN.warm_picks(u, hi, lo, True, held, np.full(6, 0.1), warm_up, warm_lo, picks)
    # node 0 above its upper wall, 2 and 5 below the lower one; 1 within the slack,
    # 3 held, 4 not in the warm set
    assert list(picks[:count]) == [1, -3, -6]
    assert KERN.warm_picks(u, hi, lo, False, held, np.full(6, 0.1), warm_up, warm_lo,
                           picks) == 1
