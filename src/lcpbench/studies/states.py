"""Which of several stable states: the equilibria that two cheap starts reach.

A scene can have more than one stable equilibrium: past θ = 180° in a channel a
cold start (the free arc pressed into the walls) finds folded states of high force
while the loading path (the bend angles grown from zero, as the pressurised
actuator is loaded; ``start="ramp"``) finds the state lying flat on the walls;
rows of sections and stepped wall profiles have their own. :func:`lcpbench.solve`
returns one of them and says which path it took (its ``route`` and ``retries``:
"load path", "ramped", "escaped"); :func:`stable_states` solves both ways and returns every
distinct certified state with its exact energy, lowest first, so that a user sees
when the answer depends on the path.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..api import solve
from ..escalations import same_state
from ..model.chain import energy
from ..model.result import ContactResult


@dataclass
class StableState:
    """One certified equilibrium: the result, its exact energy E(α) (N·mm, springs
    minus the loads' work, :func:`lcpbench.model.chain.energy`) and the start that
    reached it ("cold" or "ramp")."""

    result: ContactResult
    energy: float
    start: str


def stable_states(scene, **solve_kw) -> list[StableState]:
    """The distinct stable states that a cold start and the loading path reach.

    ``solve_kw`` are :func:`lcpbench.solve`'s (not ``start``). Each answer is
    certified by lcpbench's judge, the second-order check included; a start whose
    answer is refused contributes nothing. Answers whose wall forces agree to the
    accuracy asked for are one state (:func:`lcpbench.escalations.same_state`; the
    first start's kept). Sorted by energy, lowest first; empty when neither start is
    certified.
    """
    if "start" in solve_kw:
        from ..errors import ProblemError

        raise ProblemError("stable_states tries the starts itself: leave out start")
    chain = scene.chain()
    states: list[StableState] = []
    for start in ("cold", "ramp"):
        res = solve(scene, start="ramp" if start == "ramp" else None, **solve_kw)
        if not res.converged:
            continue
        if any(same_state(res, s.result) for s in states):
            continue
        states.append(StableState(res, float(energy(chain, np.asarray(res.alpha, float))),
                                  start))
    return sorted(states, key=lambda s: s.energy)
