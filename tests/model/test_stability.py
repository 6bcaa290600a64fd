"""The second-order check (model.stability_kernel) and the escape from saddles
(model.escape, escalations.escaped), against independent oracles:

- linear algebra: the count of negative eigenvalues of the reduced Hessian, from a
  dense null-space basis and eigvalsh, on random tridiagonal Hessians and segments;
- finite differences of the exact energy (model.chain.energy) and of the node
  heights (model.chain.node_positions) on small chains: the Lagrangian's Hessian
  with λ from stationarity of its own finite-difference gradient, reduced on the
  null space of the finite-difference gradients of the held nodes' heights;
- the issue's reproducers (channel, θ > 180°), whose stable neighbours a reviewer
  found by other means (forces quoted in the issue, to their 4-5 digits).
"""

import numpy as np
import pytest
import scipy.linalg as sl
from energy_oracle import fd_unstable_directions

import lcpbench
from lcpbench.model.chain import energy
from lcpbench.model.compiled import drive
from lcpbench.model.judge import judge, unstable_directions
from lcpbench.model.result import certify
from lcpbench.model.step_solver import make_step_solver
from lcpbench.numba_cache import kernel_module
from lcpbench.problems.walls import WallProfile
from lcpbench.solvers.registry import DEFAULT


def _kernel():
    return kernel_module("lcpbench.model.stability_kernel", "unstable_directions")


# ---- the inertia count, against dense linear algebra -------------------------------

def _dense_count(d, o, c, s, event, stiffness, slope, curvature, pinned):
    """Negative eigenvalues of the Hessian in α on the null space of the held nodes' rows,
    written in α alone: the walls' curvatures and the springs as rank-one terms."""
    n = d.size
    H = np.diag(d) + np.diag(o, 1) + np.diag(o, -1)
    rows = []
    for q in range(1, n + 1):
        dy = np.where(np.arange(n) < q, c, 0.0)
        dx = np.where(np.arange(n) < q, -s, 0.0)
        if event[q] == 0:
            continue
        if not (q == n and pinned):
            H += curvature[q] * np.outer(dx, dx)
        if event[q] == 2:
            H += stiffness[q] * np.outer(dy, dy)
        else:
            rows.append(dy - slope[q] * dx)
    Z = sl.null_space(np.array(rows)) if rows else np.eye(n)
    if Z.shape[1] == 0:
        return 0
    return int(np.sum(np.linalg.eigvalsh(Z.T @ H @ Z) < 0.0))


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("walls", ["flat", "flat, with the x rows", "curved"])
def test_inertia_count_matches_dense_eigenvalues(seed, walls):
    rng = np.random.default_rng(seed)
    k = _kernel()
    for _ in range(100):
        n = int(rng.integers(2, 12))
        d = rng.normal(size=n) * 2.0 + 0.5
        o = rng.normal(size=n - 1)
        angle = rng.uniform(-np.pi, np.pi, n)
        c, s = np.cos(angle), np.sin(angle)
        pinned = bool(rng.random() < 0.7)
        event = np.zeros(n + 1, np.int64)
        event[1:] = rng.choice([0, 0, 1, 2], size=n)
        if pinned:
            event[n] = 1
        stiffness = np.where(event == 2, rng.uniform(0.2, 5.0, n + 1), np.inf)
        slope = np.zeros(n + 1)
        curvature = np.zeros(n + 1)
        if walls == "curved":
            slope = np.where(event == 1, rng.normal(size=n + 1), 0.0)
            curvature = np.where(event > 0, rng.normal(size=n + 1), 0.0)
            if pinned:
                slope[n] = curvature[n] = 0.0
        neg, _ = k.reduced_inertia(d, o, c, s, event, stiffness, slope, curvature,
                                   walls != "flat", pinned)
        assert neg == _dense_count(d, o, c, s, event, stiffness, slope, curvature, pinned)


def test_positive_definite_hessian_has_no_unstable_direction_whatever_the_segments():
    """Property: H ≻ 0 in the full space is positive on every subspace."""
    rng = np.random.default_rng(7)
    k = _kernel()
    n = 30
    for _ in range(20):
        o = rng.normal(size=n - 1)
        d = np.abs(np.r_[o, 0.0]) + np.abs(np.r_[0.0, o]) + 0.1  # diagonally dominant
        event = np.zeros(n + 1, np.int64)
        event[1:] = rng.choice([0, 1, 2], size=n)
        stiffness = np.where(event == 2, 1.0, np.inf)
        angle = rng.uniform(-np.pi, np.pi, n)
        zero = np.zeros(n + 1)
        assert k.reduced_inertia(d, o, np.cos(angle), np.sin(angle), event, stiffness, zero,
                                 zero, False, True)[0] == 0


