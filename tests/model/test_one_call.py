"""The one-wall route of ``lcpbench.solve`` (issue 19, target 2): the solve kernel, the
judge kernel and its verdict, the rest of the result built when read.

Checked against the route it replaces, the full build of every field
(:func:`lcpbench.model.compiled.run_kernel`, then :func:`lcpbench.model.finish.finish` with the
compiled judge): the same answer, the same verdict, the same reason, every field; a
kernel that stops falls back to compiled code or the loading path; an answer the driver
did not reach is judged as before. Converged answers
are also checked against the equilibrium oracle (tests/energy_oracle.py: kinematics,
walls, signs, and stationarity by central differences of the exact energy), which
shares no code with either route.
"""

import dataclasses
import pickle
from functools import partial

import numpy as np
import pytest
from energy_oracle import assert_solved

import lcpbench
from lcpbench import ActuatorScene
from lcpbench import api as api_module
from lcpbench.escalations import Context, escalate
from lcpbench.model import compiled, kernel_call
from lcpbench.model.finish import finish
from lcpbench.model.judge import chain_args
from lcpbench.model.lazy_result import LAZY, LazyResult
from lcpbench.model.result import ContactResult
from lcpbench.model.step_solver import make_step_solver
from lcpbench.plan import make_plan
from lcpbench.solvers.registry import DEFAULT

SCENES = [dict(theta=150.0, height=3.0, links=140),  # the paper's default scene
          dict(theta=150.0, height=3.0, links=40, weight=0.0),
          dict(theta=120.0, height=2.0, links=60),
          dict(theta=170.0, height=1.0, links=33, EI=5.0)]


def _full(scene, **kw):
    """The result as the route before built it: run_kernel, then finish (every field)."""
    tol, max_outer = kw.get("tol", 1e-3), kw.get("max_outer", 200)
    method = kw.get("method", "globalised")
    chain = scene.chain()
    args = kernel_call.kernel_args(chain)
    out, used = compiled.run_kernel(
        chain, partial(make_step_solver, DEFAULT, "default", True), settings="default",
        tol=tol, max_outer=max_outer, method=method, args=args)
    why = "auto: the built-in active set (exact)"
    res = finish(scene, chain, out, solver=DEFAULT, method=method, tol=tol, elapsed=0.0,
                 settings="default", engine=used, why=why,
                 judge_args=chain_args(chain, args), route="one-wall kernel")
    # then, as solve() does, a refusal solved further (its plan's escalations)
    ctx = Context(chain, partial(make_step_solver, DEFAULT, "default", True), DEFAULT,
                  "default", "auto", tol, max_outer, method, why, None)
    return res if res.converged else escalate(
        res, ctx, make_plan(chain, DEFAULT, method, "auto", tol).escalations)


def _same_fields(got: ContactResult, want: ContactResult) -> None:
    for f in dataclasses.fields(ContactResult):
        a, b = getattr(got, f.name), getattr(want, f.name)
        if f.name in ("time_s", "scene"):
            continue
        if f.name == "steps":  # solve_time: a share of each run's own wall time
            a = [dataclasses.replace(s, solve_time=0.0) for s in a]
            b = [dataclasses.replace(s, solve_time=0.0) for s in b]
        if f.name == "extra":
            assert a.keys() == b.keys()
            a, b = dict(a), dict(b)
            for key in ("last_step",):
                sa, sb = a.pop(key), b.pop(key)
                assert (sa is None) == (sb is None)
                if sa is not None:
                    assert np.array_equal(sa.u, sb.u) and sa.residuals == sb.residuals
                    assert np.array_equal(sa.active_upper, sb.active_upper)
        if f.name in ("certificate", "judgement"):
            a, b = dataclasses.asdict(a), dataclasses.asdict(b)
        assert _equal(a, b), f.name


