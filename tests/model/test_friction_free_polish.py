"""A free right end's step in its primal form (issue 39, target 2; model/friction_primal.py,
model/friction_polish.py): the rotation about the pin (K = H + k_r r rᵀ, every height
coupled) borders the banded system with two unknowns, solved by block elimination on the
band's factor.

Expectations are independent of the polish: the exact solution of the step's primal
equations in rational arithmetic (benchmarks/exact_friction.py, from the step's doubles),
the step's move from its Delassus form (a dense solve of K), and theory: a chain pinned
at the left and free at the right turns, in a step, by the moment of its loads about the
pin over the rotation's stiffness (H r = 0: bending does not see a rigid rotation).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.model.friction_driver import (
    ROT_STIFFNESS,
    FrictionState,
    frictional_chain,
    frictional_step,
)
from lcpbench.model.friction_lemke import polish_kernels

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import exact_friction as ef  # noqa: E402
from friction_agreement import Recorder, scenes  # noqa: E402


def free_step(pull: float = 0.0, left: str = "pinned"):
    """A free right end's step away from the walls (no wall row, no friction pair): a
    12-link chain in a 5 mm channel, bent a little about its centre line."""
    scene = ActuatorScene(theta=120, height=5.0, links=12, channel=True, friction=0.3,
                          left_end=left, right_end="free", pull=pull)
    chain = frictional_chain(scene)
    alpha = 0.04 * np.sin(np.linspace(0.3, 4.0, scene.links))
    state = FrictionState(alpha)
    x, _ = state.positions(chain)
    fs = frictional_step(scene, chain, state, x)
    assert fs.normal_node.size == 0 and fs.friction_node.size == 0
    assert fs.parts["rot"].size == scene.links  # a free end: its rotation borders the band
    return scene, fs


def primal_move(fs):
    """(δy of the free heights, ρ, ς) by the bordered primal system (no rows, no pairs)."""
    k, P = polish_kernels(), fs.parts
    none_i, none_f = np.zeros(0, np.int64), np.zeros(0)
    ei, ej, ev, rhs, n, lay, _, _ = k.primal_system(
        P["bands"], P["f"], P["tan"], float(P["k_tau"]), int(P["first"]),
        bool(P["right_datum"]), P["gap"], P["slip"], P["compliance"], fs.normal_node,
        fs.normal_xy, fs.friction_node, fs.tangent_xy, fs.mu, fs.pair, P["rot"],
        float(P["rot_k"]), np.zeros(0, np.bool_), none_i, none_i, none_f, 0.0)
    assert rhs.size == n
    fac = k.bordered_factor(ei, ej, ev, n, 2)
    assert fac[4]
    x, ok = k.bordered_resolve(fac, rhs)
    assert ok
    Y = lay[1]
    first, nh = int(P["first"]), P["bands"].shape[1]
    return x[Y[first:first + nh]], x[n - 2], x[n - 1], (ei, ej, ev, rhs, x)


@pytest.mark.parametrize("pull,left", [(0.0, "pinned"), (0.02, "pinned"), (0.02, "slider")])
def test_the_bordered_system_is_the_exact_solution(pull, left):
    """The free end's step solved bordered (two banded solves more) is the exact solution
    of the step's primal equations (Fractions, the oracle's own assembly, ρ = rᵀ δy) to
    1e-9 of the largest height, and the Delassus form's move (K = H + k_r r rᵀ solved
    dense) to 1e-9; its equations hold to round-off."""
    scene, fs = free_step(pull, left)
    dy, rho, sig, (ei, ej, ev, rhs, x) = primal_move(fs)
    step = ef.chain_step(fs)
    ex = ef.solve(step, [], [])
    assert ex.solution and not ex.ray and ex.free == 0
    exact = np.array([float(ex.x[step.names["Y"][i]]) for i in sorted(step.names["Y"])])
    size = np.max(np.abs(exact))
    assert size > 0.0
    np.testing.assert_allclose(dy, exact, rtol=0, atol=1e-9 * size)
    arm = np.sum(np.abs(fs.parts["rot"]))
    assert abs(rho - float(ex.x[step.names["rho"]])) <= 1e-9 * size * arm
    assert abs(sig - dy[-1]) <= 1e-12 * size  # the tip's copy
    _, _, dense, _ = fs.forces(np.zeros(0))
    np.testing.assert_allclose(dy, dense, rtol=0, atol=1e-9 * size)
    acc = np.zeros(rhs.size)
    np.add.at(acc, ei, ev * x[ej])
    assert np.max(np.abs(acc - rhs)) <= 1e-9 * max(np.max(np.abs(rhs)), 1e-300)


def test_the_free_end_turns_by_the_moment_over_its_stiffness():
    """No pull, no wall: the bending Hessian does not see a rigid turn about the pin
    (H r = 0, r_i = x_i − x_1), so the step's turn φ = rᵀ δy / |r|² is the loads' moment
    about the pin, rᵀ f (f: the step's generalised forces), over the rotation's
    stiffness ROT_STIFFNESS · EI / L."""
    scene, fs = free_step()
    P = fs.parts
    r = P["rot"]
    bands = P["bands"]
    nh = bands.shape[1]
    H = np.zeros((nh, nh))
    for p in range(3):
        for j in range(nh - p):
            H[j + p, j] = H[j, j + p] = bands[p, j]
    assert np.max(np.abs(H @ r)) <= 1e-9 * np.max(np.abs(H)) * np.max(np.abs(r))
    dy, _, _, _ = primal_move(fs)
    phi = r @ dy / (r @ r)
    theory = (r @ P["f"][:nh]) / (ROT_STIFFNESS * scene.EI / scene.length)
    assert abs(theory) > 0.0
    assert abs(phi - theory) <= 1e-9 * abs(theory)


def test_a_free_ends_answer_is_polished_onto_the_exact_answer():
    """Path 88 of benchmarks/friction_agreement.py (N = 12, slider–free, a channel), its
    first state: the answer that ends it went unpolished (2.6e-6 of the largest force
    from the exact answer in N); polished now, it is the exact solution of its index set
    (Fractions) to 1e-9 in N and the move, and every sign of the set holds there."""
    scene, states = list(scenes(89, 39))[88]
    assert scene.right_end == "free" and scene.links == 12
    rec = Recorder()
    res = lcpbench.solve_path(scene, states[:1], tol=1e-8, lcp=rec)
    assert res[0].converged
    fs, sol = rec.steps[-1]
    assert sol.extra["polish"] == "kept"
    step = ef.chain_step(fs)
    ex, dist, _ = ef.nearest_exact(step, ef.answer_values(fs, step, sol.z), search=False)
    assert ex.solution and not ex.failed
    assert max(dist[0], dist[2]) <= 1e-9, dist
    before = ef.answer_values(fs, step, sol.extra["unpolished"])
    ex0, d0, _ = ef.nearest_exact(step, before, search=False)
    assert max(d0[0], d0[2]) > 1e-7  # the polish had something to do
