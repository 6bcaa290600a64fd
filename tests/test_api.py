"""The library call reads no file: the same scene takes the same path anywhere."""

import os
import subprocess
import sys
import textwrap

import pytest

import lcpbench
from lcpbench.api import solve_internal
from lcpbench.errors import ProblemError

PROBE = textwrap.dedent("""
    import json, lcpbench
    r = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links=40))
    print(json.dumps([r.solver, r.extra["settings"], r.outer_iterations, r.inner_iterations,
                      r.total_force]))
""")


def _run_in(folder) -> str:
    env = {**os.environ, "LCPBENCH_STORE": str(folder / "results" / "lcpbench.sqlite")}
    out = subprocess.run([sys.executable, "-c", PROBE], cwd=folder, env=env, check=True,
                         capture_output=True, text=True, timeout=120)
    return out.stdout.strip()


def test_solve_takes_the_same_path_in_any_directory(tmp_path):
    """One folder holds a store whose cached probes favour another back-end
    (a file named like the default store, and $LCPBENCH_STORE pointing at it);
    the other is empty. The default call must not notice."""
    from lcpbench.bench.select import select_backend

    holder, empty = tmp_path / "holder", tmp_path / "empty"
    (holder / "results").mkdir(parents=True)
    empty.mkdir()
    scene = lcpbench.ActuatorScene(theta=150, height=3.0, links=40)
    sel = select_backend(scene, force_tol=1e-3, store=holder / "results" / "lcpbench.sqlite",
                         candidates=["lemke"], settings=("default",), workers=1)
    assert sel.backend == "lemke"  # the store really holds a different choice
    a, b = _run_in(holder), _run_in(empty)
    assert a == b
    assert '"active-set"' in a


HEAVY = ("lcpbench.bench", "sqlite3", "subprocess", "matplotlib", "multiprocessing")


def test_import_loads_no_benchmark_code():
    """``import lcpbench`` loads none of HEAVY; a solve loads no benchmark,
    database or plotting code (subprocess is then loaded by scipy itself,
    scipy._lib._testutils, not by lcpbench)."""
    code = ("import sys, lcpbench; heavy = %r; a = [m for m in heavy if m in sys.modules]; "
            "lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links=20)); "
            "b = [m for m in heavy if m in sys.modules]; print(a, b)").replace("%r", repr(HEAVY))
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True, timeout=120)
    before, after = (eval(part + "]") for part in out.stdout.strip()[:-1].split("] "))
    assert before == []
    assert set(after) <= {"subprocess"}


@pytest.mark.parametrize("scene", [None, {}, "theta=150", 3.0])
def test_a_non_scene_is_refused(scene):
    with pytest.raises(ProblemError, match="scene must be"):
        lcpbench.solve(scene)


def test_links_auto_is_a_study_not_a_hidden_solve():
    with pytest.raises(ProblemError, match="auto_links"):
        lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links="auto"))


@pytest.mark.parametrize("scaled", ["no", 1, None])
def test_scaled_must_be_a_real_bool(scaled):
    with pytest.raises(ProblemError, match="scaled must be True or False"):
        solve_internal(lcpbench.ActuatorScene(theta=150, height=3.0, links=20), scaled=scaled)


def test_a_dense_backend_refuses_a_huge_step_before_allocating():
    """N = 20000: M would be 20000² doubles (3.2 GB). The step comes back FAILED
    with the size in the message, without forming M."""
    import tracemalloc

    from lcpbench.model.compiled_driver import assemble_step
    from lcpbench.model.step_solver import solve_step

    chain = lcpbench.ActuatorScene(theta=150, height=3.0, links=20000).chain()
    step = assemble_step(chain, chain.rest_alpha)
    tracemalloc.start()
    sol = solve_step(step, "lemke")
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert sol.status.value == "failed" and "GiB" in sol.message
    assert peak < 100e6


@pytest.mark.parametrize("call, match", [
    (lambda s: lcpbench.solve(s, solver=3), "got 3$"),
    (lambda s: lcpbench.solve(s, start={"alpha": 1}), r"got \{'alpha': 1\}$"),
    (lambda s: lcpbench.solve_many([{"theta": 150}]), r"got \{'theta': 150\}$"),
])
def test_a_bad_argument_is_shown_as_written_not_by_its_type(call, match):
    """Issue 40, item 7: no type name in a message ("got 3", not "got int")."""
    with pytest.raises(ProblemError, match=match) as err:
        call(lcpbench.ActuatorScene(theta=150, height=3.0, links=10))
    assert not any(t in str(err.value) for t in ("int", "dict", "NoneType"))
