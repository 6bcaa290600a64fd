"""The solve kernel's Python side: which chains it takes, its arguments, one call, its answer.

:func:`applies` says whether :func:`lcpbench.model.compiled_kernel.solve_chain` runs a
solve (the default back-end, the globalised or Newton scheme, a chain of consecutive
joints and free nodes with flat walls); :func:`kernel_args` lays the chain's arrays
out in the kernel's order; :func:`call_kernel` makes one call;
:func:`kernel_output` turns its outputs into the driver's answer (a
:class:`~lcpbench.model.outer.DriverOutput`, built by the outer loop's own helpers);
:func:`run_compiled` does all three, or names the reason (:data:`BAIL_REASONS`) where
the kernel left the reference's path. Which engine runs a solve is decided above this,
in :func:`lcpbench.model.compiled.drive`; the compiled driver and the wall-free search
call the kernel from here too, so none of them imports the other.

numba is imported, and the kernel loaded (:func:`solve_kernel`), at the first call.
"""

from __future__ import annotations

import functools
import math
import time

import numpy as np

from ..numba_cache import kept
from ..problems.scenes import Chain
from ..solvers.base import Status, StepSolution
from ..solvers.judge import requested
from ..solvers.registry import DEFAULT, get_settings
from ..thresholds import STALL_RUN, STALL_STEP
from . import large_n
from .outer import (
    DriverOutput,
    DriverStart,
    StepRecord,
    converged_output,
    failed_output,
    out_of_iterations,
)
from .profile import wall_rows, wall_tables
from .step import residuals_of

#: the solve kernel's bail codes (it left the reference's path) and their reasons
BAIL_REASONS = {
    10: "crossed walls (the primal active set)",
    11: "a face that is not positive definite",
    12: "a working set repeated (round-off)",
    13: "the face-solve limit",
    14: "the step certificate rejected the step",
    15: "lcpbench's judge rejected the step",
    16: ("the outer steps stalled from the cold start (line searches cut t to "
         f"1/{round(1 / STALL_STEP)} or less "
         f"{'twice' if STALL_RUN == 2 else f'{STALL_RUN} outer steps'} running)"),
}


def applies(backend: str, method: str, chain: Chain | None = None) -> bool:
    """Whether the kernel runs this solve: the default back-end, the globalised
    driver or its Newton scheme, and (given ``chain``) a chain of consecutive joints and free nodes,
    with flat walls, rigid or elastic (not a wall profile)."""
    if backend not in (DEFAULT, "auto") or method not in ("globalised", "newton"):
        return False
    if chain is None:
        return True
    return chain.derived("_kernel_layout", lambda: _layout(chain))


def _layout(chain: Chain) -> bool:
    if chain.profiled_walls:
        return False  # walls of any profile: the profile kernel (profile_applies)
    return consecutive(chain)


def consecutive(chain: Chain) -> bool:
    """Whether the chain's joints join consecutive links in order and its free nodes are
    contiguous from node 1 (the layout of every compiled assembly)."""
    if chain.consecutive is not None:  # the scene says (the test below, done at building)
        return chain.consecutive
    left, right = chain.joint_links[:, 0], chain.joint_links[:, 1]
    f = chain.free_nodes
    return bool(right.size and f.size and np.all(np.diff(right) == 1)
                and np.all((left < 0) | (right == left + 1)) and np.all(np.diff(f) == 1)
                and f[0] >= 1)


def profile_applies(backend: str, method: str, chain: Chain) -> bool:
    """Whether the profile kernel (:func:`lcpbench.model.compiled_kernel.solve_profile_chain`)
    runs this solve: the default back-end, the globalised scheme, a chain of consecutive
    joints and free nodes with a wall of any profile whose table of cubic pieces exists
    (:meth:`lcpbench.problems.walls.WallProfile.pieces`), below large N
    (:func:`lcpbench.model.large_n.applies`: there the increments take profiles)."""
    if backend not in (DEFAULT, "auto") or method != "globalised" or not chain.profiled_walls:
        return False
    if large_n.applies(chain):
        return False
    return profile_layout(chain)


