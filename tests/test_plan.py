"""The plan (lcpbench.plan.make_plan) and the escalations table (lcpbench.escalations).

The expected routes come from the scenes' features and the rules the plan module
documents (one wall or two, N against LARGE_N, wℓ³/EI against MODERATE and HEAVY, the
back-end's form, the method, the start), checked here on the features first; they are
not copied from the code's output.
"""

import copy
from dataclasses import replace

import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.escalations import ESCALATIONS, Context, escalate
from lcpbench.model import angle_step, heavy_driver, large_n
from lcpbench.model.compiled import ENGINES_RUN
from lcpbench.model.result import Retry
from lcpbench.plan import ROUTES, STARTS, make_plan
from lcpbench.solvers.registry import DEFAULT, get_backend

PAPER = dict(theta=150.0, height=3.0)  # the arc rises ~15 mm mid-span: far past h = 3 mm
#: what the built-in back-end may do after a refusal, globalised, where round-off of
#: node heights cannot reach the judge's τ (N = 140, tol 1e-3: cond H·ε ≈ 1e-8 < τ)
OWN = ("tightened", "escaped", "ramped")


def _q(chain) -> float:
    return angle_step.load_parameter(chain)  # wℓ³/EI


def test_a_flat_wall_takes_the_one_wall_kernel_route():
    chain = ActuatorScene(**PAPER, links=140).chain()
    assert not chain.channel and chain.links < large_n.LARGE_N  # the features
    assert _q(chain) < heavy_driver.MODERATE
    for method in ("globalised", "newton"):
        plan = make_plan(chain, DEFAULT, method, "auto", 1e-3)
        assert (plan.route, plan.start, plan.engine, plan.judge) == \
            ("one-wall kernel", "cold", "compiled", "heights")
        assert plan.escalations == OWN


def test_a_channel_takes_the_channel_kernel_route():
    chain = ActuatorScene(**PAPER, links=140, channel=True).chain()
    assert chain.channel
    plan = make_plan(chain, DEFAULT, "globalised", "auto", 1e-3)
    assert (plan.route, plan.engine, plan.escalations) == ("channel kernel", "compiled", OWN)


@pytest.mark.parametrize("weight, route", [(0.3, "heavy SQP"), (0.02, "heights, then SQP")])
def test_a_heavy_chain_takes_sqp_steps_in_the_angles(weight, route):
    chain = ActuatorScene(**PAPER, links=30, weight=weight).chain()
    q = _q(chain)
    assert angle_step.in_reach(chain)
    assert (q >= angle_step.HEAVY) == (route == "heavy SQP") and q >= heavy_driver.MODERATE
    plan = make_plan(chain, DEFAULT, "globalised", "auto", 1e-3)
    assert plan.route == route and plan.escalations == OWN
    # another back-end keeps the height steps (the SQP's answer only where it touches no
    # wall, which is known at run time only)
    assert make_plan(chain, "lemke", "globalised", "auto", 1e-3).route == "compiled driver"


def test_from_large_n_the_increments_route():
    chain = ActuatorScene(**PAPER, links=large_n.LARGE_N).chain()
    assert large_n.takes(chain)
    plan = make_plan(chain, DEFAULT, "globalised", "auto", 1e-3)
    assert (plan.route, plan.engine, plan.judge) == ("large N", "increments driver", "increments")
    assert plan.kernel_takes  # the wall-free search still runs in the kernel
    # already in increments: no retry in increments
    assert plan.escalations == OWN


def test_a_tight_tolerance_at_large_n_plans_the_retry_in_increments():
    chain = ActuatorScene(**PAPER, links=3000).chain()
    tau = 1e-9  # the judge's force tolerance at tol 1e-11 (100 tol)
    assert large_n.heights_condition(3000) * 2.2e-16 >= tau  # round-off may reach τ
    plan = make_plan(chain, DEFAULT, "globalised", "auto", 1e-11)
    assert plan.escalations == ("in_increments", *OWN)
    assert make_plan(chain, DEFAULT, "newton", "auto", 1e-11).escalations == OWN


