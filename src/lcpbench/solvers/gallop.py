"""Which violated walls the dual walk adds next, galloping from its contacts (large N).

The dual active-set walk (:func:`lcpbench.solvers.banded._dual`) may put *any*
violated node against its wall: the dual objective rises on every move of
non-zero length whichever violated node joins (Goldfarb & Idnani, 1983), so the
choice changes the path, never the answer. Its default choice is the deepest
node of every run of consecutive violated nodes (:func:`.banded._run_maxima`).
At large N, warm-started from the last outer step's contact set, that choice
bisects: when a point contact has moved by a few nodes, the warm face releases
the old contact, the chain between two contacts bulges through the wall over
thousands of nodes, and the deepest node is in the middle of the span; each
halving costs two face solves (add, release), ~2 log₂(span) in all, even for a
move of one node (30 face solves at N = 10⁵).

:func:`gallop_picks` searches from the contacts instead: a run of violated nodes
next to a held node (the contact it moved away from) gets the node ``reach``
nodes into the run, with ``reach`` = 1, 2, 4, … (doubled at every use within a
walk); a run no longer than ``reach``, or with no held neighbour, gets its
deepest node, as before. A move of k nodes then costs ~2 log₂ k face solves to
overshoot it, and a bisection of the overshoot (at most ``reach`` nodes) after.
"""

from __future__ import annotations

import numpy as np


def gallop_picks(v: np.ndarray, slack: float | np.ndarray, held: np.ndarray,
                 reach: int) -> np.ndarray:
    """The nodes to add (a mask): per run of ``v > slack``, the node ``reach`` nodes
    in from each end that borders a held node (``held``) when the run is longer than
    ``reach``, else the run's deepest node (the first of equal ones).

    ``v``: the violations (−inf on held nodes); ``reach >= 1``.
    """
    viol = v > slack
    picks = np.zeros(v.size, bool)
    idx = np.flatnonzero(viol)
    if idx.size == 0:
        return picks
    breaks = np.flatnonzero(np.diff(idx) > 1)
    starts = np.concatenate((idx[:1], idx[breaks + 1]))
    ends = np.concatenate((idx[breaks], idx[-1:]))
    n = v.size
    for a, b in zip(starts.tolist(), ends.tolist()):
        left = a >= 1 and bool(held[a - 1])
        right = b + 1 < n and bool(held[b + 1])
        if (left or right) and b - a + 1 > reach:
            if left:
                picks[a + reach - 1] = True
            if right:
                picks[b - reach + 1] = True
        else:
            picks[a + int(np.argmax(v[a:b + 1]))] = True
    return picks
