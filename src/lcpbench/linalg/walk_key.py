"""The dual walks' working-set key, compiled: one 64-bit hash of (node, wall) per held
node, the set's key the XOR of its nodes' (a change of one node updates it in O(1)).

Both walks record the keys of the working sets they met and stop where one repeats:
the walk in node heights (:func:`lcpbench.solvers.dual_kernel.dual_active_set`) and the
walk on a twisted factor at large N (:func:`lcpbench.linalg.twisted_walk_kernel.walk`).
A collision of two keys only stops a walk early (its caller's fall-back goes on).
"""

from __future__ import annotations

import numpy as np
from numba import config, njit

# splitmix64's golden-ratio increment γ and its finaliser's multipliers (Steele, Lea &
# Flood 2014)
M1, M2, M3 = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9),
              np.uint64(0x94D049BB133111EB))


def _wrapping(f):
    """``f``, whose uint64 products wrap modulo 2⁶⁴: compiled they wrap silently; as plain
    Python (``NUMBA_DISABLE_JIT=1``) numpy's scalars wrap the same but warn of overflow,
    silenced here (the same numbers either way)."""
    if not config.DISABLE_JIT:
        return f

    def wrapped(*args):
        with np.errstate(over="ignore"):
            return f(*args)

    return wrapped


@_wrapping
@njit(cache=True)
def walk_key(i, side):
    """The key of node i held on the upper (``side`` > 0) or the lower wall (< 0): the
    splitmix64 finaliser of (2i + 1)·γ or (2i + 2)·γ (mod 2⁶⁴; an odd multiplier and the
    finaliser are bijections, so no two (node, wall) share a key); 0 off the walls
    (``side`` 0)."""
    if side == 0.0:
        return np.uint64(0)
    z = np.uint64(2 * i + (1 if side > 0 else 2)) * M1
    z = (z ^ (z >> np.uint64(30))) * M2
    z = (z ^ (z >> np.uint64(27))) * M3
    return z ^ (z >> np.uint64(31))
