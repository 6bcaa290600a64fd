"""The frictional contact step and loading paths (issue 39, docs/friction.md).

Expectations are independent of the frictional code: today's frictionless solve (μ = 0
limit), force balance at gross slip (the pull equals μ ΣN), Coulomb's law read off
each node, and the judge refusing answers broken by hand.
"""

from dataclasses import replace

import numpy as np
import pytest
from friction_oracle import coulomb_holds

import lcpbench
from lcpbench import ActuatorScene, ProblemError
from lcpbench.model.friction_driver import (
    FrictionState,
    frictional_chain,
    frictional_step,
    solve_state,
)
from lcpbench.model.friction_result import build_result

TIGHT = 1e-12


def _from_rest(scene):
    """The frictional outer loop of one state started at the unconstrained arc."""
    chain = scene.chain()
    rest = FrictionState(chain.rest_alpha.copy())
    return solve_state(scene, rest, rest.positions(chain)[0], tol=TIGHT)


@pytest.mark.parametrize("kw", [dict(theta=150, height=3.0),
                                dict(theta=170, height=2.5, channel=True),
                                dict(theta=120, height=2.0, weight=0.0)],
                         ids=["flat", "channel", "weightless"])
def test_mu_zero_reproduces_the_frictionless_answer(kw):
    """μ = 0 (pin and slider: the frictional route) from the rest arc, an iteration of
    its own, against today's solve at tight tolerance: 1e-10 relative per node."""
    base = ActuatorScene(links=30, **kw)
    ref = lcpbench.solve(base, tol=TIGHT)
    assert ref.converged
    ans = _from_rest(replace(base, right_end="slider"))
    assert ans.converged, ans.reason
    res = build_result(replace(base, right_end="slider"), {}, ans,
                       FrictionState(base.chain().rest_alpha).positions(base.chain())[0], TIGHT)
    scale = max(np.max(ref.forces), 1e-300)
    np.testing.assert_allclose(res.forces, ref.forces, rtol=0, atol=1e-10 * scale)
    if base.channel:
        np.testing.assert_allclose(res.forces_lower, ref.forces_lower, rtol=0,
                                   atol=1e-10 * scale)
    assert abs(res.total_force - ref.total_force) <= 1e-10 * ref.total_force
    np.testing.assert_allclose(res.alpha, ref.alpha, rtol=0, atol=1e-10)
    assert np.max(np.abs(res.tangential_forces)) <= 1e-14 * scale  # μ = 0: round-off


def test_path_of_one_frictionless_state_is_todays_solve():
    scene = ActuatorScene(theta=150, height=3.0, links=30)
    ref = lcpbench.solve(scene)
    (res,) = lcpbench.solve_path(scene, [{}])
    assert res.route == "frictionless" and res.contact is not None
    assert res.total_force == ref.total_force
    np.testing.assert_array_equal(res.forces, ref.forces)


@pytest.mark.parametrize("kw", [dict(left_end="pinned", right_end="slider"),
                                dict(left_end="slider", right_end="slider"),
                                dict(left_end="slider", right_end="slider", channel=True,
                                     theta=200, friction=(0.3, 0.1))],
                         ids=["pin-slider", "slider-slider", "channel"])
def test_pull_path_balances_and_obeys_coulomb(kw):
    scene = ActuatorScene(**{**dict(theta=150, height=3.0, links=30, friction=0.3), **kw})
    path = lcpbench.solve_path(scene, [{}, {"pull": 0.02}, {"pull": 0.05}, {"pull": 0.0}],
                               tol=1e-10)
    for res in path:
        assert res.converged, res.reason
        assert res.route == "frictional"
        coulomb_holds(res)
        if scene.left_end == "slider":  # nothing else holds x: friction takes the pull
            assert abs(np.sum(res.tangential_forces) + res.pull) <= 1e-12 + 1e-9 * res.pull
    # the pull straightens the chain and unloads the wall (the tension's moment)
    assert path[2].total_force < path[1].total_force < path[0].total_force


def _holds(scene, pull):
    (res,) = lcpbench.solve_path(replace(scene, pull=pull), [{}], tol=1e-10)
    return res


