"""The dual walk at large N with its loop compiled (:func:`lcpbench.linalg.twisted_walk_kernel.walk`).

:func:`lcpbench.solvers.banded._dual` on a step with its own twisted factor
(large N, in increments): the walk of :func:`lcpbench.solvers.dual_kernel.dual_active_set`
— the warm contact set first, then nodes galloping from the contacts (below) or the
local maxima of each violated run (:mod:`lcpbench.linalg.walk_picks`), every move to
a face minimiser one compiled face solve, the ratio test, the releases within
``tie`` — with the per-face bookkeeping
(violations, picks, the working set's key, the twist, the ratio test) in the same
compiled call as the face solves. The refinement at every optimum it finds, with the
step's exact factored gradient, is one compiled call too where the step has it
(:meth:`lcpbench.model.large_n.IncrementStep.walk_refine`), else :func:`refine_on_face`.

**Galloping** (:func:`lcpbench.linalg.walk_picks.picks_in` with ``reach`` > 0).
The walk may put *any* violated node against its wall: the dual objective rises on
every move of non-zero length whichever violated node joins (Goldfarb & Idnani,
1983), so the choice changes the path, never the answer. Its default choice is
every local maximum of the violations in each run of consecutive violated nodes
(along a wall with one bulge, the deepest node). At large N, warm-started
from the last outer step's contact set, that choice bisects: when a point contact
has moved by a few nodes, the warm face releases the old contact, the chain between
two contacts bulges through the wall over thousands of nodes, and the deepest node
is in the middle of the span; each halving costs two face solves (add, release),
~2 log₂(span) in all, even for a move of one node (30 face solves at N = 10⁵).
Galloping searches from the contacts instead: a run of violated nodes next to a held
node (the contact it moved away from) gets the node ``reach`` nodes into the run,
with ``reach`` = 1, 2, 4, … (doubled at every use within a walk); a run no longer
than ``reach``, or with no held neighbour, gets its deepest node. A move
of k nodes then costs ~2 log₂ k face solves to overshoot it, and a bisection of the
overshoot (at most ``reach`` nodes) after.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import LinAlgError

#: working sets remembered (their hashes) to see one repeat
SEEN = 4096
#: the refinement at an optimum in one compiled call where the step has it
#: (:meth:`lcpbench.model.large_n.IncrementStep.walk_refine`); False: numpy
COMPILED_REFINE = True


def dual_walk(step, H, u, slack, warm_up, warm_lo, has_lo: bool, max_iter: int,
              reach: int, tie: float, refine):
    """``(u, grad, S_up, S_lo, face_solves, why)`` as :func:`banded._dual` (own factor
    ``H`` with ``walk``; ``u`` the unconstrained minimiser, just solved on ``H``;
    ``refine(step, H, S, u)`` the walk's refinement, :func:`refine_on_face`)."""
    n = step.size
    u = np.array(u, dtype=float)
    # written, not np.zeros: pages of np.zeros that are only read are slow to read in
    # compiled loops (the face move reads ``wall`` at every node; 2x the walk at 10⁵)
    g = np.full(n, 0.0)  # the gradient there, up to round-off
    sigma, wall = np.full(n, 0.0), np.full(n, 0.0)
    warm = bool(np.count_nonzero(warm_up) or np.count_nonzero(warm_lo))
    ctl = np.array([0, 0, int(reach), int(warm), 0, 0, 0], dtype=np.int64)
    seen = np.zeros(min(max_iter + 2, SEEN), dtype=np.uint64)
    slack = np.ascontiguousarray(np.broadcast_to(slack, (n,)), dtype=float)
    up_w = np.ascontiguousarray(warm_up, dtype=np.bool_)
    lo_w = np.ascontiguousarray(warm_lo, dtype=np.bool_)
    while True:
        code = H.walk(ctl, step, slack, u, g, sigma, wall, up_w, lo_w, has_lo, tie,
                      max_iter, seen)
        it = int(ctl[1])
        if code == 1:
            return u, None, sigma > 0, sigma < 0, it, "a working set repeated (round-off)"
        if code == 2:
            return u, None, sigma > 0, sigma < 0, it, f"limit of {max_iter} face solves"
        if code == 3:
            raise LinAlgError("a face of H is singular (zero pivot)")
        S = sigma != 0.0
        u = np.where(S, wall, u)
        if ctl[4]:  # refined, and no wall violated after it: the optimum
            return u, step.gradient(u), sigma > 0, sigma < 0, it, None
        # the optimum of the unrefined moves: one step of refinement with the exact
        # gradient on the face just factored, more while it halves; then the walls again
        if COMPILED_REFINE and H is getattr(step, "factor", None) and \
                hasattr(step, "walk_refine") and refine is refine_on_face:
            u, g = step.walk_refine(S, u)  # the same arithmetic in one compiled call
        else:
            r = step.gradient(u)
            r[S] = 0.0
            u, g = refine(step, H, S, u - H.resolve(r))
        u = np.ascontiguousarray(u, dtype=float)
        g = np.ascontiguousarray(g, dtype=float)
        ctl[4] = 1


def refine_on_face(step, H, S, u, rounds: int = 4):
    """More refinement on the last face while the free nodes' residual halves (a
    step with its own face solves, at large N: there one refinement contracts by
    cond(J) ε only, and a height error δ costs ~16 EI δ / a³ of force)."""
    g = step.gradient(u)
    r = np.where(S, 0.0, g)
    size = float(np.max(np.abs(r), initial=0.0))
    for _ in range(rounds):
        v = u - H.resolve(r)
        g_v = step.gradient(v)
        r_v = np.where(S, 0.0, g_v)
        size_v = float(np.max(np.abs(r_v), initial=0.0))
        if not size_v < 0.5 * size:
            break
        u, g, r, size = v, g_v, r_v, size_v
    return u, g
