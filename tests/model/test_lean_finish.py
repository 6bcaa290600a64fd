"""The lean Python of one solve (issue 19, targets 1 and 2): what is now kept, shared
or built at once gives what the definitions give.

- the values a scene's chain keeps from its build (nodal load, total load, whether
  loaded) equal the model's own definitions of them, bit for bit;
- a scene's chain, built field by field at once, equals the dataclass built by its
  constructor, is still frozen, and shares no array with another chain;
- its arrays are the paper's: the arc's rest angles (eq. 2), EI/a, −θ/N, −w a, the
  walls on the rows that can reach them;
- a result built at once (``new_result``) has every field the constructor gives;
- the cold-start arguments shared by every solve with N links stay zero;
- a new scene's first solve and the same scene's second agree with the numpy reference.
"""

import dataclasses
import math

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.api import solve_internal
from lcpbench.errors import ProblemError
from lcpbench.model import compiled, kernel_call
from lcpbench.model.result import ContactResult, new_result
from lcpbench.problems.scenes import Chain, reachable

GRID = [dict(theta=t, height=h, links=n, weight=w, channel=c, EI=ei)
        for t, h, n, w, c, ei in [
            (150.0, 3.0, 140, 2.45e-4, False, 32.01),
            (150.0, 3.0, 140, 0.0, False, 32.01),  # no load: μ = −0.0
            (90.0, 0.5, 17, 1e-3, True, 5.0),
            (300.0, 2.0, 9, 3e-2, True, 100.0),
            (45.0, 12.0, 64, 2.45e-4, False, 32.01),
        ]]


def _plain(chain: Chain) -> Chain:
    """The same chain built by the dataclass's constructor: nothing kept with it."""
    return Chain(**{f.name: getattr(chain, f.name) for f in dataclasses.fields(Chain)})


def _same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.tobytes() == b.tobytes()  # (−0.0 and 0.0 differ)


@pytest.mark.parametrize("kw", GRID)
def test_what_a_chain_keeps_from_its_scene_equals_the_definitions(kw):
    chain = ActuatorScene(**kw).chain()
    plain = _plain(chain)
    assert "_nodal_load" not in plain.__dict__
    # Chain.nodal_load: each link's load half to each end node
    assert _same_bits(chain.__dict__["_nodal_load"], plain.nodal_load)
    # Σ|μ_i|, as lcpbench.model defines it
    assert chain.__dict__["_total_load"] == float(np.sum(np.abs(plain.link_load)))
    # and the kernel's arguments made from either chain are the same bits
    for a, b in zip(kernel_call.kernel_args(chain), kernel_call._kernel_args(plain, None),
                    strict=True):
        assert _same_bits(a, b) and type(a) is type(b)


@pytest.mark.parametrize("kw", GRID)
def test_a_scenes_chain_is_the_paper_chain_and_the_constructors(kw):
    scene = ActuatorScene(**kw)
    chain = scene.chain()
    n, th, h = scene.links, math.radians(scene.theta), scene.height
    a = scene.length / n
    plain = _plain(chain)
    assert chain == plain and type(chain) is Chain
    with pytest.raises(dataclasses.FrozenInstanceError):
        chain.links = 3  # type: ignore[misc]
    # eq. (2): α_k = θ/2 − (k + ½)θ/N, the springs EI/a at rest angle −θ/N, the load −w a
    assert _same_bits(chain.rest_alpha, th / 2 - (np.arange(n) + 0.5) * th / n)
    assert _same_bits(chain.joint_stiffness, np.full(n - 1, scene.EI / a))
    assert _same_bits(chain.rest_joint, np.full(n - 1, -th / n))
    assert _same_bits(chain.link_load, np.full(n, -scene.weight * a))
    can = reachable(np.arange(1, n) * a, scene.length, h, "pinned-pinned")
    assert _same_bits(chain.upper, np.where(can, h, np.inf))
    lower = np.where(can, -h, -np.inf) if scene.channel else np.full(n - 1, -np.inf)
    assert _same_bits(chain.lower, lower)