def test_at_gross_slip_the_pull_equals_mu_times_the_normal_forces():
    """Sliders at both ends on a flat wall: the largest pull held (bisection on whether
    an equilibrium exists) equals μ ΣN at that pull; every contact node slides."""
    scene = ActuatorScene(theta=150, height=3.0, links=30, friction=0.3,
                          left_end="slider", right_end="slider")
    lo, hi = 0.0, 0.2
    assert _holds(scene, lo).converged and not _holds(scene, hi).converged
    for _ in range(45):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _holds(scene, mid).converged else (lo, mid)
    res = _holds(scene, lo)
    assert res.converged
    # Within ~1e-7 of gross slip every node sits on its cone and the step's LCP is
    # degenerate: Lemke turns INACCURATE there, so the bisection stops ~1e-8 N short
    # of the pull-out force, and the identity is held to that (not to round-off).
    assert abs(res.pull - 0.3 * res.total_force) <= 1e-6 * res.pull
    assert np.all(res.stick[res.forces > 0])  # held: the last nodes stick on their cones
    N = res.forces[res.forces > 0]
    np.testing.assert_allclose(-res.tangential_forces[res.forces > 0], 0.3 * N, rtol=1e-6)
    assert "gross slip" in _holds(scene, 1.001 * hi).reason


def test_the_judge_refuses_a_broken_answer():
    scene = ActuatorScene(theta=150, height=3.0, links=30, friction=0.3,
                          left_end="slider", right_end="slider", pull=0.05)
    chain = scene.chain()
    placed = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                    right_end="pinned", pull=0.0), tol=1e-10)
    start = FrictionState(placed.alpha.copy())
    ans = solve_state(scene, start, placed.x, tol=1e-10)
    good = build_result(scene, {}, ans, placed.x, 1e-10)
    assert good.converged and not good.judgement["fails"]
    pairs = ans.step.friction_node - chain.free_nodes[0]
    for how, check in [("over the cone", "cone"), ("turned", "x balance")]:
        bad = replace(ans, tangential=ans.tangential.copy())
        if how == "over the cone":
            bad.tangential *= 1.0 / 0.3 * 1.5  # |T| = 1.5 μ N at least at one node
            bad.tangential *= np.max(good.tangential_forces[pairs] != 0)
        else:
            bad.tangential = -bad.tangential
        res = build_result(scene, {}, bad, placed.x, 1e-10)
        assert not res.converged and check in res.judgement["fails"], (how, res.judgement)


def test_the_step_lcp_is_not_symmetric_and_lemke_solves_it():
    scene = ActuatorScene(theta=150, height=3.0, links=20, friction=0.4, right_end="slider",
                          pull=0.03)
    chain = scene.chain()
    placed = lcpbench.solve(replace(scene, friction=0.0, right_end="pinned", pull=0.0))
    fs = frictional_step(scene, chain, FrictionState(placed.alpha.copy()), placed.x)
    assert not np.allclose(fs.M, fs.M.T)
    W = 0.5 * (fs.W + fs.W.T)
    assert np.allclose(fs.W, fs.W.T, atol=1e-12 * np.abs(fs.W).max())
    assert np.min(np.linalg.eigvalsh(W)) >= -1e-10 * np.abs(W).max()


@pytest.mark.parametrize("states,words", [
    ({"theta": 120}, "sequence of dicts"),
    ([{"links": 40}], "may change"),
    ([{"theta": -5}], "theta"),
    ([], "at least one state"),
    ([3], r"states\[0\] must be a dict"),
])
def test_bad_paths_give_one_clear_error(states, words):
    scene = ActuatorScene(links=20, friction=0.3, right_end="slider")
    with pytest.raises(ProblemError, match=words):
        lcpbench.solve_path(scene, states)


def test_unsupported_ends_and_scenes_are_refused_clearly():
    with pytest.raises(ProblemError, match="a free end needs channel=True"):
        ActuatorScene(links=20, friction=0.3, right_end="free")
    with pytest.raises(ProblemError, match="ActuatorScene"):
        lcpbench.solve_path(lcpbench.CantileverScene(links=20))