def _equal(a, b) -> bool:
    """Equal values, arrays bit for bit, NaN equal to NaN, through dicts and lists."""
    if isinstance(a, dict) or isinstance(b, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(a, b, equal_nan=np.asarray(a).dtype.kind == "f")
    if isinstance(a, float) and isinstance(b, float) and a != a:
        return b != b
    return a == b


@pytest.mark.parametrize("kw", SCENES)
@pytest.mark.parametrize("tol", [1e-3, 1e-8])
def test_every_field_is_the_one_the_full_build_gives(kw, tol):
    """The lazy result is the full build bit for bit (a promise of the route: kept), and
    its answer is the scene's equilibrium (the oracle)."""
    scene = ActuatorScene(**kw)
    res = lcpbench.solve(scene, tol=tol)
    assert type(res) is LazyResult and "_build" in res.__dict__
    assert not set(LAZY) & res.__dict__.keys()  # nothing built yet
    converged, force = res.converged, res.total_force
    _same_fields(res, _full(scene, tol=tol))  # (builds the rest)
    assert "_build" not in res.__dict__
    assert res.converged is converged and res.total_force == force
    assert res.total_force == float(np.sum(res.forces))  # F = ΣR, eq. (30)
    assert_solved(res)


@pytest.mark.parametrize("kw", SCENES[:3])
def test_the_answer_at_a_tight_tol_is_the_equilibrium(kw):
    got = lcpbench.solve(ActuatorScene(**kw), tol=1e-8)
    assert got.converged and got.reason == "converged"
    assert_solved(got)  # the equilibrium from first principles (tests/energy_oracle.py)


@pytest.mark.parametrize("kw", SCENES[:2])
def test_the_newton_scheme_takes_the_same_route(kw):
    scene = ActuatorScene(**kw)
    res = lcpbench.solve(scene, tol=1e-9, method="newton")
    assert type(res) is LazyResult and res.method == "newton"
    _same_fields(res, _full(scene, tol=1e-9, method="newton"))
    assert_solved(res)


@pytest.mark.parametrize("tol, max_outer", [(1e-3, 1), (1e-3, 2), (0.5, 200), (0.3, 200)])
def test_a_driver_that_stops_or_a_loose_tol_gives_the_full_builds_verdict(tol, max_outer):
    """Route against route: an answer the driver did not reach, or reached only to a
    loose tol, is no equilibrium an oracle could confirm; what is promised is that the
    lazy route builds the full build's verdict and fields, bit for bit."""
    scene = ActuatorScene(theta=150.0, height=3.0, links=60)
    res = lcpbench.solve(scene, tol=tol, max_outer=max_outer)
    want = _full(scene, tol=tol, max_outer=max_outer)
    assert res.converged == want.converged and res.reason == want.reason
    _same_fields(res, want)


def test_a_kernel_whose_step_is_refused_hands_over_to_the_loading_path(monkeypatch):
    """The lean route's kernel call reports its step refused: the answer is not rerun in
    the numpy reference (the kernel's own scheme) but escalated along the loading path,
    whose answer is judged and checked here against the equilibrium."""
    scene = ActuatorScene(theta=150.0, height=3.0, links=40)
    real = kernel_call.call_kernel

    def stopped(chain, **kw):
        got, elapsed, name = real(chain, **kw)
        return (14, *got[1:]), elapsed, name  # "the step certificate rejected the step"

    monkeypatch.setattr(api_module, "call_kernel", stopped)
    res = lcpbench.solve(scene)
    assert type(res) is ContactResult
    assert [r.name for r in res.retries] == ["ramped"], res.retries
    assert "the step certificate rejected the step" in res.retries[0].why
    assert_solved(res)


def test_a_lazy_result_pickles_replaces_and_keeps_a_field_set_by_hand():
    scene = ActuatorScene(theta=150.0, height=3.0, links=40)
    a, b, c = (lcpbench.solve(scene) for _ in range(3))
    a.reason = "mine"
    assert a.reason == "mine" and a.certificate.min_force >= -1e-12
    back = pickle.loads(pickle.dumps(b))
    assert type(back) is LazyResult and back.reason == "converged"
    assert np.array_equal(back.x, c.x) and back.total_force == c.total_force
    moved = dataclasses.replace(c, alpha=c.alpha + 0.0)
    assert moved.steps == c.steps and moved.converged
    assert "converged=True" in repr(c) and c.to_dict()["converged"]


def test_channels_keep_the_full_build():
    channel = lcpbench.solve(ActuatorScene(theta=170, height=2.5, links=30, channel=True))
    assert type(channel) is ContactResult and channel.converged


def test_a_verdict_set_by_hand_stays_and_a_verdict_unlike_the_judges_is_caught(
        monkeypatch, skip_escalations):
    scene = ActuatorScene(theta=150.0, height=3.0, links=40)
    mine = lcpbench.solve(scene)
    mine.converged = False  # set before the rest is built: kept, not checked
    assert mine.reason == "converged" and mine.converged is False
    solve_k, judge_k, _ = api_module._JUDGE[0]

    class Wrong:  # a compiled verdict that says the opposite of the judge's checks
        @staticmethod
        def accepted(settled, stats, tol):
            return False

    monkeypatch.setattr(api_module, "_JUDGE", [(solve_k, judge_k, Wrong)])
    # solve() reads a refusal's reasons, to continue one on the force bound alone
    # (tightened) or leave a saddle (escaped): the wrong verdict is caught there
    with pytest.raises(RuntimeError, match="is not the judge's"):
        lcpbench.solve(scene)
    # and, where nothing reads them first, when the result's reasons are read
    skip_escalations("tightened", "ramped", "escaped")  # (the last two read them too)
    res = lcpbench.solve(scene)
    assert res.converged is False
    with pytest.raises(RuntimeError, match="is not the judge's"):
        _ = res.reason