def test_chains_share_no_arrays_and_stay_writable():
    one, two = (ActuatorScene(theta=150, height=3.0, links=30).chain() for _ in range(2))
    arrays = [f.name for f in dataclasses.fields(Chain)
              if isinstance(getattr(one, f.name), np.ndarray)]
    assert len(arrays) == 8
    for name in arrays:
        a, b = getattr(one, name), getattr(two, name)
        assert a.flags.writeable and not np.shares_memory(a, b), name
    one.upper[:] = -1.0  # a user writing into one chain's array changes no other chain
    three = ActuatorScene(theta=150, height=3.0, links=30).chain()
    assert np.array_equal(three.upper, two.upper) and not np.array_equal(three.upper,
                                                                         one.upper)


def test_a_result_built_at_once_has_every_field_of_the_constructor():
    res = lcpbench.solve(ActuatorScene(theta=150, height=3.0, links=30))
    names = {f.name for f in dataclasses.fields(ContactResult)}
    assert res.steps  # (a LazyResult builds its other fields at the first read of one)
    assert names <= res.__dict__.keys()
    again = dataclasses.replace(res)  # through ContactResult.__init__
    for name in names:
        a, b = getattr(res, name), getattr(again, name)
        assert a is b or (isinstance(a, np.ndarray) and np.array_equal(a, b)), name
    fields = {name: getattr(res, name) for name in names}
    built = new_result({k: v for k, v in fields.items() if k not in ("extra", "time_s")})
    assert built.extra == {} and built.time_s == 0.0  # the defaults, as the constructor's
    with pytest.raises(TypeError, match="links"):
        new_result({k: v for k, v in fields.items() if k != "links"})
    with pytest.raises(TypeError, match="nonsense"):
        new_result({**fields, "nonsense": 1})


def test_each_result_gets_its_own_extra():
    scene = ActuatorScene(theta=150, height=3.0, links=30)
    a, b = lcpbench.solve(scene), lcpbench.solve(scene)
    assert a.extra is not b.extra
    a.extra["mine"] = 1
    assert "mine" not in b.extra


def test_the_shared_cold_start_arguments_stay_zero():
    scene = ActuatorScene(theta=150, height=3.0, links=30)
    first = lcpbench.solve(scene, tol=1e-8)
    lcpbench.solve(ActuatorScene(theta=151, height=3.0, links=30), start=first, tol=1e-8)
    lcpbench.solve(scene, method="newton")
    lcpbench.solve(ActuatorScene(theta=170, height=2.5, links=30, channel=True))
    alpha, u, up, lo, flags = kernel_call.cold_start(29)
    assert alpha.size == 0 and flags == 0
    assert not u.any() and not up.any() and not lo.any()
    assert u.flags.writeable and up.flags.writeable  # the kernel's one signature


@pytest.mark.parametrize("kw", GRID[:3] + GRID[4:])
def test_a_new_scene_and_the_same_scene_again_give_the_reference(kw):
    """The compiled answer of a new scene and of the same scene again (its chain kept):
    the same (a property: what the chain keeps does not change the answer), and the
    scene's equilibrium (tests/energy_oracle.py)."""
    ref = lcpbench.solve(ActuatorScene(**kw), tol=1e-8)
    scene = ActuatorScene(**kw)
    for _ in range(2):  # built, then kept
        res = lcpbench.solve(scene, tol=1e-8)
        assert res.converged == ref.converged and res.engine == "compiled"
        assert res.total_force == ref.total_force
        assert np.array_equal(res.alpha, ref.alpha)
        if res.converged:
            assert_solved(res)


@pytest.mark.parametrize("bad,match", [
    (dict(tol=float("nan")), "tol must be a number"),
    (dict(tol=True), "tol must be a number"),
    (dict(tol=1), "tol must be a number"),
    (dict(max_outer=0), "max_outer must be an integer"),
    (dict(engine="fast"), "engine must be one of"),
    (dict(settings="best"), "settings must be one of"),
])
def test_bad_arguments_still_name_the_parameter(bad, match):
    with pytest.raises(ProblemError, match=match):
        solve_internal(ActuatorScene(links=10), **bad)
    with pytest.raises(ProblemError, match="scene must be"):
        lcpbench.solve({"theta": 150})