def _energy_minimiser(scene, T, x0, start):
    """Independent: SLSQP on the exact energy of the chain with the tangential forces T
    (N, per free node) and the pull applied as fixed external loads along x, the left
    end at x0, the right end closed on y = 0 and the nodes kept off the walls."""
    from scipy.optimize import minimize

    from lcpbench.model.chain import energy, node_positions

    chain = frictional_chain(scene)
    free = chain.free_nodes
    up, lo = np.isfinite(chain.upper), np.isfinite(chain.lower)

    def total(a):
        x, _ = node_positions(chain, a)
        return energy(chain, a) - float(T @ (x[free] + x0)) - scene.pull * (x[-1] + x0)

    closure = [{"type": "eq", "fun": lambda a: np.array([node_positions(chain, a)[1][-1]])}]
    cons = (closure if scene.right_end != "free" else []) + [
            {"type": "ineq", "fun": lambda a: np.concatenate([
                chain.upper[up] - node_positions(chain, a)[1][free][up],
                node_positions(chain, a)[1][free][lo] - chain.lower[lo]])}]
    res = minimize(total, start, method="SLSQP", constraints=cons,
                   options={"ftol": 1e-16, "maxiter": 2000})
    return res.x


@pytest.mark.parametrize("pull", [0.05, "gross"])
def test_the_shape_is_the_energy_minimiser_under_its_tangential_loads(pull):
    """The frictional answer's shape equals the minimiser of the chain's energy with its
    tangential forces (μ N_i at gross slip) applied as fixed loads: 1e-6 rad."""
    scene = ActuatorScene(theta=150, height=3.0, links=20, friction=0.3,
                          left_end="slider", right_end="slider")
    gross = pull == "gross"
    if gross:  # just below the pull-out force: every contact node on its cone
        lo, hi = 0.0, 0.2
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if _holds(scene, mid).converged else (lo, mid)
        pull = lo
    res = _holds(scene, pull)
    assert res.converged, res.reason
    T = res.tangential_forces
    if gross:
        N = res.forces
        np.testing.assert_allclose(-T, 0.3 * N, atol=1e-6 * np.max(N))
        T = -0.3 * N  # the loads μ N_i themselves
    alpha = _energy_minimiser(replace(scene, pull=pull), T, res.x[0], scene.chain().rest_alpha)
    np.testing.assert_allclose(alpha, res.alpha, rtol=0, atol=1e-6)


def test_mu_to_infinity_the_contact_nodes_clamp_the_chain():
    """The μ → ∞ limit (μ = 20 and 1000, the largest accepted), a pin and a slider, the
    paper's scene at N = 20 pulled by 0.2 N (at μ = 0.3 its contact nodes slide 0.016
    mm and the pin takes half the pull). Theory: nothing slides, so every node still
    pressed is where the first state put it and sticks, and the answer no longer depends
    on μ. The run of stuck nodes (on level links) is a clamp: the chain left of it does
    not see the pull (its angles are those of the first state), and the run alone holds
    the pull (Σ T + P = 0 though the left end is a pin). Independent: the shape is the
    minimiser of the exact energy minus P x_N+1 (SLSQP) with the run's first node held
    where the first state put it and the run's links level."""
    from scipy.optimize import minimize

    from lcpbench.model.chain import energy, node_positions

    pull = 0.2
    paths = {mu: lcpbench.solve_path(ActuatorScene(theta=150, height=3.0, links=20,
                                                   friction=mu, right_end="slider"),
                                     [{}, {"pull": pull}], tol=TIGHT)
             for mu in (20.0, 1000.0)}
    first, res = paths[1000.0]
    assert first.converged and res.converged, res.reason
    run = np.flatnonzero(res.forces > 0)  # still pressed (the pull lifts one node)
    assert run.size >= 2 and np.all(np.diff(run) == 1) and np.all(first.forces[run] > 0)
    assert np.all(res.stick[run])
    a = res.scene.length / res.links
    np.testing.assert_allclose(res.x[run + 1], first.x[run + 1], rtol=0, atol=1e-12 * a)
    other = paths[20.0][1]
    for key in ("forces", "tangential_forces", "alpha"):
        np.testing.assert_allclose(getattr(other, key), getattr(res, key), rtol=0,
                                   atol=1e-12 * max(1.0, np.max(np.abs(res.forces))))
    j0, j1 = run[0] + 1, run[-1] + 1  # the run's first and last node (0: the left pin)
    np.testing.assert_allclose(res.alpha[:j0], first.alpha[:j0], rtol=0, atol=1e-12)
    assert abs(np.sum(res.tangential_forces) + pull) <= 1e-10 * pull
    scene = res.scene
    chain = frictional_chain(scene)
    free = chain.free_nodes
    up = np.isfinite(chain.upper)

    def total(al):  # in units of EI/ℓ
        return (energy(chain, al) - pull * node_positions(chain, al)[0][-1]) * (
            scene.length / scene.EI)

    cons = [{"type": "eq", "fun": lambda al: np.array([node_positions(chain, al)[1][-1]])},
            {"type": "eq", "fun": lambda al: np.array([
                node_positions(chain, al)[0][j0] - first.x[j0],
                node_positions(chain, al)[1][j0] - scene.height])},
            {"type": "eq", "fun": lambda al: al[j0:j1]},
            {"type": "ineq", "fun": lambda al: chain.upper[up]
             - node_positions(chain, al)[1][free][up]}]
    alpha = first.alpha.copy()
    for _ in range(4):  # SLSQP stops short; started again from where it stopped
        alpha = minimize(total, alpha, method="SLSQP", constraints=cons,
                         options={"ftol": 1e-15, "maxiter": 2000}).x
    np.testing.assert_allclose(alpha, res.alpha, rtol=0, atol=1e-6)