def profile_layout(chain: Chain) -> bool:
    """Whether the compiled routes take this chain with its wall of any profile: joints
    and free nodes consecutive (the solve kernel's layout), and every profiled wall a
    table of cubic pieces over the chain's reach (:func:`profile_args`)."""
    return chain.derived("_profile_layout",
                         lambda: consecutive(chain) and profile_args(chain) is not None)


def profile_args(chain: Chain) -> tuple | None:
    """The profile kernel's arguments after the solve kernel's first nine: the rows, ℓ,
    EI/ℓ², the two walls' tables (empty: flat) and whether there is a channel; None
    where a wall has no table."""
    return chain.derived("_profile_args", lambda: _profile_args(chain))


def _profile_args(chain: Chain) -> tuple | None:
    tables = wall_tables(chain)
    if tables is None:
        return None
    base = kernel_args(chain)
    return (*base[9:13], *tables, bool(chain.channel))


def run_profile_compiled(chain: Chain, *, tol: float, max_outer: int = 200,
                         start: DriverStart | None = None,
                         settings="default") -> tuple[DriverOutput | None, str]:
    """The globalised profile driver in the profile kernel: ``(output, "")``, or
    ``(None, why)`` where the kernel stopped (the caller then runs its compiled
    fall-back, :func:`lcpbench.model.compiled.reference`)."""
    got, elapsed, name = call_profile_kernel(chain, tol=tol, max_outer=max_outer, start=start,
                                             settings=settings)
    code, *rest, upper, lower = got
    if code in BAIL_REASONS:
        return None, BAIL_REASONS[code]
    from dataclasses import replace

    at = replace(chain, upper=upper, lower=lower) if chain.channel else chain
    return kernel_output(at, code, *rest, elapsed=elapsed, settings=name,
                         max_outer=max_outer, tol=tol), ""


def call_profile_kernel(chain: Chain, *, tol: float, max_outer: int,
                        start: DriverStart | None, settings) -> tuple[tuple, float, str]:
    """One call of :func:`lcpbench.model.compiled_kernel.solve_profile_chain` on the chain:
    (its outputs, its wall time in s, the name of the back-end's settings). A warm
    ``start`` gives the starting shape and, from its last step's net reactions, the
    lagged reactions."""
    k = kept(_PROFILE, "lcpbench.model.compiled_kernel", "solve_profile_chain")
    n = chain.free_nodes.size
    max_iter, request, name = kernel_settings(settings, n)
    start_alpha, mu_up, mu_lo = _NO_START, np.zeros(n), np.zeros(n)
    if start is not None:
        start_alpha = np.ascontiguousarray(start.alpha, dtype=float)
        net = None if start.warm is None else start.warm.forces_net
        if net is not None and np.size(net) == n and np.all(np.isfinite(net)):
            # (one wall: every reaction is its own, wherever the walls are at the start;
            # a channel: each node's, the nearer wall's at the start's x)
            net = np.ascontiguousarray(net, dtype=float)
            if chain.channel:
                u = np.ascontiguousarray(start.warm.u, dtype=float)
                k.split_by_wall(net, u, *wall_rows(chain, start_alpha)[2:4], True, mu_up, mu_lo)
            else:
                k.split_by_wall(net, net, net, net, False, mu_up, mu_lo)
    base = kernel_args(chain)
    t0 = time.perf_counter()
    got = k.solve_profile_chain(*base[:9], *profile_args(chain), float(tol), int(max_outer),
                                start_alpha, mu_up, mu_lo, int(max_iter), request)
    return got, time.perf_counter() - t0, name


_PROFILE: list = []  # the profile kernel's module, once loaded
_NO_START = np.zeros(0)  # (never written)


def solve_kernel():
    """The kernel module (numba imported, the kernel loaded, at the first call)."""
    return kept(_KERNEL, "lcpbench.model.compiled_kernel", "solve_chain")


_KERNEL: list = []  # the kernel module, once loaded (emptied by numba_cache.use_aot)