# ---- the whole check, against finite differences of the exact energy ----------------

def _driver_answer(scene, tol=1e-3):
    """The driver's own answer (no retry, no escape) and the judge's verdict on it."""
    chain = scene.chain()
    out, _ = drive(chain, make_step_solver(DEFAULT, "default", True), backend=DEFAULT,
                   settings="default", tol=tol, max_outer=200, method="globalised",
                   start=None)
    verdict = judge(chain, out.alpha, out.forces_upper, out.forces_lower, tol=tol,
                    driver_converged=out.converged, driver_reason=out.reason,
                    step_statuses=[s.status for s in out.steps],
                    step_sizes=[s.max_dalpha for s in out.steps],
                    certificate=lambda up, lo: certify(chain, out.alpha, up, lo))
    return chain, out, verdict


SADDLE_40 = dict(theta=300, height=0.8, channel=True, links=40)  # the 67.50 N


@pytest.mark.parametrize("kw, saddle", [
    (SADDLE_40, True),
    (dict(theta=270, height=0.5, channel=True, links=40), False),
    (dict(theta=150, height=3.0, links=40), False),
    (dict(theta=120, height=2.0, channel=True, links=24, weight=0.05), False),
    # curved walls: the δx rows, the walls' slopes and curvatures in the check
    (dict(theta=150, links=30, wall_profile=WallProfile.from_table(
        [-5, 10, 15, 20, 35], [3.5, 3.5, 2.5, 3.5, 3.5], kind="pchip")), False),
    (dict(theta=150, links=30, channel=True, wall_profile=WallProfile.from_table(
        [-5, 35], [2.0, 3.5], kind="linear")), False),
])
def test_check_agrees_with_finite_differences_of_the_energy(kw, saddle):
    chain, out, verdict = _driver_answer(lcpbench.ActuatorScene(**kw))
    assert out.converged
    threshold = verdict.contact_threshold
    fd = fd_unstable_directions(chain, out.alpha, out.forces_upper, out.forces_lower, threshold)
    assert (fd > 0) == saddle
    assert unstable_directions(chain, out.alpha, out.forces_upper, out.forces_lower,
                               threshold) == fd
    assert verdict.unstable_directions == fd
    assert ("stability" in verdict.failed) == saddle


def test_the_judge_refuses_the_saddle_on_stability_alone():
    _, out, verdict = _driver_answer(lcpbench.ActuatorScene(**SADDLE_40))
    assert out.converged  # the driver's criterion holds: first order alone is met
    assert verdict.failed == ["stability"] and not verdict.converged
    assert "unstable equilibrium" in verdict.reason


# ---- the reproducers: refused as saddles, escaped to the stable neighbour ----

@pytest.mark.parametrize("kw, saddle_force, stable_force", [
    (dict(theta=270, height=0.5, channel=True), 179.03, 180.96),
    (dict(theta=230, height=0.2, channel=True), 993.8, 1043.3),
    (dict(theta=330, height=0.3, channel=True), 475.7, 489.7),
])
def test_reproducers_escape_the_saddle_to_a_lower_energy(kw, saddle_force, stable_force):
    scene = lcpbench.ActuatorScene(**kw)
    chain, out, verdict = _driver_answer(scene)
    assert verdict.failed == ["stability"]
    assert float(np.sum(out.forces_upper)) == pytest.approx(saddle_force, rel=1e-3)
    res = lcpbench.solve(scene)
    assert res.converged and "saddle" in res.retried("escaped")
    assert res.judgement.unstable_directions == 0
    assert energy(chain, res.alpha) < energy(chain, out.alpha)
    # the stable neighbour at a tighter tolerance; at tol 1e-3 within 0.1 %
    assert res.total_force == pytest.approx(stable_force, rel=1e-3)


def test_solve_many_escapes_too():
    scenes = [lcpbench.ActuatorScene(theta=270, height=0.5, channel=True),
              lcpbench.ActuatorScene(theta=150, height=3.0)]
    many = lcpbench.solve_many(scenes)
    assert all(r.converged and r.judgement.unstable_directions == 0 for r in many)
    assert many[0].total_force == pytest.approx(180.96, rel=1e-3)


def test_a_restart_that_is_not_certified_keeps_the_refusal_and_says_why():
    res = lcpbench.solve(lcpbench.ActuatorScene(**SADDLE_40))
    if res.converged:  # escaped: then to a stable state of lower energy
        assert res.judgement.unstable_directions == 0
    else:
        assert "stability" in res.judgement.failed
        assert "restarts downhill" in res.retried("escaped")