def test_a_load_of_minus_zero_and_a_nodal_load_of_zero_keep_their_signs():
    # w = 0: each link carries μ = −0.0 and each node ½μ + ½μ = +0.0; with N + 1 links
    # and N links the two arrays have the same size, and neither takes the other's sign
    a = ActuatorScene(theta=150, height=3.0, links=41, weight=0.0).chain()
    b = ActuatorScene(theta=150, height=3.0, links=40, weight=0.0).chain()
    assert np.all(np.signbit(b.link_load)) and b.link_load.size == 40
    assert not np.any(np.signbit(a.__dict__["_nodal_load"])) and a.free_nodes.size == 40
    assert _same_bits(a.__dict__["_nodal_load"], _plain(a).nodal_load)
    assert _same_bits(b.link_load, np.full(40, -0.0 * (30.0 / 40)))


ROUTES = [  # (scene, solve's arguments, whether the direct route takes it)
    (dict(theta=150, height=3.0, links=60), {}, True),  # contact
    (dict(theta=150, height=3.0, links=60), dict(method="newton"), True),
    (dict(theta=150, height=3.0, links=60), dict(max_outer=2), True),  # not converged
    (dict(theta=170, height=2.5, links=30, channel=True), dict(tol=1e-9), True),
    (dict(theta=195, height=3.0, links=20), {}, True),  # the kernel stops (on main)
    (dict(theta=40, height=6.0, links=30), {}, False),  # no wall touched: the search
    (dict(theta=150, height=3.0, links=30, weight=0.3), {}, False),  # heavy: SQP steps
    (dict(theta=150, height=3.0, links=30, weight=0.02), {}, False),  # moderately heavy
    (dict(theta=150, height=3.0, links=30, wall_stiffness=0.5), {}, True),  # elastic
]


@pytest.mark.parametrize("kw,how,route", ROUTES)
def test_the_direct_route_is_drives_route(kw, how, route, monkeypatch):
    """lcpbench.solve's direct route to the kernel answers what the route through
    solve_without_contact and drive answers, bit for bit, engine and reason included.

    Route against route: the direct route is a shortcut promised to change nothing, bit
    for bit (answers that do not converge included); the answers themselves are the
    oracle's in test_a_new_scene_and_the_same_scene_again_give_the_reference."""
    from lcpbench import plan

    scene = ActuatorScene(**kw)
    assert compiled.direct(scene.chain()) is route
    fast = lcpbench.solve(scene, **how)
    monkeypatch.setattr(plan, "direct", lambda chain: False)
    slow = lcpbench.solve(ActuatorScene(**kw), **how)
    assert (fast.converged, fast.reason, fast.engine, fast.outer_iterations) == \
        (slow.converged, slow.reason, slow.engine, slow.outer_iterations)
    for name in ("alpha", "forces", "gaps", "x", "y"):
        assert _same_bits(getattr(fast, name), getattr(slow, name)), name
    assert fast.total_force == slow.total_force
    assert [(s.iterations, s.status, s.step_length, s.max_dalpha, s.energy)
            for s in fast.steps] == [(s.iterations, s.status, s.step_length, s.max_dalpha,
                                      s.energy) for s in slow.steps]


def test_the_lean_profile_route_builds_what_the_full_route_builds(monkeypatch):
    """Route against route: the profile kernel's lean result (its fields built when read)
    against the same solve through drive and finish; only the full build can say the
    lazy one built the same fields (the answer itself is checked against the energy
    minimisation in tests/model/test_profile.py)."""
    from lcpbench import api
    from lcpbench.problems.walls import WallProfile

    wall = WallProfile.from_table([0, 10, 14, 18, 30], [3.0, 3.0, 2.4, 3.0, 3.0])
    kw = dict(theta=150, height=3.0, links=60, wall_profile=wall)
    fast = lcpbench.solve(ActuatorScene(**kw), tol=1e-9)
    monkeypatch.setattr(api, "arc_far", lambda chain: False)
    slow = lcpbench.solve(ActuatorScene(**kw), tol=1e-9)
    assert fast.route == slow.route == "profile kernel" and fast.converged
    assert (fast.converged, fast.reason, fast.engine, fast.judge, fast.outer_iterations) == \
        (slow.converged, slow.reason, slow.engine, slow.judge, slow.outer_iterations)
    for name in ("alpha", "forces", "gaps", "x", "y"):
        assert _same_bits(getattr(fast, name), getattr(slow, name)), name
    assert fast.certificate.min_gap == slow.certificate.min_gap
    assert fast.judgement.force_error_bound == slow.judgement.force_error_bound
