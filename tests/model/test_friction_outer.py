"""The compiled outer step of a frictional state (model/friction_outer.py, issue 39).

Expectations are independent of the kernels: a dense build of each step from the exact
kinematics (central differences of the node positions) and the wall's own function at
the nodes' x, forward kinematics for the move, and Coulomb's gross-slip balance
|P| − Σ μN for the excess.
"""

import numpy as np
import pytest

import lcpbench
import lcpbench.model.friction_driver as fd
from lcpbench import ActuatorScene
from lcpbench.model.chain import node_positions
from lcpbench.model.friction_driver import (
    MAX_TURN,
    ROW_BAND,
    FrictionState,
    frictional_chain,
    frictional_chain_args,
)
from lcpbench.model.friction_solvers import step_runner
from lcpbench.model.friction_walls import outer_kernels
from lcpbench.problems.walls import WallProfile

RAMP = WallProfile.from_table([-40.0, 0.0, 15.0, 30.0, 70.0], [3.2, 3.0, 2.8, 2.9, 3.1],
                              kind="linear")
SCENES = [
    ActuatorScene(theta=150, height=3.0, links=12, friction=0.3, left_end="slider",
                  right_end="slider"),
    ActuatorScene(theta=170, height=2.0, links=16, channel=True, friction=(0.3, 0.1),
                  left_end="pinned", right_end="slider"),
    ActuatorScene(theta=150, wall_profile=RAMP, links=12, friction=0.4, left_end="slider",
                  right_end="slider"),
]
PATH = [{}, {"pull": 0.03}, {"pull": 0.0}]


def recorded(scene, monkeypatch):
    """Every outer step of ``PATH`` on ``scene`` as (the state it was built at, the step,
    its answer), and the path's results."""
    steps, run, built = [], step_runner("lemke"), []
    assemble = fd.frictional_step

    def step(scene, chain, state, *args, **kw):
        built.append(state)
        return assemble(scene, chain, state, *args, **kw)

    def keep(fs):
        sol = run(fs)
        steps.append((built[-1], fs, sol))
        return sol

    monkeypatch.setattr(fd, "frictional_step", step)
    keep.takes_step, keep.newton = True, True
    return lcpbench.solve_path(scene, PATH, tol=1e-10, lcp=keep), steps


def kinematic_jacobian(chain, state, h=1e-6):
    """∂(x, y)/∂u of every node by central differences of the exact kinematics (u the free
    heights; each link keeps its branch), x from node 1 (τ moves every node by 1)."""
    from lcpbench.model.chain import alpha_from_heights

    _, y0 = node_positions(chain, state.alpha)
    u0 = y0[chain.free_nodes]
    J = np.zeros((2, chain.links + 1, u0.size))
    for j in range(u0.size):
        e = np.zeros(u0.size)
        e[j] = h
        xp, yp = node_positions(chain, alpha_from_heights(chain, u0 + e, state.alpha))
        xm, ym = node_positions(chain, alpha_from_heights(chain, u0 - e, state.alpha))
        J[0, :, j], J[1, :, j] = (xp - xm) / (2 * h), (yp - ym) / (2 * h)
    return J


@pytest.mark.parametrize("scene", SCENES, ids=["flat", "channel", "ramp"])
def test_each_compiled_step_is_the_delassus_form_of_its_kinematics(scene, monkeypatch):
    """Every outer step of a path, as the kernel builds it, against an independent dense
    build: the wall rows' and friction pairs' columns G from the exact kinematics
    (central differences of node positions in the free heights, τ moving every x),
    projected on the wall's normal and tangent read from the profile's own function at
    the nodes' x; K the step's banded Hessian made dense (k_τ on τ); W = Gᵀ K⁻¹ G
    (plus the walls' compliances), g_f = g + G_nᵀ K⁻¹ f, s_f = s + G_tᵀ K⁻¹ f, with the
    gaps g the walls' heights at the nodes' x less theirs, along the normal; the LCP's
    M blocks W's as docs/friction.md writes them."""
    res, steps = recorded(scene, monkeypatch)
    assert all(r.converged for r in res)
    chain = frictional_chain(scene)
    profile = scene.profiles[0]
    first = int(chain.free_nodes[0])
    for state, fs, _ in steps:
        x, y = state.positions(chain)
        nodes = chain.free_nodes[fs.normal_node]
        upper = fs.normal_sign < 0
        h = np.full(nodes.size, scene.height) if profile is None else profile(x[nodes])
        h1 = np.zeros(nodes.size) if profile is None else profile.slope(x[nodes])
        wall = np.where(upper, h, -h)  # (the channel's lower wall: the mirror, flat)
        c = np.sqrt(1 + h1 * h1)
        n_xy = np.column_stack([np.where(upper, h1, 0.0) / c, np.where(upper, -1.0, 1.0) / c])
        np.testing.assert_allclose(fs.normal_xy, n_xy, rtol=0, atol=1e-13)
        gap = np.where(upper, wall - y[nodes], y[nodes] - wall) / c
        np.testing.assert_allclose(fs.parts["gap"], gap, rtol=0, atol=1e-12 * scene.length)
        J = kinematic_jacobian(chain, state)
        ny = J.shape[2]
        n = ny + fs.has_tau
        G = np.zeros((n, fs.normal_node.size + fs.friction_node.size))
        for r, node in enumerate(nodes):
            G[:ny, r] = n_xy[r, 0] * J[0, node] + n_xy[r, 1] * J[1, node]
            G[ny:, r] = n_xy[r, 0]  # τ moves the node along x
        for p, node in enumerate(fs.friction_node):
            t = fs.tangent_xy[p]
            G[:ny, fs.normal_node.size + p] = t[0] * J[0, node] + t[1] * J[1, node]
            G[ny:, fs.normal_node.size + p] = t[0]
        bands = fs.parts["bands"]
        K = np.zeros((n, n))
        for d in range(3):
            idx = np.arange(ny - d)
            K[idx + d, idx] = K[idx, idx + d] = bands[d, :ny - d]
        if fs.has_tau:
            K[ny, ny] = fs.parts["k_tau"]
        KG = np.linalg.solve(K, np.column_stack([G, fs.parts["f"]]))
        W = G.T @ KG[:, :-1]
        W[np.arange(nodes.size), np.arange(nodes.size)] += fs.parts["compliance"]
        scale = np.max(np.abs(W))
        np.testing.assert_allclose(fs.W, W, rtol=0, atol=1e-6 * scale)
        free = G.T @ KG[:, -1]
        mn = nodes.size
        gscale = max(np.max(np.abs(free)), chain.link_length)
        np.testing.assert_allclose(fs.g_f, fs.parts["gap"] + free[:mn], atol=1e-6 * gscale)
        np.testing.assert_allclose(fs.s_f, fs.parts["slip"] + free[mn:], atol=1e-6 * gscale)
        mt = fs.friction_node.size
        np.testing.assert_allclose(fs.M[:mn, :mn], W[:mn, :mn] * fs.force / fs.length,
                                   atol=1e-6 * scale * fs.force / fs.length)
        np.testing.assert_allclose(fs.M[mn:mn + mt, mn + mt:mn + 2 * mt],
                                   -W[mn:, mn:] * fs.force / fs.length,
                                   atol=1e-6 * scale * fs.force / fs.length)
        assert first == fs.parts["first"]


