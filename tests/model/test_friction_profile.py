"""Coulomb friction against walls of any profile y = h(x) (issue 39, target 1;
docs/friction.md, walls of any profile).

Expected values are independent of the frictional code: the frictionless profile solve
(μ = 0; itself validated against SLSQP energy minimisation, tests/model/test_profile.py),
the flat-wall frictional solve (a flat profile is the same problem), the balance along x
at gross slip read off the answer with the slopes of the profile itself, an SLSQP
minimisation of the chain's exact energy with the tangential loads as fixed external
forces, Coulomb's law read off each node in the wall's frame, and the judge refusing
answers broken by hand.
"""

from dataclasses import replace

import numpy as np
import pytest
from friction_oracle import coulomb_on

import lcpbench
from lcpbench import ActuatorScene, ProblemError
from lcpbench.model.friction_driver import FrictionState, solve_state
from lcpbench.model.friction_result import build_result
from lcpbench.problems.walls import WallProfile

TIGHT = 1e-12
MU = 0.3


def bump(h0, depth, centre, width):
    """A stenosis: a Gaussian narrowing (mm), analytic slope."""
    def h(x):
        return h0 - depth * np.exp(-((x - centre) / width) ** 2)

    def dh(x):
        return depth * 2 * (x - centre) / width**2 * np.exp(-((x - centre) / width) ** 2)

    return WallProfile.from_function(h, dh, name="bump")


def ramp(h0, slope):
    """A straight wall y = h0 + slope (x − 15) (mm), every x."""
    return WallProfile.from_function(lambda x: h0 + slope * (np.asarray(x) - 15.0),
                                     lambda x: np.full_like(np.asarray(x, float), slope),
                                     lambda x: np.zeros_like(np.asarray(x, float)),
                                     name="ramp")


def frames(res):
    """Per free node, the upper wall's slope at the answer's x, and n, t there (from the
    profile itself, not the solver's frames)."""
    h1 = res.scene.wall_profile.slope(res.x[1:-1])
    c = np.sqrt(1.0 + h1 * h1)
    return h1, np.column_stack([h1 / c, -1.0 / c]), np.column_stack([1.0 / c, h1 / c])


def coulomb_in_the_wall_frame(res, prev, rtol=1e-9, slip=1e-6):
    """Coulomb's law read off each node in the wall's frame: the slip is the tangential
    part t·(p − p_prev) of the node's displacement since ``prev`` (the previous state)."""
    _, _, t = frames(res)
    s = (t[:, 0] * (res.x - prev.x)[1:-1] + t[:, 1] * (res.y - prev.y)[1:-1])
    N = res.forces
    return coulomb_on(res.tangential_forces, s, MU * N, max(float(np.sum(N)), abs(res.pull)),
                      slip * res.scene.length, rtol)


@pytest.mark.parametrize("profile,theta", [(bump(3.0, 0.8, 20.0, 4.0), 150),
                                           (ramp(3.0, 0.08), 160)], ids=["stenosis", "ramp"])
def test_mu_zero_reproduces_the_frictionless_profile_answer(profile, theta):
    """μ = 0, a pin and a slider (the frictional route), iterated from the unconstrained
    arc, against the frictionless profile solve at tight tolerance: the vertical part of
    N (N/√(1 + h'²), the frictionless answer's forces) to 1e-10 of the largest, α to 1e-10
    rad, T = 0."""
    base = ActuatorScene(theta=theta, wall_profile=profile, links=30)
    ref = lcpbench.solve(base, tol=TIGHT)
    assert ref.converged and ref.total_force > 0
    scene = replace(base, right_end="slider")
    chain = scene.chain()
    rest = FrictionState(chain.rest_alpha.copy())
    x, y = rest.positions(chain)
    ans = solve_state(scene, rest, x, tol=TIGHT, y_prev=y)
    assert ans.converged, ans.reason
    assert ans.iterations > 3  # an iteration of its own, not the frictionless answer again
    res = build_result(scene, {}, ans, x, TIGHT, y)
    assert res.converged, res.reason
    h1 = profile.slope(res.x[1:-1])
    scale = np.max(ref.forces)
    np.testing.assert_allclose(res.forces / np.sqrt(1 + h1 * h1), ref.forces, rtol=0,
                               atol=1e-10 * scale)
    np.testing.assert_allclose(res.alpha, ref.alpha, rtol=0, atol=1e-10)
    assert np.max(np.abs(res.tangential_forces)) <= 1e-14 * scale