def test_another_back_end():
    chain = ActuatorScene(**PAPER, links=140).chain()
    assert get_backend("lemke").form == "lcp"
    plan = make_plan(chain, "lemke", "globalised", "auto", 1e-3)
    # a back-end's refusal stays its own; a saddle is left by every back-end
    assert (plan.route, plan.engine, plan.escalations) == \
        ("compiled driver", "compiled driver", ("escaped",))
    assert plan.judge == "heights"  # the judge kernel takes the chain, whoever solved
    assert make_plan(chain, "lemke", "globalised", "auto", 1e-3, scaled=False).route == \
        "compiled driver"  # the step's forms in the problem's units, the loop compiled
    assert make_plan(chain, "lemke", "newton", "auto", 1e-3).route == "compiled driver"


def test_the_undamped_scheme_runs_the_compiled_driver_and_never_escalates():
    chain = ActuatorScene(**PAPER, links=140).chain()
    for backend in (DEFAULT, "lemke"):
        plan = make_plan(chain, backend, "undamped", "auto", 1e-3)
        assert (plan.route, plan.engine, plan.escalations) == \
            ("compiled driver", "compiled driver", ())


def test_a_warm_start():
    chain = ActuatorScene(**PAPER, links=140).chain()
    warm = make_plan(chain, DEFAULT, "globalised", "auto", 1e-3, "warm")
    assert (warm.route, warm.start, warm.engine) == ("kernel", "warm", "compiled")


def test_start_ramp_follows_the_load_path_with_the_cold_plan_as_fallback():
    chain = ActuatorScene(**PAPER, links=140).chain()
    plan = make_plan(chain, DEFAULT, "globalised", "auto", 1e-3, "ramp")
    assert (plan.route, plan.start, plan.escalations) == ("load path", "ramp", ())
    assert plan.fallback == make_plan(chain, DEFAULT, "globalised", "auto", 1e-3)
    assert plan.fallback.route == "one-wall kernel" and plan.fallback.escalations == OWN


def test_every_planned_route_and_start_is_documented():
    for kw in (dict(), dict(channel=True), dict(weight=0.3), dict(links=large_n.LARGE_N)):
        chain = ActuatorScene(**PAPER, **{"links": 40, **kw}).chain()
        for backend in (DEFAULT, "lemke"):
            for method in ("globalised", "newton", "undamped"):
                for start in STARTS:
                    plan = make_plan(chain, backend, method, "auto", 1e-3, start)
                    assert plan.route in ROUTES and plan.start in STARTS
                    assert list(plan.escalations) == [e for e in ESCALATIONS
                                                      if e in plan.escalations]


def test_every_escalation_has_a_predicate_and_a_function():
    assert list(ESCALATIONS) == ["in_increments", "tightened", "escaped", "from_neighbour",
                                 "ramped"]
    for name, row in ESCALATIONS.items():
        assert callable(row.planned) and callable(row.applies) and callable(row.run), name


def _refused():
    res = lcpbench.solve(ActuatorScene(**PAPER, links=40), max_outer=1)
    assert not res.converged  # one contact step: out of iterations
    return res


def _recording(monkeypatch, calls, certify_at=None):
    for name, row in ESCALATIONS.items():
        def run(res, ctx, name=name):
            calls.append(name)
            got = copy.copy(res)  # a new result, as a restart's: its own retries
            got.retries = ()
            if name == certify_at:
                got.converged = True
            return got, f"{name} ran"
        monkeypatch.setitem(ESCALATIONS, name,
                            replace(row, applies=lambda res, ctx: True, run=run))


def test_a_refused_result_runs_the_escalations_in_the_tables_order(monkeypatch):
    res = _refused()
    calls: list = []
    _recording(monkeypatch, calls)
    chain = res.scene.chain()
    ctx = Context(chain, lambda: None, DEFAULT, "default", "auto", 1e-3, 1, "globalised")
    got = escalate(res, ctx, tuple(ESCALATIONS))
    assert calls == list(ESCALATIONS)
    assert got.retries == (*res.retries, *(Retry(n, f"{n} ran") for n in ESCALATIONS))
    assert got.route == res.route == "one-wall kernel"
    # the first certified answer ends them
    calls.clear()
    _recording(monkeypatch, calls, certify_at="tightened")
    assert escalate(res, ctx, tuple(ESCALATIONS)).converged
    assert calls == ["in_increments", "tightened"]
    # a plan's subset, in the table's order
    calls.clear()
    escalate(res, ctx, ("escaped",))
    assert calls == ["escaped"]