@functools.lru_cache(maxsize=16)
def cold_start(n: int) -> tuple:
    """The kernel's start arguments of a cold start with ``n`` free nodes: no start α,
    no warm step (zeros), made once per n. Writable (numba types read-only arrays
    apart: another compilation) and never written: the kernel copies them into its
    workspace (tests/model/test_lean_path.py checks that they stay zero)."""
    return np.zeros(0), np.zeros(n), np.zeros(n, bool), np.zeros(n, bool), 0


def warm_args(start: DriverStart | None, n: int):
    """(start α, warm heights, upper mask, lower mask, flags) for the kernel."""
    if start is None:
        return cold_start(n)
    empty_f, empty_b = np.zeros(n), np.zeros(n, bool)
    alpha = np.ascontiguousarray(start.alpha, dtype=float)
    w = start.warm
    if w is None:
        return alpha, empty_f, empty_b, empty_b, 0
    flags, u, up, lo = 0, empty_f, empty_b, empty_b
    if w.u is not None and np.size(w.u) == n:
        u, flags = np.ascontiguousarray(w.u, dtype=float), flags | 1
    if w.active_upper is not None and np.size(w.active_upper) == n:
        up, flags = np.ascontiguousarray(w.active_upper, dtype=bool), flags | 2
    if w.active_lower is not None and np.size(w.active_lower) == n:
        lo, flags = np.ascontiguousarray(w.active_lower, dtype=bool), flags | 4
    return alpha, u, up, lo, flags


def kernel_args(chain: Chain, const: tuple | None = None) -> tuple:
    """The chain's arrays in the order :func:`compiled_kernel.solve_chain` takes them.

    ``const``: ``(left links, right links, nodal load)`` as contiguous arrays, when
    the caller has them for a run of chains that share them (a batch). Kept with
    the chain (:meth:`~lcpbench.problems.scenes.Chain.derived`)."""
    return chain.derived("_kernel_args", lambda: _kernel_args(chain, const))


def _kernel_args(chain: Chain, const: tuple | None) -> tuple:
    f64 = np.ascontiguousarray
    if const is None:
        joints = np.array(chain.joint_links.T, dtype=np.int64, order="C")  # rows: left, right
        const = (joints[0], joints[1],
                 f64(chain.derived("_nodal_load", lambda: chain.nodal_load), dtype=float))
    jl, jr, nodal_load = const
    if chain.elastic_walls:  # the walls' compliances 1/k (0: rigid), the kernel's form
        from .elastic import compliances

        cu, cl = (f64(c, dtype=float) for c in compliances(chain))
    else:
        cu = cl = _NO_SPRINGS
    return (f64(chain.rest_alpha, dtype=float), float(chain.link_length), jl, jr,
            f64(chain.joint_stiffness, dtype=float), f64(chain.rest_joint, dtype=float),
            f64(chain.link_load, dtype=float), nodal_load, int(chain.free_nodes[0]) + 1,
            f64(chain.lower, dtype=float), f64(chain.upper, dtype=float), float(chain.length),
            float(chain.force_scale), cu, cl)


#: the kernels' compliances where no wall yields (empty; never written)
_NO_SPRINGS = np.zeros(0)


def run_compiled(chain: Chain, *, tol: float, max_outer: int = 200,
                 start: DriverStart | None = None, settings="default",
                 args: tuple | None = None,
                 newton: bool = False) -> tuple[DriverOutput | None, str]:
    """The globalised driver (``newton``: its Newton scheme) with the dual active
    set, in the compiled kernel.

    Returns ``(output, "")``, or ``(None, why)`` when the kernel stopped (the caller
    then runs its compiled fall-back, :func:`lcpbench.model.compiled.reference`). Each step
    record's ``solve_time`` is the kernel's wall time shared evenly over the
    steps (assembly included; ``assemble_time`` is 0): the kernel does not
    time its parts. ``args``: the chain's :func:`kernel_args`, when the caller
    has them already.
    """
    got, elapsed, name = call_kernel(chain, tol=tol, max_outer=max_outer, start=start,
                                     settings=settings, args=args, newton=newton)
    code = got[0]
    if code in BAIL_REASONS:
        return None, BAIL_REASONS[code]
    return kernel_output(chain, *got, elapsed=elapsed, settings=name, max_outer=max_outer,
                         tol=tol), ""