@pytest.mark.parametrize("kw,states", [
    (dict(left_end="slider", right_end="slider"), [{}, {"pull": 0.02}, {"pull": 0.05}]),
    (dict(right_end="slider", channel=True, theta=200, friction=(0.3, 0.1)),
     [{}, {"theta": 210}, {"pull": 0.03}]),
    (dict(left_end="slider", right_end="pinned"), [{}, {"theta": 160}, {"theta": 170}]),
], ids=["sliders-pull", "channel", "slider-pin"])
def test_a_flat_profile_reproduces_the_flat_wall(kw, states):
    """h(x) = 3 mm as a WallProfile (its lower wall the mirror) against the flat wall at
    3 mm, along paths: normal and tangential forces to 1e-10 of the largest, α to 1e-10.

    In the channel the chain lies flat on the upper wall, and where it sticks there the
    tangential force per node along that run is statically indeterminate (the links
    between the nodes carry any axial force without moving them; docs/friction.md, the
    warm start): two routes may end at two answers that split the same ΣT differently.
    There the test compares what is determinate — the stick pattern, the slips, ΣT, N and
    α (to 1e-5 of the largest N and 1e-7 rad: the run is flat only to the linearisation)
    — and checks Coulomb's law on each route node by node. There the steps' round-off
    moves the answer by up to ~3e-10 rad a step (T shifting along the run), so the outer
    loop cannot be asked for 1e-11 (on one host it wandered 1e-11–2.5e-10 for 100 steps):
    the channel runs at tol 3e-10 and compares ΣT to 1e-8 of the largest N."""
    flat = ActuatorScene(**{**dict(theta=150, height=3.0, links=30, friction=MU), **kw})
    prof = replace(flat, height=20.0, wall_profile=WallProfile.flat(3.0))
    tol = 3e-10 if flat.channel else 1e-11
    for a, b in zip(lcpbench.solve_path(flat, states, tol=tol),
                    lcpbench.solve_path(prof, states, tol=tol), strict=True):
        assert a.converged and b.converged, (a.reason, b.reason)
        scale = np.max(a.forces)
        if flat.channel:
            mu_up, mu_lo = flat.wall_friction
            for r in (a, b):
                coulomb_on(r.tangential_forces, r.slip,
                           mu_up * r.forces + mu_lo * r.forces_lower,
                           float(np.sum(r.forces + r.forces_lower)), 1e-9 * flat.length, 1e-9)
            np.testing.assert_array_equal(b.stick, a.stick)
            np.testing.assert_allclose(b.slip, a.slip, rtol=0, atol=1e-10 * flat.length)
            assert abs(np.sum(b.tangential_forces) - np.sum(a.tangential_forces)) <= 1e-8 * scale
            np.testing.assert_allclose(b.forces, a.forces, rtol=0, atol=1e-5 * scale)
            np.testing.assert_allclose(b.forces_lower, a.forces_lower, rtol=0,
                                       atol=1e-5 * scale)
            np.testing.assert_allclose(b.alpha, a.alpha, rtol=0, atol=1e-7)
            continue
        np.testing.assert_allclose(b.forces, a.forces, rtol=0, atol=1e-10 * scale)
        np.testing.assert_allclose(b.tangential_forces, a.tangential_forces, rtol=0,
                                   atol=1e-10 * scale)
        np.testing.assert_allclose(b.alpha, a.alpha, rtol=0, atol=1e-10)
        if a.forces_lower is not None:
            np.testing.assert_allclose(b.forces_lower, a.forces_lower, rtol=0,
                                       atol=1e-10 * scale)


