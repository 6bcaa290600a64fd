"""Loading paths (issue 39): a sequence of states, each solved from the last.

A state is a dict of scene fields that change from the previous state (``theta``,
``height``, ``pull``, ``friction``, ``weight``, ``EI``), applied in turn. The path
starts from the frictionless equilibrium of its first state's scene (the actuator
placed in its walls without friction; :func:`lcpbench.solve` of that scene with
μ = 0, both ends pinned and no pull); each state's slips are measured from the
previous state's node positions (docs/friction.md). A path whose states are all the
paper's model (μ = 0, both ends pinned, no pull) runs today's :func:`lcpbench.solve`
for each state, unchanged.
"""

from __future__ import annotations

from dataclasses import replace

from ..errors import ProblemError
from ..problems.checks import describe
from ..problems.scenes import ActuatorScene
from .friction_driver import FrictionState, check_frictional_ends, solve_state
from .friction_result import FrictionResult, build_result, from_contact
from .friction_solvers import step_runner

#: the scene fields a state may change
STATE_FIELDS = ("theta", "height", "pull", "friction", "weight", "EI")


def path_scenes(scene, states) -> list[tuple[dict, ActuatorScene]]:
    """(state, its scene) for each state, each applied to the previous scene."""
    if not isinstance(scene, ActuatorScene):
        raise ProblemError(f"solve_path takes an ActuatorScene (friction, end conditions "
                           f"and a pull are built for it), got {type(scene).__name__}")
    if isinstance(scene.links, str):
        raise ProblemError("solve_path needs an integer links (resolve 'auto' with "
                           "lcpbench.studies.discretisation.auto_links first)")
    if states is None:
        states = [{}]
    if isinstance(states, dict) or not hasattr(states, "__iter__"):
        raise ProblemError(f"states must be a sequence of dicts of scene fields "
                           f"({', '.join(STATE_FIELDS)}), got {describe(states)}")
    out, current = [], scene
    for i, state in enumerate(states):
        if not isinstance(state, dict):
            raise ProblemError(f"states[{i}] must be a dict of scene fields, got "
                               f"{describe(state)}")
        bad = sorted(set(state) - set(STATE_FIELDS))
        if bad:
            raise ProblemError(f"states[{i}] may change {', '.join(STATE_FIELDS)}; got "
                               f"{', '.join(map(repr, bad))}")
        current = replace(current, **state)  # (the scene checks the values)
        out.append((dict(state), current))
    if not out:
        raise ProblemError("states must hold at least one state")
    return out


def place(scene: ActuatorScene, *, tol: float, max_outer: int, solve
          ) -> tuple[FrictionState, object, str]:
    """Where a path starts: the frictionless equilibrium of ``scene`` (μ = 0, both ends
    pinned, no pull), its node x (the first slips' reference) and why it failed ("")."""
    placed = solve(replace(scene, friction=0.0, left_end="pinned", right_end="pinned",
                           pull=0.0), tol=tol, max_outer=max_outer)
    why = "" if placed.converged else (
        f"the frictionless placement did not converge ({placed.reason})")
    return FrictionState(placed.alpha.copy(), 0.0), placed.x.copy(), why


def advance(scene: ActuatorScene, state: dict, current: FrictionState, x_prev, *,
            tol: float, max_outer: int, lcp=None):
    """One state of a path solved from ``current`` (slips from ``x_prev``): its judged
    result and the outer loop's end state."""
    kw = {} if lcp is None else {"lcp": lcp}
    ans = solve_state(scene, current, x_prev, tol=tol, max_outer=max_outer, **kw)
    return build_result(scene, state, ans, x_prev, tol), ans.state


def run_path(scene, states, *, tol: float, max_outer: int, solve, lcp=None,
             solver: str | None = None) -> list[FrictionResult]:
    """:func:`lcpbench.solve_path`'s work; ``solve`` is :func:`lcpbench.solve`; the
    frictional step by ``lcp`` (a function ``(M, q) -> LCPSolution``) or by the back-end
    named ``solver`` (:func:`~.friction_solvers.step_runner`; default Lemke)."""
    if lcp is not None and solver is not None:
        raise ProblemError("give solver= (a back-end's name) or lcp= (a function), not both")
    steps = path_scenes(scene, states)
    if lcp is None and solver is not None:
        lcp = step_runner(solver)
    if not any(s.frictional for _, s in steps):  # the paper's model: today's solve
        out, x_prev = [], None
        for state, s in steps:
            res = solve(s, tol=tol, max_outer=max_outer)
            out.append(from_contact(s, state, res, x_prev))
            x_prev = res.x
        return out
    for _, s in steps:
        check_frictional_ends(s)
    current, x_prev, broken = place(steps[0][1], tol=tol, max_outer=max_outer, solve=solve)
    out = []
    for state, s in steps:
        res, end = advance(s, state, current, x_prev, tol=tol,
                           max_outer=0 if broken else max_outer, lcp=lcp)
        if broken:
            res.converged, res.reason = False, broken
        out.append(res)
        if not res.converged and not broken:
            broken = f"an earlier state did not converge ({res.reason})"
        if not broken:
            current, x_prev = end, res.x.copy()
    return out
