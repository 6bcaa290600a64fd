"""The galloping dual walk at large N (issue 19, target 5): same answers, optimal.

The walk's choice of which violated wall joins next changes its path, never
its answer (the dual objective rises on every move): so the galloping walk is
checked against the bisecting one (reach 0) and against the KKT conditions of
the step, computed here from the step's own exact gradient; the whole solve
against the bisecting walk (no reach hint, the small tie), within the judge's own
error bounds.
"""

from __future__ import annotations

import numpy as np
import pytest

import lcpbench
from lcpbench.model import large_driver
from lcpbench.model.large_driver import run_large
from lcpbench.model.step_solver import make_step_solver
from lcpbench.problems.scenes import ActuatorScene
from lcpbench.solvers import banded
from lcpbench.solvers.banded import solve_banded_qp
from lcpbench.thresholds import TIE


def gallop_picks(v, slack, held, reach):
    """The walk's picks (linalg.walk_picks.picks_in) on violations ``v`` of an
    upper wall at 0 (u = v), as a mask."""
    from lcpbench.numba_cache import kernel_module

    kern = kernel_module("lcpbench.linalg.walk_picks", "picks_in")
    n = v.size
    picks = np.zeros(2 * n, np.int64)
    u = np.where(held, 0.0, v)
    count = kern.picks_in(u, np.zeros(n), 1, np.full(n, slack), np.asarray(held, bool),
                          reach, picks, 0, 0, n - 1)
    mask = np.zeros(n, bool)
    mask[picks[:count] - 1] = True
    return mask


def test_gallop_picks_are_violated_and_follow_the_rule():
    v = np.full(40, -1.0)
    held = np.zeros(40, bool)
    held[[4, 30]] = True
    v[5:30] = np.linspace(0.1, 1.0, 25) * np.linspace(1.0, 0.1, 25)  # a run between two contacts
    v[34:38] = [0.2, 0.9, 0.5, 0.1]  # a run with no held neighbour
    v[held] = -np.inf
    picks = gallop_picks(v, 0.0, held, 3)
    assert np.all(v[picks] > 0.0)
    assert set(np.flatnonzero(picks)) == {5 + 2, 29 - 2, 35}  # reach 3 in from each held side
    # a run no longer than the reach: its deepest node, as the bisecting walk
    short = gallop_picks(v, 0.0, held, 25)
    assert set(np.flatnonzero(short)) == {5 + int(np.argmax(v[5:30])), 35}
    assert not gallop_picks(np.full(5, -1.0), 0.0, np.zeros(5, bool), 1).any()


def _recorded_steps(links=10000, theta=150.0, height=3.0):
    """(step, warm) of every warm-started step of a large-N solve."""
    chain = ActuatorScene(theta, height, links=links).chain()
    inner = make_step_solver()
    seen = []

    def record(step, warm):
        if warm is not None:
            seen.append((step, warm))
        return inner(step, warm)

    out = run_large(chain, record, tol=1e-3)
    assert out.converged
    return seen


def _kkt(step, u, up, lo):
    """Scaled KKT residuals from the step's exact gradient (independent of the walk)."""
    g = step.gradient(u)
    scale = np.max(step.gradient_scale(u))
    free = ~(up | lo)
    span = 1.0 + np.max(np.abs(u))
    return {"stationarity": np.max(np.abs(g[free]), initial=0.0) / scale,
            "reactions": max(np.max(g[up], initial=0.0), np.max(-g[lo], initial=0.0)) / scale,
            "feasibility": max(np.max(u - step.upper), np.max(step.lower - u), 0.0) / span,
            "on_walls": max(np.max(np.abs(u[up] - step.upper[up]), initial=0.0),
                            np.max(np.abs(u[lo] - step.lower[lo]), initial=0.0)) / span}


@pytest.fixture(scope="module")
def steps():
    return _recorded_steps()


@pytest.mark.parametrize("reach", [1, 3, 40, 1000])
def test_galloping_walk_is_optimal_and_agrees_with_bisection(steps, reach):
    assert len(steps) >= 3
    for step, warm in steps:
        ref = solve_banded_qp(step, start=warm.u, active_upper=warm.active_upper,
                              active_lower=warm.active_lower)
        got = solve_banded_qp(step, start=warm.u, active_upper=warm.active_upper,
                              active_lower=warm.active_lower, reach=reach)
        assert got.status.value == "solved"
        kkt = _kkt(step, got.u, got.active_upper, got.active_lower)
        assert max(kkt.values()) < 1e-9, kkt
        # a strictly convex QP has one minimiser: both walks reach it, to the round-off
        # of the heights (increments about u₀: the walls' gaps set the scale)
        walls = np.concatenate((step.upper[np.isfinite(step.upper)],
                                step.lower[np.isfinite(step.lower)]))
        size = np.max(np.abs(ref.u)) + np.max(np.abs(walls), initial=0.0)
        assert np.max(np.abs(got.u - ref.u)) <= 1e-9 * size
        assert np.array_equal(got.active_upper, ref.active_upper)
        assert np.array_equal(got.active_lower, ref.active_lower)
        net_got = got.forces_upper - got.forces_lower
        net_ref = ref.forces_upper - ref.forces_lower
        assert np.max(np.abs(net_got - net_ref)) <= 1e-6 * np.max(np.abs(net_ref))


def _old_path(monkeypatch):
    """The walk before galloping: no reach hint (it bisects), the small tie."""
    monkeypatch.setattr(large_driver, "_contact_move", lambda sol, last: (None, None))
    monkeypatch.setattr(banded, "TIE_LARGE", TIE)


@pytest.mark.parametrize("theta,height", [(150.0, 3.0), (120.0, 2.0), (170.0, 4.0)])
def test_new_path_gives_the_old_answer_at_n_1e4(monkeypatch, theta, height):
    """Route against route: at N = 10⁴ the energy oracle is out of reach (~N² terms per
    answer); the bisecting walk takes another path to the same equilibrium, within the
    judge's bounds."""
    scene = ActuatorScene(theta, height, links=10000)
    new = lcpbench.solve(scene, tol=1e-3)
    with monkeypatch.context() as m:
        _old_path(m)
        old = lcpbench.solve(scene, tol=1e-3)
    assert new.converged and old.converged
    # both are judged answers of one equilibrium: within the judge's bounds of each other
    bound = new.judgement.force_error_bound + old.judgement.force_error_bound
    assert abs(new.total_force - old.total_force) <= bound * max(abs(old.total_force), 1e-12) + 1e-12


@pytest.mark.parametrize("reach", [None, 0, 5])
def test_compiled_walk_solves_every_step_of_a_1e4_solve(steps, reach):
    """The walk's loop compiled (:mod:`lcpbench.solvers.compiled_walk`, the default at
    large N) on every warm step of a 10⁴ solve and cold, judged by the step's KKT
    conditions from its exact gradient (:func:`_kkt`, independent of the walk)."""
    cases = [(step, warm) for step, warm in steps] + [(steps[0][0], None)]
    for step, warm in cases:
        kw = {} if warm is None else dict(
            active_upper=warm.active_upper, active_lower=warm.active_lower,
            reach=int(getattr(warm, "reach", 0) or 0) if reach is None else reach)
        step.factor._fixed = None  # the walk factors from scratch
        got = solve_banded_qp(step, **kw)
        assert got.status.value == "solved"
        kkt = _kkt(step, got.u, got.active_upper, got.active_lower)
        assert max(kkt.values()) < 1e-9, kkt