def test_paths_against_a_stenosis_obey_coulomb_in_the_wall_frame():
    """Sliders, a pull and a release against a stenosis: every state converges, obeys
    Coulomb's law node by node in the wall's frame and balances along x with the normal
    reactions' x parts: P + Σ (N n_x + T t_x) = 0."""
    scene = ActuatorScene(theta=150, wall_profile=bump(3.0, 0.8, 20.0, 4.0), links=30,
                          friction=MU, left_end="slider", right_end="slider")
    placed = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                    right_end="pinned"), tol=1e-10)
    prev = placed
    path = lcpbench.solve_path(scene, [{}, {"pull": 0.02}, {"pull": 0.05}, {"pull": 0.0}],
                               tol=1e-10)
    slid = 0
    for res in path:
        assert res.converged, res.reason
        slid += int(np.any(coulomb_in_the_wall_frame(res, prev)))
        _, n, t = frames(res)
        fx = res.forces @ n[:, 0] + res.tangential_forces @ t[:, 0]
        assert abs(fx + res.pull) <= 1e-9 * max(res.total_force, res.pull)
        prev = res
    assert slid >= 1  # the path has sliding nodes, not only sticking ones


def _holds(scene, pull):
    (res,) = lcpbench.solve_path(replace(scene, pull=pull), [{}], tol=1e-10)
    return res


def _gross(scene, hi=0.3, steps=40):
    lo = 0.0
    assert _holds(scene, lo).converged and not _holds(scene, hi).converged
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _holds(scene, mid).converged else (lo, mid)
    return _holds(scene, lo)


def _energy_minimiser(scene, F, x0, start):
    """Independent: SLSQP on the exact energy of the chain with fixed external loads F
    (N, per free node, (F_x, F_y)) and the pull, the left end at x0, the right end closed
    on y = 0 and the nodes kept below the wall y = h(x) at their exact x."""
    from scipy.optimize import minimize

    from lcpbench.model.chain import energy, node_positions

    chain = scene.chain()
    free, up = chain.free_nodes, np.isfinite(chain.upper)
    h = scene.wall_profile

    def total(a):
        x, y = node_positions(chain, a)
        return (energy(chain, a) - float(F[:, 0] @ (x[free] + x0) + F[:, 1] @ y[free])
                - scene.pull * (x[-1] + x0))

    def wall(a):
        x, y = node_positions(chain, a)
        return h(x[free][up] + x0) - y[free][up]

    cons = [{"type": "eq", "fun": lambda a: np.array([node_positions(chain, a)[1][-1]])},
            {"type": "ineq", "fun": wall}]
    return minimize(total, start, method="SLSQP", constraints=cons,
                    options={"ftol": 1e-16, "maxiter": 2000}).x


def test_gross_slip_against_a_ramp():
    """Sliders at both ends against a ramp (h' = 0.08): the largest pull held (bisection
    on whether an equilibrium exists, each pull one state from the placement) is the
    balance along x at gross slip, P = Σ N_i (μ t_x,i − n_x,i) (= μ ΣN on a flat wall),
    read off with the profile's own slopes; every contact node at its cone; and the shape
    is the minimiser of the exact energy with the loads −μ N_i t_i applied as fixed forces
    (SLSQP), to 1e-6 rad. pull_out (a path in the pull) finds the same force."""
    scene = ActuatorScene(theta=150, wall_profile=ramp(3.0, 0.08), links=20, friction=MU,
                          left_end="slider", right_end="slider")
    res = _gross(scene)
    assert res.converged, res.reason
    _, n, t = frames(res)
    N = res.forces
    balance = float(N @ (MU * t[:, 0] - n[:, 0]))
    assert balance != pytest.approx(MU * float(np.sum(N)), rel=1e-3)  # the slope counts
    # (within ~1e-7 of gross slip Lemke turns INACCURATE on the degenerate step, so the
    # bisection stops short of the pull-out force, as on a flat wall: docs/friction.md)
    assert abs(res.pull - balance) <= 1e-6 * res.pull
    on = N > 0
    np.testing.assert_allclose(-res.tangential_forces[on], MU * N[on], rtol=1e-6)
    F = -MU * N[:, None] * t  # the loads μ N_i along −t_i, fixed
    alpha = _energy_minimiser(replace(scene, pull=res.pull), F, res.x[0],
                              scene.chain().rest_alpha)
    np.testing.assert_allclose(alpha, res.alpha, rtol=0, atol=1e-6)
    assert "gross slip" in _holds(scene, 1.001 * res.pull).reason
    po = lcpbench.pull_out(scene)
    assert po.converged, po.reason
    assert po.force == pytest.approx(res.pull, rel=1e-5)
    assert po.solves <= 20


