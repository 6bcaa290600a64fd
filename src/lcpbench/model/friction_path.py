"""Loading paths (issue 39): a sequence of states, each solved from the last.

A state is a dict of scene fields that change from the previous state (``theta``,
``height``, ``pull``, ``friction``, ``weight``, ``EI``; on a row of sections also
``sections``), applied in turn. On a row of sections ``theta`` sets the sharpest
section's |θ| and scales the others with it (signs kept: the anchoring actuator's
pressure ramp; a row straightened by θ = 0 bends each section back to |θ| on its own
side), and ``weight``, ``EI`` set every section's. The path starts from the
frictionless equilibrium of its first state's scene (the actuator placed in its walls
without friction; :func:`lcpbench.solve` of that scene with μ = 0, both ends pinned
and no pull); each state's slips are measured from the
previous state's node positions (docs/friction.md). A path whose states are all the
paper's model (μ = 0, both ends pinned, no pull) runs today's :func:`lcpbench.solve`
for each state, unchanged.
"""

from __future__ import annotations

import math
from dataclasses import replace

from ..errors import ProblemError
from ..problems.checks import check_number, describe
from ..problems.scenes import ActuatorScene
from ..problems.sections import Section, SectionedScene
from .friction_driver import FrictionState, StepLemke, solve_state
from .friction_mirror import mirror_result, mirror_state, mirror_x, mirrored_scene
from .friction_result import FrictionResult, build_result, from_contact
from .friction_solvers import step_runner

#: the scene fields a state may change (a row of sections: ``sections`` too)
STATE_FIELDS = ("theta", "height", "pull", "friction", "weight", "EI")
#: the scene kinds a path takes
PATH_SCENES = (ActuatorScene, SectionedScene)


def with_pull(scene, pull: float):
    """``scene`` with another axial pull (N), its chain kept: a scene's chain (links,
    walls, loads) does not depend on the pull, so the states of a pull share one chain
    and what is derived from it (the step's arrays, the compliances), not one each. The
    chain is built on ``scene`` where it was not yet (a pull-out's states are each
    ``scene`` with another pull: they share the chain of ``scene``)."""
    new = scene.with_pull(pull)  # (the scene checks the value)
    new.__dict__["_chain"] = scene.chain()  # (a frozen dataclass: not via setattr)
    return new


def apply_state(scene, state: dict):
    """``scene`` with the fields of ``state`` changed (see the module's note)."""
    if set(state) <= {"pull"}:  # (a pull, or nothing: the chain kept)
        return with_pull(scene, state.get("pull", scene.pull))
    if not isinstance(scene, SectionedScene):
        return replace(scene, **state)
    state = dict(state)
    secs = state.pop("sections", scene.sections)
    per = {k: check_number(f"state's {k}", state.pop(k)) for k in ("theta", "weight", "EI")
           if k in state}
    if per:
        secs = SectionedScene(sections=secs).sections  # (checked, as Sections)
        top = max(abs(s.theta) for s in secs)
        if "theta" not in per:
            angle = [s.theta for s in secs]
        elif top > 0.0:  # the sharpest section to |θ|, the others scaled, signs kept
            angle = [s.theta * per["theta"] / top for s in secs]
        else:  # every section straight (a ramp from 0): each bends to |θ| on its own
            # side, the sign its zero kept from the scaling that straightened it
            angle = [math.copysign(per["theta"], s.theta) for s in secs]
        secs = tuple(Section(th, s.length, per.get("EI", s.EI), per.get("weight", s.weight))
                     for th, s in zip(angle, secs, strict=True))
    return replace(scene, sections=secs, **state)


def path_scenes(scene, states) -> list[tuple[dict, ActuatorScene]]:
    """(state, its scene) for each state, each applied to the previous scene."""
    if not isinstance(scene, PATH_SCENES):
        raise ProblemError(f"solve_path takes an ActuatorScene or a SectionedScene (friction, "
                           f"end conditions and a pull are built for them), got "
                           f"{type(scene).__name__}")
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
        allowed = STATE_FIELDS + (("sections",) if isinstance(scene, SectionedScene) else ())
        bad = sorted(set(state) - set(allowed))
        if bad:
            raise ProblemError(f"states[{i}] may change {', '.join(allowed)}; got "
                               f"{', '.join(map(repr, bad))}")
        current = apply_state(current, state)  # (the scene checks the values)
        out.append((dict(state), current))
    if not out:
        raise ProblemError("states must hold at least one state")
    return out


def place(scene, *, tol: float, max_outer: int, solve
          ) -> tuple[FrictionState, object, str, object]:
    """Where a path starts: the frictionless equilibrium of ``scene`` (μ = 0, both ends
    pinned, no pull), its node x, why it failed ("") and its node y (x and y: the first
    slips' reference)."""
    placed = solve(replace(scene, friction=0.0, left_end="pinned", right_end="pinned",
                           pull=0.0), tol=tol, max_outer=max_outer)
    why = "" if placed.converged else (
        f"the frictionless placement did not converge ({placed.reason})")
    return FrictionState(placed.alpha.copy(), 0.0), placed.x.copy(), why, placed.y.copy()


def advance(scene, state: dict, current: FrictionState, x_prev, *,
            tol: float, max_outer: int, lcp=None, y_prev=None):
    """One state of a path solved from ``current`` (slips from the previous node
    positions ``x_prev``, ``y_prev``): its judged result and the outer loop's end state.
    A free left end is solved as its mirror image (:mod:`lcpbench.model.friction_mirror`;
    flat walls only, where the slip is along x)."""
    kw = {} if lcp is None else {"lcp": lcp}
    if scene.left_end == "free":
        mirror, left_pull = mirrored_scene(scene)
        a, xm = scene.length / scene.links, mirror_x(x_prev)
        ans = solve_state(mirror, mirror_state(current, a), xm, tol=tol,
                          max_outer=max_outer, left_pull=left_pull, **kw)
        res = build_result(mirror, state, ans, xm, tol)
        return mirror_result(res, scene, state), mirror_state(ans.state, a)
    ans = solve_state(scene, current, x_prev, tol=tol, max_outer=max_outer, y_prev=y_prev,
                      **kw)
    return build_result(scene, state, ans, x_prev, tol, y_prev), ans.state


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
    current, x_prev, broken, y_prev = place(steps[0][1], tol=tol, max_outer=max_outer,
                                            solve=solve)
    name = getattr(lcp, "backend", "lemke" if lcp is None else "given")
    lcp = StepLemke() if lcp is None else lcp  # one for the path: its covering carries over
    out = []
    for state, s in steps:
        res, end = advance(s, state, current, x_prev, tol=tol,
                           max_outer=0 if broken else max_outer, lcp=lcp, y_prev=y_prev)
        if broken:
            res.converged, res.reason = False, broken
        res.solver = name
        out.append(res)
        if not res.converged and not broken:
            broken = f"an earlier state did not converge ({res.reason})"
        if not broken:
            current, x_prev, y_prev = end, res.x.copy(), res.y.copy()
    return out
