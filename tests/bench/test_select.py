"""Back-end selection: qualified, fastest, cached in the store, passed to solve() explicitly."""

import pytest

import lcpbench
from lcpbench.bench.select import probe_scenes, select_backend
from lcpbench.bench.store import Store
from lcpbench.errors import ProblemError

SCENE = lcpbench.ActuatorScene(theta=120.0, height=3.0, links=30)
CANDIDATES = ["active-set", "lemke", "pgs"]


@pytest.fixture(scope="module")
def selected(tmp_path_factory):
    path = tmp_path_factory.mktemp("sel") / "s.sqlite"
    s = select_backend(SCENE, force_tol=1e-3, store=path, candidates=CANDIDATES,
                       settings=("default", "high"), workers=2)
    return path, s


def test_probes_depend_on_the_kind_only():
    a = probe_scenes(SCENE)
    b = probe_scenes(lcpbench.ActuatorScene(theta=40.0, height=6.0, links=30))
    assert a == b and len(a) == 4
    assert all(p.arc_height > p.height for p in a)  # every probe is in contact
    with pytest.raises(ProblemError, match="scene_or_grid"):
        probe_scenes("theta=150")


def test_selection_meets_the_accuracy_and_is_the_fastest(selected):
    _, s = selected
    assert s.backend in ("active-set", "lemke") and s.error <= 1e-3
    ok = [e for e in s.evidence if e["ok"]]
    assert s.time_s == min(e["time_s"] for e in ok)
    for e in s.evidence:  # qualified means: converged on every probe, within force_tol
        if e["ok"]:
            assert e["converged"] == e["probes"] == 4 and e["error"] <= 1e-3
        else:
            assert e["why"]
    assert "fastest" in s.reason


def test_probes_are_cached_in_the_store(selected):
    path, s = selected
    with Store(path) as st:
        n = st.count()
    again = select_backend(SCENE, force_tol=1e-3, store=path, candidates=CANDIDATES,
                           settings=("default", "high"))
    with Store(path) as st:
        assert st.count() == n  # nothing solved the second time
    assert (again.backend, again.settings) == (s.backend, s.settings)


def test_impossible_budget_selects_nothing(selected):
    path, _ = selected
    s = select_backend(SCENE, force_tol=1e-3, time_budget=1e-9, store=path,
                       candidates=CANDIDATES, settings=("default", "high"))
    assert s.backend is None and "budget" in s.reason


def test_bad_input():
    with pytest.raises(ProblemError, match="force_tol"):
        select_backend(SCENE, force_tol=0.0, probe=False)
    with pytest.raises(ProblemError, match="time_budget"):
        select_backend(SCENE, force_tol=1e-3, time_budget=-1, probe=False)


def test_solve_uses_an_explicit_selection(selected):
    _, s = selected
    assert s.backend is not None
    res = lcpbench.solve(SCENE, solver=s, tol=1e-3)
    assert res.solver == s.backend and res.extra["settings"] == s.settings
    assert res.converged and res.extra["auto"].startswith("selected")


def test_a_selection_without_a_backend_is_refused(selected):
    path, _ = selected
    none = select_backend(SCENE, force_tol=1e-3, time_budget=1e-9, store=path,
                          candidates=CANDIDATES, settings=("default",), probe=False)
    assert none.backend is None
    with pytest.raises(ProblemError, match="chose no back-end"):
        lcpbench.solve(SCENE, solver=none)