def test_pull_out_against_a_stenosis_is_the_sloped_balance():
    """pull_out against a stenosis (slopes of both signs under the chain): at the last
    state held, just below P*, every contact node is at its cone (to 1e-4), P* is the balance
    Σ N_i (μ t_x,i − n_x,i) read off with the profile's own slopes (to 1e-5: that state is
    within SECANT_REACH of P*), the state balances along x, and its shape is the SLSQP
    minimiser of the exact energy with its tangential forces T_i t_i as fixed loads, to
    1e-6 rad. (On a stenosis the pull-out force depends on the path: one state at a pull
    from the placement may slide the other way; docs/friction.md.)"""
    scene = ActuatorScene(theta=150, wall_profile=bump(3.0, 0.8, 20.0, 4.0), links=20,
                          friction=MU, left_end="slider", right_end="slider")
    po = lcpbench.pull_out(scene)
    assert po.converged, po.reason
    assert po.solves <= 20
    res = po.path[-1]
    _, n, t = frames(res)
    N, T = res.forces, res.tangential_forces
    on = N > 0
    np.testing.assert_allclose(-T[on], MU * N[on], rtol=1e-4)  # (held just below P*)
    balance = float(N @ (MU * t[:, 0] - n[:, 0]))
    assert abs(po.force - balance) <= 1e-5 * po.force
    assert abs(res.pull + N @ n[:, 0] + T @ t[:, 0]) <= 1e-12 + 1e-9 * res.pull
    alpha = _energy_minimiser(replace(scene, pull=res.pull), T[:, None] * t, res.x[0],
                              scene.chain().rest_alpha)
    np.testing.assert_allclose(alpha, res.alpha, rtol=0, atol=1e-6)


def test_the_judge_refuses_a_broken_answer_against_a_profile():
    """T past the cone, a sticking node that slipped (the previous state moved by hand
    under it), and T turned (the balance along x): each refused by its check."""
    scene = ActuatorScene(theta=150, wall_profile=bump(3.0, 0.8, 20.0, 4.0), links=30,
                          friction=MU, left_end="slider", right_end="slider", pull=0.02)
    placed = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                    right_end="pinned", pull=0.0), tol=1e-10)
    ans = solve_state(scene, FrictionState(placed.alpha.copy()), placed.x, tol=1e-10,
                      y_prev=placed.y)
    good = build_result(scene, {}, ans, placed.x, 1e-10, placed.y)
    assert good.converged and not good.judgement["fails"]
    inside = (good.forces > 0) & (np.abs(good.tangential_forces) < 0.9 * MU * good.forces)
    assert inside.any()  # nodes that stick inside their cones
    over = replace(ans, tangential=ans.tangential * (1.5 / MU))
    res = build_result(scene, {}, over, placed.x, 1e-10, placed.y)
    assert not res.converged and "cone" in res.judgement["fails"]
    moved = placed.x.copy()
    moved[1:-1][inside] -= 1e-3  # a slip of 1 µm at the sticking nodes
    res = build_result(scene, {}, ans, moved, 1e-10, placed.y)
    assert not res.converged and "slip" in res.judgement["fails"]
    turned = replace(ans, tangential=-ans.tangential)
    res = build_result(scene, {}, turned, placed.x, 1e-10, placed.y)
    assert not res.converged and "x balance" in res.judgement["fails"]