def call_kernel(chain: Chain, *, tol: float, max_outer: int, start: DriverStart | None,
                settings, args: tuple | None, newton: bool) -> tuple[tuple, float, str]:
    """One call of :func:`compiled_kernel.solve_chain` on the chain: (its outputs, its
    wall time in s, the name of the back-end's settings)."""
    k = solve_kernel()
    n = chain.free_nodes.size
    max_iter, request, name = kernel_settings(settings, n)
    s_alpha, w_u, w_up, w_lo, flags = warm_args(start, n)
    if args is None:
        args = kernel_args(chain)
    t0 = time.perf_counter()
    got = k.solve_chain(*args, float(tol), int(max_outer), s_alpha, w_u, w_up, w_lo, flags,
                        int(max_iter), float(request), bool(newton))
    return got, time.perf_counter() - t0, name


def kernel_settings(settings, n: int) -> tuple[int, float, str]:
    """(max_iter, request, name): the solve kernel's arguments from the back-end's
    ``settings`` for ``n`` free nodes (the active set's iteration limit, 20 n + 50 where
    the settings give none; the step's accuracy request), and the settings' name."""
    s = get_settings(settings)
    return (s.max_iter if s.max_iter else 20 * n + 50), float(requested(s)), s.name


def kernel_output(chain: Chain, code: int, alpha, r_up, r_lo, u, sigma, rec, count: int, res,
                  R, *, elapsed: float, settings: str, max_outer: int,
                  tol: float, reason: str = "converged") -> DriverOutput:
    """The DriverOutput of the solve kernel's outputs (the tuple
    :func:`compiled_kernel.solve_chain` returns, ``code`` not a bail code), built by the
    driver's own helpers: the one place for a single solve (:func:`run_compiled`,
    :func:`lcpbench.api.solve`'s one-wall route) and a batch line
    (:func:`lcpbench.studies.batch_result.driver_output`).

    ``rec``: the step records, ``count`` of them from column 0; ``elapsed``: the
    kernel's wall time, shared evenly over the steps; ``settings``: the settings'
    name; ``reason``: of a converged answer (the wall-free search's says so); ``tol``:
    the requested one, for the reason of a run out of iterations."""
    k = solve_kernel()
    n = chain.free_nodes.size
    share = elapsed / max(count, 1)
    solved = _SOLVED
    cols = rec[:4, :count].T.tolist()  # one conversion for all the records
    steps = [StepRecord(int(it), solved, share, 0.0, step, dalpha, energy)
             for it, step, dalpha, energy in cols]
    if code == k.CONVERGED:
        sol = StepSolution(u, r_up, r_lo, _SOLVED_STATUS, iterations=steps[-1].iterations,
                           solve_time=share, active_upper=sigma > 0, active_lower=sigma < 0,
                           time_source="wall", backend=DEFAULT, settings=settings,
                           residuals=residuals_of(res),
                           forces_net=R)
        # converged_output, its one-wall case (np.add.reduce: ndarray.sum without its wrapper)
        if not chain.channel and math.isfinite(_add_reduce(R)):
            return DriverOutput(alpha, R.copy(), np.zeros(n), True, reason, steps,
                                last_step=sol, multipliers_upper=r_up,
                                multipliers_lower=r_lo)
        out = converged_output(chain, alpha, sol, steps)
        if reason != "converged":
            out.reason = reason
        return out
    if code == k.NO_FIT:
        return failed_output(chain.rest_alpha.copy(), n, steps, "cannot fit the chain between the walls")
    if code == k.LINE_SEARCH:
        return failed_output(alpha, n, steps, "line search failed: no decrease of the energy along "
                                      "the step")
    return out_of_iterations(alpha, n, steps, max_outer, tol)


_SOLVED = Status.SOLVED.value
_SOLVED_STATUS = Status.SOLVED
_add_reduce = np.add.reduce
