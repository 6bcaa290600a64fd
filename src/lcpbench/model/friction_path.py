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


def run_path(scene, states, *, tol: float, max_outer: int, solve, lcp=None
             ) -> list[FrictionResult]:
    """:func:`lcpbench.solve_path`'s work; ``solve`` is :func:`lcpbench.solve`."""
    steps = path_scenes(scene, states)
    if not any(s.frictional for _, s in steps):  # the paper's model: today's solve
        out, x_prev = [], None
        for state, s in steps:
            res = solve(s, tol=tol, max_outer=max_outer)
            out.append(from_contact(s, state, res, x_prev))
            x_prev = res.x
        return out
    for _, s in steps:
        check_frictional_ends(s)
    first = steps[0][1]
    placed = solve(replace(first, friction=0.0, left_end="pinned", right_end="pinned",
                           pull=0.0), tol=tol, max_outer=max_outer)
    current = FrictionState(placed.alpha.copy(), 0.0)
    x_prev = placed.x.copy()
    out, broken = [], None if placed.converged else (
        f"the frictionless placement did not converge ({placed.reason})")
    kw = {} if lcp is None else {"lcp": lcp}
    for state, s in steps:
        if broken:
            ans = solve_state(s, current, x_prev, tol=tol, max_outer=0, **kw)
            ans.reason, ans.converged = broken, False
            out.append(build_result(s, state, ans, x_prev, tol))
            continue
        ans = solve_state(s, current, x_prev, tol=tol, max_outer=max_outer, **kw)
        res = build_result(s, state, ans, x_prev, tol)
        out.append(res)
        if not res.converged:
            broken = f"an earlier state did not converge ({res.reason})"
            continue
        current, x_prev = ans.state, res.x.copy()
    return out
