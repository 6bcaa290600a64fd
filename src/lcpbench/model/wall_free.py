"""The wall-free path: a scene that touches no wall is answered without any LCP.

With no load the unconstrained arc is the answer when it clears every wall.
With a load (gravity) the unconstrained shape is the equilibrium of the chain
without walls, found by the same globalised driver (Fig. 3, line-searched)
with each step a banded solve of K u = −z (eq. 30 with no reactions); if it
clears every wall it is the answer. Otherwise the scene is solved with its
walls. The tests that decide which (:func:`~.wall_free_kernel.arc_kind`) are compiled
once, for this module and the batch kernel's lines.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..numba_cache import kernel_module
from ..problems.scenes import Chain
from . import large_n
from .angle_step import heavy
from .chain import heights
from .kernel_call import applies, kernel_args, run_compiled
from .outer import DriverOutput, DriverStart
from .profile import walls_at


def _tests():
    """The compiled wall-free tests (:mod:`.wall_free_kernel`), loaded once."""
    return kernel_module("lcpbench.model.wall_free_kernel", "arc_kind")


def wall_overlap(chain: Chain, u: np.ndarray) -> float:
    """How far free-node heights ``u`` cross the walls (mm; < 0: strictly
    between them; NaN if u has a NaN)."""
    f64 = np.ascontiguousarray
    return float(_tests().wall_overlap(f64(u, dtype=float), f64(chain.lower, dtype=float),
                                       f64(chain.upper, dtype=float)))


def _arc_arrays(chain: Chain) -> tuple:
    """(α, a, free nodes, link loads, lower, upper, ℓ, F) of the chain's arc, as the
    compiled tests take them (the chain's own arrays where they are already so)."""
    f64 = np.ascontiguousarray
    return (f64(chain.rest_alpha, dtype=float), float(chain.link_length),
            f64(chain.free_nodes, dtype=np.int64), f64(chain.link_load, dtype=float),
            f64(chain.lower, dtype=float), f64(chain.upper, dtype=float),
            float(chain.length), float(chain.force_scale))


def arc_kind(chain: Chain) -> int:
    """What the chain's arc says of its scene before any step
    (:func:`lcpbench.model.wall_free_kernel.arc_kind`; kept with the chain)."""
    return chain.derived("_arc_kind", lambda: int(_tests().arc_kind(*_arc_arrays(chain))))


def arc_far(chain: Chain) -> bool:
    """A cheap sufficient test that :func:`solve_without_contact` finds nothing: the
    arc's middle free node alone crosses the upper wall by more than the search could
    sag it off (:func:`lcpbench.model.wall_free_kernel.arc_far_past_wall`). False says
    nothing."""
    return arc_kind(chain) == _tests().FAR


def free_layout(chain: Chain) -> Chain:
    """The chain with its walls removed (kept with the chain): the search's chain."""
    return chain.derived("_without_walls", lambda: _without_walls(chain))


def _without_walls(chain: Chain) -> Chain:
    n = chain.free_nodes.size
    return replace(chain, upper=np.full(n, np.inf), lower=np.full(n, -np.inf),
                   upper_profile=None, lower_profile=None)


def solve_without_contact(chain: Chain, tol: float, max_outer: int,
                          start: DriverStart | None = None, *, args: tuple | None = None
                          ) -> DriverOutput | None:
    """The answer of a scene that touches no wall, found without any LCP (or None).

    A continuation's ``start`` (a neighbour's shape) starts the search too.
    It is looked for when the arc clears the walls, or when the first step of
    that search (one banded solve at the arc, ~0.1 ms at N = 140) already
    does: a heavy chain can sag off a wall its arc crosses.

    The search runs in the solve kernel on the chain with its walls removed
    (:func:`lcpbench.model.kernel_call.run_compiled`: the dual active set with no bounds
    is the banded solve of the free step, refined once), whatever its walls (a wall
    profile too); None where the kernel does not take that chain (joints or free nodes
    not consecutive) or stops: the scene is then solved with its walls. ``args``: the
    chain's :func:`lcpbench.model.kernel_call.kernel_args`, when the caller has them.
    """
    n = chain.free_nodes.size
    if heavy(chain):  # links past the vertical: the angle steps (model/heavy_driver.py)
        return None
    k, kind = _tests(), arc_kind(chain)
    if kind in (k.FAR, k.CONTACT):
        return None
    if kind == k.ARC:
        return DriverOutput(chain.rest_alpha.copy(), np.zeros(n), np.zeros(n), True,
                            "no contact: the unconstrained arc clears every wall and there "
                            "is no load")
    free = free_layout(chain)
    if not applies("auto", "globalised", free):
        return None  # (a layout no compiled route takes: drive answers the scene)
    if large_n.applies(chain):
        # the search's steps are banded solves in heights, whose round-off grows as N⁴:
        # at N = 10⁴ its equilibrium is 1e-4 F₀ off per node, which the judge rejects;
        # the increment driver solves it (with no contact in its steps)
        return None
    if args is None:
        args = kernel_args(chain)
    if kind == k.FIRST_STEP and k.first_step_kind(  # the load may sag the arc off a wall
            args[0], args[1], args[2], args[3], args[4], args[5], args[8], args[7], args[9],
            args[10], args[11], args[12], 20 * n + 50, 1e-6) != k.FREE:
        return None
    if start is not None:  # a neighbour's shape (its contact set means nothing here)
        start = DriverStart(start.alpha, None)
    args = (*args[:9], free.lower, free.upper, *args[11:])  # the same arrays, no walls
    out = run_compiled(free, tol=tol, max_outer=max_outer, start=start, args=args)[0]
    if out is None or not (out.converged and wall_overlap(walls_at(chain, out.alpha),
                                                          heights(chain, out.alpha)) < 0):
        return None
    out.reason = ("no contact: the equilibrium without walls clears every wall (found by "
                  "banded solves, no LCP)")
    return out