def test_random_paths_converged_answers_obey_coulomb():
    """Random scenes and paths (a bend ramp, a pull, a release; free right ends in
    channels): every state the judge calls converged obeys Coulomb's law node by node
    and balances along x."""
    rng = np.random.default_rng(7)
    converged = 0
    for _ in range(12):
        channel = bool(rng.random() < 0.4)
        ends = [("pinned", "slider"), ("slider", "slider"), ("slider", "pinned"),
                ("pinned", "free"), ("slider", "free")][rng.integers(5 if channel else 3)]
        theta = float(rng.uniform(100, 160))
        scene = ActuatorScene(theta=theta, height=float(rng.uniform(1.5, 4.0)), links=20,
                              channel=channel, left_end=ends[0], right_end=ends[1],
                              friction=float(rng.uniform(0.05, 0.8)))
        pull = float(rng.uniform(0.0, 0.08)) if ends[1] != "pinned" else 0.0
        states = [{}, {"theta": theta + 10}, {"pull": pull}, {"pull": 0.0}]
        for res in lcpbench.solve_path(scene, states, tol=1e-10):
            if not res.converged:
                continue
            converged += 1
            coulomb_holds(res)
            if "pinned" not in ends:
                assert abs(np.sum(res.tangential_forces) + res.pull) <= 1e-9 * max(
                    res.total_force, res.pull)
    assert converged >= 30


@pytest.mark.parametrize("left", ["pinned", "slider"])
def test_a_free_right_end_in_a_channel(left):
    """A free right end (its tip's height unknown, the rotation about the left pin held
    by the walls): Coulomb node by node, the tip on a wall, and the shape is the energy
    minimiser (no closure) under the answer's tangential loads and the pull."""
    scene = ActuatorScene(theta=120, height=2.0, links=20, channel=True, friction=0.3,
                          left_end=left, right_end="free")
    path = lcpbench.solve_path(scene, [{}, {"pull": 0.02}], tol=1e-10)
    for res in path:
        assert res.converged, res.reason
        coulomb_holds(res)
        assert res.forces.size == scene.links  # nodes 2..N+1: the tip too
        assert abs(abs(res.y[-1]) - scene.height) <= 1e-9  # the tip rests on a wall
    res = path[-1]
    placed = lcpbench.solve(replace(scene, friction=0.0, left_end="pinned",
                                    right_end="pinned"))  # a start away from the answer
    alpha = _energy_minimiser(replace(scene, pull=0.02), res.tangential_forces, res.x[0],
                              placed.alpha)
    np.testing.assert_allclose(alpha, res.alpha, rtol=0, atol=1e-6)
