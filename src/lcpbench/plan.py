"""The one routing table of :func:`lcpbench.solve`: (scene features, back-end, method,
N, tol, start) → a typed :class:`Plan` (route, start, escalations, engine).

:func:`make_plan` decides up front what :func:`lcpbench.solve` runs; ``solve`` calls it
once and executes the plan. The routes, in the order the rules are tried:

============== ==========================================================================
route          when (and what runs)
============== ==========================================================================
load path      ``start="ramp"``: :func:`lcpbench.model.ramp.follow_load`, the bend angles
               from zero; where the path stops or its answer is refused, the plan's
               ``fallback`` (the cold plan; its result's ``retries`` begin with "cold").
one-wall       the default back-end, the globalised or Newton scheme, a cold start, a
kernel         chain the solve kernel takes (:func:`lcpbench.model.kernel_call.applies`:
               consecutive joints, flat walls), one wall, neither large
               (N < ``LARGE_N``) nor heavy, its arc far past the wall
               (:func:`lcpbench.model.compiled.direct`): the solve kernel and the judge
               kernel, the rest of the result built when read.
channel kernel the same in a channel (two walls): the solve kernel, judged in full.
heavy SQP      the default back-end, not undamped, a chain in reach of the SQP in the link
               angles (rigid flat walls) with wℓ³/EI ≥ ``angle_step.HEAVY``: SQP steps
               first, height steps where they fail.
heights, then  the same with ``heavy_driver.MODERATE`` ≤ wℓ³/EI < ``HEAVY``: height
SQP            steps (the kernel where it takes the chain), finished by SQP steps where
               they do not converge within ``heavy_driver.FIRST_TRY``.
profile kernel the default back-end, the globalised scheme, a wall of
               any profile with a table of cubic pieces, a chain the kernel's layout takes
               (:func:`lcpbench.model.kernel_call.profile_applies`, below ``LARGE_N``):
               the profile kernel;
               a cold start on one wall its arc crosses far: its result built when read.
large N        the globalised scheme and N ≥ ``large_n.LARGE_N`` (or a chain in
               increments) on a layout it takes: increments on the tridiagonal factor,
               every wall model (rigid or elastic, flat or profiled) a parameter of the
               step (:class:`lcpbench.model.large_driver.WallTerms`).
kernel         the default back-end, globalised or Newton, a chain
               the kernel takes (a warm start, or an arc near the wall): the solve kernel.
compiled       another back-end and the globalised or Newton scheme, any back-end and
driver         the undamped scheme, or the default back-end's Newton scheme on a wall
               profile, on a chain the kernel's layout takes (flat walls, rigid or
               elastic, or walls of any profile with a table): its calls in Python, the
               driver around them compiled
               (:func:`lcpbench.model.compiled_driver.run`). A chain no driver takes is
               a ProblemError of :func:`lcpbench.model.compiled.drive`.
============== ==========================================================================

Every route but the first two and the load path begins with the wall-free search
(:func:`lcpbench.model.wall_free.solve_without_contact`), which answers a scene that
touches no wall without any LCP, and then runs :func:`lcpbench.model.compiled.drive`,
which makes the same choices at run time (the rules here follow it). Decided at run
time only, and seen in the result's ``engine``: a kernel that stops (a bail: the compiled
driver around the default back-end's step solver, increments where round-off of node
heights is the likely cause, or a not-converged answer for a refused step that the
escalations take over: :func:`lcpbench.model.compiled.reference`), and a
heavy chain's SQP answer that another back-end cannot use (it touches a wall).

The escalations that may follow a refusal are the rows of
:data:`lcpbench.escalations.ESCALATIONS` whose ``planned`` predicate holds, in the
table's order.
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import ProblemError
from .escalations import ESCALATIONS
from .model import angle_step, heavy_driver, large_n
from .model.compiled import direct
from .model.judge import judged_in
from .model.kernel_call import applies, profile_applies, profile_args
from .problems import profile_table
from .problems.scenes import Chain
from .solvers.registry import DEFAULT

#: The routes of a plan, by name (see the module).
ROUTES = ("load path", "one-wall kernel", "channel kernel", "heavy SQP", "heights, then SQP",
          "profile kernel", "large N", "kernel", "compiled driver")
#: The starts: from the free arc (cold), from a neighbour's answer (warm), along the
#: loading path (ramp).
STARTS = ("cold", "warm", "ramp")
#: The engine each route plans for (one of :data:`lcpbench.model.compiled.ENGINES_RUN`;
#: the result's ``engine`` says what ran).
ENGINE = {"load path": "", "one-wall kernel": "compiled", "channel kernel": "compiled",
          "heavy SQP": "compiled SQP", "heights, then SQP": "", "profile kernel": "compiled",
          "large N": "increments driver",
          "kernel": "compiled", "compiled driver": "compiled driver"}


@dataclass(frozen=True)
class Plan:
    """What :func:`lcpbench.solve` runs for one scene.

    Attributes
    ----------
    route : one of :data:`ROUTES`.
    start : one of :data:`STARTS`.
    escalations : names in :data:`lcpbench.escalations.ESCALATIONS`, in its order: what
        may run on a refused answer.
    engine : the engine the route plans for (:data:`lcpbench.model.compiled.ENGINES_RUN`;
        the load path's and "heights, then SQP"'s are their height steps' engine).
    kernel_takes : whether the compiled kernels take the chain (a layout the solve
        kernel takes, whichever back-end): the route's calls share its arrays.
    judge : where the result judge takes its exact steps
        (:func:`lcpbench.model.judge.judged_in`): "heights" (the judge kernel, whatever
        back-end and engine) or "increments" (from ``LARGE_N`` links); both compiled.
    fallback : the load path's cold plan (None for every other route).
    """

    route: str
    start: str
    escalations: tuple[str, ...]
    engine: str
    kernel_takes: bool = False
    judge: str = "increments"
    fallback: Plan | None = None


def make_plan(chain: Chain, backend: str, method: str, engine: str, tol: float,
              start: str = "cold", *, scaled: bool = True, neighbour: bool = False) -> Plan:
    """The plan of a solve of ``chain`` (its scene's features: walls, N, load) with the
    back-end ``backend`` (a registry name), ``method`` ("globalised", "newton" or
    "undamped"), ``engine`` ("auto" or "compiled"), the driver tolerance
    ``tol`` (rad), ``start`` (one of :data:`STARTS`) and the step ``scaled`` or not.
    The arguments are :func:`lcpbench.solve`'s, checked; ``neighbour``: the solve has a
    neighbouring row's answer to escalate from (:func:`lcpbench.solve_many`'s rows of
    sections), which plans the escalations that need one."""
    if chain.profiled_walls and profile_args(chain) is None:
        refuse_untabled(chain)
    takes = _kernel(chain, DEFAULT, "globalised", engine)
    judge = judged_in(chain)
    if start == "ramp":
        cold = make_plan(chain, backend, method, engine, tol, "cold", scaled=scaled)
        return Plan("load path", "ramp", (), cold.engine, takes, judge, fallback=cold)
    route = _route(chain, backend, method, engine, start, scaled)
    escalations = tuple(name for name, e in ESCALATIONS.items()
                        if (neighbour or not e.needs_neighbour)
                        and e.planned(chain, backend, method, tol))
    used = ENGINE[route] or ("compiled" if _kernel(chain, backend, method, engine)
                             else "compiled driver")
    return Plan(route, start, escalations, used, takes, judge)


def refuse_untabled(chain: Chain) -> None:
    """The one ProblemError for a wall profile with no table of cubic pieces over the
    chain's reach (x in [−ℓ, ℓ]), naming the parameter of the wall that has none (read
    by every plan, and by :func:`lcpbench.solve_many`'s checks of the batch)."""
    reach = (-float(chain.length), float(chain.length))
    for name, profile in (("wall_profile", chain.upper_profile),
                          ("lower_profile", chain.lower_profile)):
        if profile is not None and profile.pieces(*reach) is None:
            raise ProblemError(f"{name}: the result judge reads a wall as a table of cubic "
                               f"pieces, and this profile needs more than "
                               f"{profile_table.MAX_PIECES} of them over the chain's reach "
                               "(a function that oscillates too fast); give it "
                               "as a table (WallProfile.from_table)")


def _kernel(chain: Chain, backend: str, method: str, engine: str) -> bool:
    return applies(backend, method, chain)


def _route(chain: Chain, backend: str, method: str, engine: str, start: str,
           scaled: bool) -> str:
    own = backend == DEFAULT
    if own and start == "cold" and method != "undamped" and direct(chain):
        return "channel kernel" if chain.channel else "one-wall kernel"
    if own and method != "undamped" and angle_step.in_reach(chain):
        q = angle_step.load_parameter(chain)
        if q >= angle_step.HEAVY:
            return "heavy SQP"
        if q >= heavy_driver.MODERATE:
            return "heights, then SQP"
    if profile_applies(backend, method, chain):
        return "profile kernel"
    if method == "globalised" and large_n.applies(chain):
        return "large N"
    if _kernel(chain, backend, method, engine):
        return "kernel"
    return "compiled driver"  # (or, where it does not take the chain, drive's ProblemError)


__all__ = ["ENGINE", "ROUTES", "STARTS", "Plan", "make_plan"]