def test_solve_runs_its_plans_escalations_in_order(monkeypatch):
    calls: list = []
    _recording(monkeypatch, calls)
    scene = ActuatorScene(**PAPER, links=40)
    res = lcpbench.solve(scene, max_outer=1)
    assert calls == list(OWN)  # the plan's (N = 40, tol 1e-3: no retry in increments)
    assert [r.name for r in res.retries] == list(OWN)
    calls.clear()
    res = lcpbench.solve(scene, solver="lemke", max_outer=1)
    assert calls == ["escaped"] and res.retries == (Retry("escaped", "escaped ran"),)
    calls.clear()
    res = lcpbench.solve(scene, max_outer=1, method="undamped")
    assert calls == [] and res.retries == ()


def test_the_result_says_what_ran():
    scene = ActuatorScene(**PAPER, links=40)
    res = lcpbench.solve(scene)
    assert (res.route, res.engine, res.judge, res.retries) == \
        ("one-wall kernel", "compiled", "heights", ())
    ref = lcpbench.solve(scene, method="undamped")  # an option of the compiled driver
    assert (ref.route, ref.engine) == ("compiled driver", "compiled driver")
    bumped = ActuatorScene(**PAPER, links=40, wall_profile=_bump())
    ref = lcpbench.solve(bumped, solver="lemke")  # the compiled driver, its walls a profile
    assert (ref.route, ref.engine) == ("compiled driver", "compiled driver")
    assert "engine" not in res.extra and "judge" not in res.extra


def _bump():
    from lcpbench.problems.walls import WallProfile

    return WallProfile.from_table([0, 10, 14, 18, 30], [3.0, 3.0, 2.4, 3.0, 3.0])


@pytest.mark.parametrize("kw, how, engine", [
    (dict(links=40), dict(), "compiled"),
    (dict(links=40, channel=True), dict(), "compiled"),
    (dict(links=30, weight=0.3), dict(), "compiled SQP (SQP steps in the link angles"),
    (dict(links=40), dict(solver="lemke"), "compiled driver"),
    (dict(links=40), dict(method="undamped"), "compiled driver"),
    (dict(links=40, wall_profile=_bump()), dict(), "compiled"),
    (dict(links=40, wall_profile=_bump()), dict(method="newton"), "compiled driver"),
    (dict(links=40, wall_profile=_bump()), dict(solver="lemke"), "compiled driver"),
    (dict(links=40, wall_profile=_bump()), dict(method="undamped"), "compiled driver"),
])
def test_the_planned_engine_is_the_one_drive_runs(kw, how, engine):
    # model.compiled.drive decides again at run time: the plan must not drift from it
    res = lcpbench.solve(ActuatorScene(**PAPER, **kw), **how)
    plan = make_plan(res.scene.chain(), how.get("solver", DEFAULT),
                     how.get("method", "globalised"), "auto", 1e-3)
    assert res.route == plan.route and res.engine.startswith(engine)
    assert res.engine.startswith(plan.engine) and res.judge == plan.judge
    assert res.engine.split(" (")[0] in ENGINES_RUN  # one vocabulary, no "numpy"


def test_the_json_says_what_ran():
    """`solve --json` (ContactResult.to_dict) carries the typed fields of what ran."""
    import lcpbench
    from lcpbench.plan import ROUTES

    res = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links=40))
    d = res.to_dict()
    assert d["route"] in ROUTES and d["route"] == res.route
    assert (d["engine"], d["judge"]) == (res.engine, res.judge)
    assert d["retries"] == [{"name": r.name, "why": r.why} for r in res.retries]