def test_what_is_not_built_is_refused_clearly():
    with pytest.raises(ProblemError, match="free end cannot be combined with wall_profile"):
        ActuatorScene(wall_profile=bump(3.0, 0.8, 20.0, 4.0), links=20, channel=True,
                      friction=MU, right_end="free")


def _read_off(res, prev):
    """Per free node, read off with the scene's own profiles: N (both walls), T, the
    slip t · Δp along the wall the node presses (the upper one where it presses none)
    and the x part of the wall forces N n + T t."""
    up, lo = res.scene.profiles
    xf = res.x[1:-1]
    h1 = up.slope(xf)
    l1 = lo.slope(xf) if lo is not None else np.zeros_like(xf)
    Nu = res.forces
    Nl = res.forces_lower if res.forces_lower is not None else np.zeros_like(Nu)
    slope = np.where(Nl > 0, l1, h1)
    c, cu, cl = (np.sqrt(1 + v * v) for v in (slope, h1, l1))
    s = ((res.x - prev.x)[1:-1] + slope * (res.y - prev.y)[1:-1]) / c
    fx = Nu * h1 / cu - Nl * l1 / cl + res.tangential_forces / c
    return Nu + Nl, res.tangential_forces, s, fx


def test_random_paths_against_profiles_obey_coulomb():
    """Random walls (a stenosis, a ramp, a PCHIP table; with and without a channel),
    ends, μ and paths (a bend ramp, a pull, a release): every state the judge calls
    converged obeys Coulomb's law node by node in the wall's frame and, where no end
    holds x, P + Σ (N n_x + T t_x) = 0, read off with the scene's own profiles."""
    rng = np.random.default_rng(39)
    converged = total = 0
    for _ in range(12):
        kind = rng.integers(3)
        wall = (bump(3.0, float(rng.uniform(0.2, 0.9)), float(rng.uniform(8, 22)),
                     float(rng.uniform(2.5, 5))) if kind == 0 else
                ramp(float(rng.uniform(2.5, 3.5)), float(rng.uniform(-0.1, 0.1))) if kind == 1
                else WallProfile.from_table(np.linspace(-5, 35, 9),
                                            rng.uniform(2.2, 3.8, 9)))
        channel = bool(rng.random() < 0.3)
        ends = [("pinned", "slider"), ("slider", "slider"), ("slider", "pinned")][
            rng.integers(3)]
        theta = float(rng.uniform(120, 170)) + (40.0 if channel else 0.0)
        mu = float(rng.uniform(0.1, 0.8))
        scene = ActuatorScene(theta=theta, wall_profile=wall, links=20, channel=channel,
                              left_end=ends[0], right_end=ends[1], friction=mu)
        pull = float(rng.uniform(0.0, 0.06)) if ends[1] == "slider" else 0.0
        prev = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                      right_end="pinned"), tol=1e-10)
        for res in lcpbench.solve_path(scene, [{}, {"theta": theta + 8}, {"pull": pull},
                                               {"pull": 0.0}], tol=1e-10):
            total += 1
            if not res.converged:
                break
            converged += 1
            N, T, s, fx = _read_off(res, prev)
            F = max(float(np.sum(N)), abs(res.pull))
            assert np.all(np.abs(T) <= mu * N + 1e-9 * F)
            sliding = np.abs(s) > 1e-6 * scene.length
            assert np.all(np.abs(np.abs(T[sliding]) - mu * N[sliding]) <= 1e-9 * F)
            assert np.all(T[sliding] * s[sliding] <= 1e-9 * F * np.abs(s[sliding]))
            inside = np.abs(T) < mu * N - 1e-9 * F
            assert np.all(np.abs(s[inside]) <= 1e-6 * scene.length)
            if "pinned" not in ends:
                assert abs(res.pull + float(np.sum(fx))) <= 1e-9 * F
            prev = res
    assert converged >= 0.75 * total, (converged, total)