def test_move_is_exact_inverse_kinematics(monkeypatch):
    """The move of a step's answer: the new link angles' node heights (forward
    kinematics) are the step's origin + δy, the chain moved by τ, max|Δα| as measured,
    the pressed nodes those with N > 0; a δy no chain can take (a link longer than a)
    is refused (VERTICAL), and one that turns a link by more than MAX_TURN is halved."""
    scene = SCENES[0]
    _, steps = recorded(scene, monkeypatch)
    state, fs, sol = steps[1]
    state = FrictionState(state.alpha.copy(), state.x0)
    chain = frictional_chain(scene)
    k = outer_kernels()
    arrays = frictional_chain_args(chain)

    def move(z):
        return k.move(z, fs.X, fs.normal_node.size, fs.friction_node.size, fs.force,
                      fs.length, fs.has_tau, fs.normal_node, fs.pair, fs.mu, fs.normal_xy,
                      fs.tangent_xy, fs.rowed, fs.origin, state.alpha, state.x0,
                      chain.link_length, int(chain.free_nodes[0]) + 1, False, 0.0, MAX_TURN,
                      1e-10, 1.0, True, *arrays[5:11], ROW_BAND, scene.pull)

    N, T, dy, tau = fs.forces(sol.z)
    code, N2, T2, tau2, pressed, alpha, x0, dalpha, tau_taken, done, _ = move(sol.z)
    np.testing.assert_allclose(N2, N, rtol=0, atol=1e-14 * max(1.0, np.max(np.abs(N))))
    assert code == k.OK and tau2 == pytest.approx(tau, abs=1e-15)
    if np.max(np.abs(alpha - state.alpha)) <= MAX_TURN and tau_taken == tau2:  # a full step
        _, y = node_positions(chain, alpha)
        np.testing.assert_allclose(y[chain.free_nodes], fs.origin + dy, rtol=0,
                                   atol=1e-12 * chain.link_length)
        assert x0 == pytest.approx(state.x0 + tau, abs=1e-14)
    assert dalpha == pytest.approx(np.max(np.abs(alpha - state.alpha)), abs=0)
    assert np.array_equal(np.flatnonzero(pressed), np.sort(fs.normal_node[N > 0]))
    # a δy that puts a link beyond its length at every share down to 2⁻³⁰ is refused;
    # one that turns links by more than MAX_TURN is taken halved until it does not
    big = sol.z.copy()
    big[:fs.normal_node.size] *= 1e12
    assert move(big)[0] == k.VERTICAL
    some = sol.z.copy()
    some[:fs.normal_node.size] *= 1e3
    out = move(some)
    assert out[0] == k.OK and out[7] <= MAX_TURN and not out[9]


def test_gross_excess_is_the_pull_beyond_coulomb():
    """Every pair at its cone, the pull beyond what they hold: the excess is
    |P| − Σ μN (flat walls; Coulomb's balance along x), 0 where one pair is inside its
    cone or the pull is within Σ μN."""
    k = outer_kernels()
    N = np.array([0.2, 0.5, 0.1])
    mu = np.array([0.3, 0.3, 0.3])
    pair = np.array([0, 1, 2])
    normal = np.array([[0.0, -1.0]] * 3)
    tangent = np.array([[1.0, 0.0]] * 3)
    T = -mu * N
    cap = float(np.sum(mu * N))
    assert k.gross_excess(N, T, pair, mu, normal, tangent, 0.5) == pytest.approx(0.5 - cap,
                                                                               rel=1e-14)
    assert k.gross_excess(N, T, pair, mu, normal, tangent, 0.9 * cap) == 0.0
    inside = T.copy()
    inside[1] *= 0.5
    assert k.gross_excess(N, inside, pair, mu, normal, tangent, 0.5) == 0.0
