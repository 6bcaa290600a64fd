"""The kernels compiled ahead of time (:mod:`lcpbench.aot`, :mod:`lcpbench.numba_cache`).

The AOT module is built once per session into a temporary directory (about half a
minute: numba.pycc compiles the solve and judge kernels and gcc builds numba's
runtime into the extension). The JIT kernels are the reference: the AOT module
compiles the same functions from the same sources, so the answers must be the
JIT's to round-off, outer iteration by outer iteration; what the AOT module
cannot serve (another kernel file, another argument type, a broken file) must
go to the JIT, never to a wrong or stale answer.

The tests that need the built module are marked ``slow`` (``pytest -m slow``): the
build alone takes 75-90 s on two cores, which would take the default suite past its
ten minutes on a fresh install; the tests of the loader's refusals run by default.
"""

import json
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import lcpbench
from lcpbench import numba_cache
from lcpbench.numba_cache import AotKernels

SRC = Path(lcpbench.__file__).resolve().parent
SOLVE, JUDGE = "lcpbench.model.compiled_kernel", "lcpbench.model.judge_kernel"
PATH = "lcpbench.model.path_kernel"


@pytest.fixture(scope="session")
def aot_build(tmp_path_factory):
    """(directory, manifest) of the AOT module of the current kernels: the one that
    ``lcpbench compile`` put in its default place for these kernel files, else one
    built here, once per session."""
    from lcpbench.aot import build

    where = numba_cache.aot_dir()
    if numba_cache.load_aot(where) is not None and not os.environ.get("LCPBENCH_AOT_DIR"):
        return where, json.loads((Path(where) / numba_cache.MANIFEST).read_text())
    where = str(tmp_path_factory.mktemp("aot") / "aot-test")
    return where, build(where)


@pytest.fixture
def served_from(monkeypatch):
    """Switch this process to the AOT module in a directory (or to the JIT: None)."""
    def serve(where):
        if where is None:
            numba_cache.use_aot(False)
        else:
            monkeypatch.setenv("LCPBENCH_AOT_DIR", where)
            numba_cache.use_aot(True)
    yield serve
    numba_cache.use_aot(None)


def _summary(r):
    lower = r.forces_lower if r.forces_lower is not None else np.zeros(0)
    return (r.converged, r.outer_iterations, r.total_force, np.asarray(r.alpha),
            np.asarray(r.forces), np.asarray(lower), r.force_error_bound)


SCENES = [lcpbench.ActuatorScene(theta=150, height=3.0),
          lcpbench.ActuatorScene(theta=40, height=6.5, links=60),
          lcpbench.ActuatorScene(theta=150, height=3.0, channel=True),
          lcpbench.CantileverScene(load=0.002, height=1.0, links=80)]


@pytest.mark.slow  # the build: 75-90 s on 2 cores
def test_the_build_exports_the_solve_and_judge_kernels(aot_build):
    where, info = aot_build
    assert set(info["modules"]) >= {SOLVE, JUDGE}
    assert "solve_chain" in info["modules"][SOLVE]["functions"]
    assert "judge_answer" in info["modules"][JUDGE]["functions"]
    # the loading path's walk (aot.representative_solves' row of sections, start="ramp")
    assert "walk_heights" in info["modules"][PATH]["functions"]
    # the wall-free tests and the first step without walls (a loaded arc on the wall)
    wall_free = info["modules"]["lcpbench.model.wall_free_kernel"]["functions"]
    assert {"arc_kind", "first_step_kind", "wall_overlap"} <= set(wall_free)
    # the continuation predictor, which Solved calls from Python
    assert "predict_start" in info["modules"]["lcpbench.model.predictor_kernel"]["functions"]
    assert json.loads((Path(where) / "manifest.json").read_text()) == json.loads(
        json.dumps(info))
    assert (Path(where) / info["file"]).exists()


def _no_jit(*args):
    raise AssertionError("the JIT was asked for")


@pytest.mark.slow  # the build: 75-90 s on 2 cores
def test_the_aot_kernels_give_the_jits_answers(aot_build, served_from, monkeypatch):
    """Scene by scene (the actuator, a wide and low one, the channel, the cantilever)
    and along a continuation line (warm starts): the same path and the same
    answer, to round-off.

    Route against route: the AOT module compiles the same source as the JIT, and the
    promise is the JIT's answers; an oracle cannot tell two compilations apart (the
    answers are the oracle's in tests/model/test_compiled.py)."""
    line = [lcpbench.ActuatorScene(theta=t, height=3.0, links=60) for t in (120, 135, 150)]
    answers = {}
    for label, where in (("aot", aot_build[0]), ("jit", None)):
        served_from(where)
        if where:  # every call to be served by the AOT module: no way back to the JIT
            monkeypatch.setattr(numba_cache, "jit_module", _no_jit)
        else:
            monkeypatch.undo()
            numba_cache.use_aot(False)
        kinds = (type(numba_cache.kernel_module(SOLVE, "solve_chain")),
                 type(numba_cache.kernel_module(JUDGE, "judge_answer")))
        assert kinds == ((AotKernels, AotKernels) if where else (type(np), type(np)))
        runs = [lcpbench.solve(s) for s in SCENES] + lcpbench.solve_many(line)
        assert all(r.engine == "compiled" for r in runs[:3])
        answers[label] = [_summary(r) for r in runs]
    for a, j in zip(answers["aot"], answers["jit"], strict=True):
        assert a[:2] == j[:2] and a[0]  # converged, same outer iterations
        assert a[2] == pytest.approx(j[2], rel=1e-12, abs=1e-15)
        for x, y in zip(a[3:6], j[3:6], strict=True):
            np.testing.assert_allclose(x, y, rtol=1e-11, atol=1e-14)
        assert a[6] == pytest.approx(j[6], rel=1e-9)


@pytest.mark.slow  # the build: 75-90 s on 2 cores
def test_a_fresh_process_solves_without_importing_numba(aot_build):
    """Route against route: the AOT module and the JIT compile one source; the force is
    promised equal to 1e-12 (the two compilers may order a sum differently)."""
    code = ("import sys, lcpbench; r = lcpbench.solve(lcpbench.ActuatorScene(theta=150, "
            "height=3.0, links=40)); print('numba' in sys.modules, r.engine, "
            "r.converged, r.total_force.hex())")
    env = {**os.environ, "LCPBENCH_AOT_DIR": aot_build[0]}
    aot = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=env).stdout.split()
    jit = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**env, "LCPBENCH_AOT": "0"}).stdout.split()
    assert aot[:3] == ["False", "compiled", "True"]
    assert jit[:3] == ["True", "compiled", "True"]
    assert float.fromhex(aot[3]) == pytest.approx(float.fromhex(jit[3]), rel=1e-12)


PROBE = """
import json, os
from lcpbench import numba_cache as nc
default = nc.aot_kernels("lcpbench.model.compiled_kernel") is not None
os.environ["LCPBENCH_AOT_DIR"] = {where!r}
nc.use_aot(True)
named = nc.aot_kernels("lcpbench.model.compiled_kernel") is not None
print(json.dumps([default, named, nc.kernels_dir()]))
"""


@pytest.mark.slow  # the build: 75-90 s on 2 cores
def test_a_module_built_for_other_kernel_files_is_never_used(aot_build, tmp_path):
    """An edit of any kernel file moves the cache directory (so the module is not
    found where it was built) and changes the hash the manifest must carry (so it is
    refused even where it is named explicitly)."""
    where = aot_build[0]
    base = tmp_path / "cache"
    edited = tmp_path / "edited"
    shutil.copytree(SRC, edited / "lcpbench", ignore=shutil.ignore_patterns("__pycache__"))
    with open(edited / "lcpbench" / "model" / "judge_kernel.py", "a") as f:
        f.write("# an edit\n")

    def probe(tree):
        env = {**os.environ, "PYTHONPATH": str(tree), "NUMBA_CACHE_DIR": str(base)}
        env.pop("LCPBENCH_AOT_DIR", None)
        out = subprocess.run([sys.executable, "-c", PROBE.format(where=where)], check=True,
                             capture_output=True, text=True, env=env)
        return json.loads(out.stdout)

    here = probe(SRC.parent)
    shutil.copytree(where, numba_cache.aot_dir(here[2]))  # where this tree looks by default
    here = probe(SRC.parent)
    assert here[:2] == [True, True]
    there = probe(edited)
    assert there[2] != here[2]
    assert there[:2] == [False, False]


@pytest.mark.slow  # the build: 75-90 s on 2 cores
def test_a_broken_module_warns_once_and_the_jit_solves(aot_build, served_from, tmp_path):
    broken = tmp_path / "broken"
    shutil.copytree(aot_build[0], broken)
    (broken / aot_build[1]["file"]).write_bytes(b"not a shared object")
    served_from(str(broken))
    with pytest.warns(RuntimeWarning, match="do not load"):
        r = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links=40))
    assert r.converged and r.engine == "compiled"
    assert type(numba_cache.kernel_module(SOLVE, "solve_chain")) is not AotKernels
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # said once: the next solve is silent
        lcpbench.solve(lcpbench.ActuatorScene(theta=140, height=3.0, links=40))


def test_a_missing_module_is_silent(served_from, tmp_path):
    served_from(str(tmp_path / "nothing-here"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert numba_cache.aot_kernels(SOLVE) is None
        assert lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0,
                                                     links=40)).converged


@pytest.mark.slow  # the build: 75-90 s on 2 cores
def test_lcpbench_aot_0_turns_it_off(aot_build, monkeypatch):
    monkeypatch.setenv("LCPBENCH_AOT_DIR", aot_build[0])
    numba_cache.use_aot(None)
    try:
        assert numba_cache.aot_kernels(SOLVE) is not None
        for var, value in (("LCPBENCH_AOT", "0"), ("LCPBENCH_NUMBA_FULL_LOAD", "1")):
            monkeypatch.setenv(var, value)
            numba_cache.use_aot(None)
            assert numba_cache.aot_kernels(SOLVE) is None
            monkeypatch.delenv(var)
    finally:
        numba_cache.use_aot(None)


def test_arguments_that_do_not_fit_the_signature_go_to_the_jit(monkeypatch):
    """What numba's dispatcher would compile a new specialisation for (another dtype,
    rank, a strided or read-only array, another scalar kind) runs the JIT function;
    what it would type the same (numpy scalars, an equal dtype) runs the AOT one."""
    spec = {"symbol": "f", "args": ["A:float64:1", "i8", "f8", "b1"],
            "names": ["x", "n", "t", "flag"], "defaults": [False]}
    monkeypatch.setitem(numba_cache._JIT, "fake.kernels",
                        type("M", (), {"f": staticmethod(lambda *a: ("jit", a))}))
    f = numba_cache._checked(lambda *a: ("aot", a), spec, "fake.kernels", "f")
    x = np.zeros(4)
    assert f(x, 3, 1.0) == ("aot", (x, 3, 1.0, False))  # the default filled in
    assert f(x, np.int64(3), np.float64(1.0), flag=np.bool_(True))[0] == "aot"
    assert f(x.view(np.dtype(np.float64, metadata={"m": 1})), 3, 1.0)[0] == "aot"
    readonly = x.copy()
    readonly.flags.writeable = False
    for args in [(x.astype(np.int64), 3, 1.0), (x.astype(np.float32), 3, 1.0),
                 (np.zeros((2, 2)), 3, 1.0), (np.zeros(8)[::2], 3, 1.0), (readonly, 3, 1.0),
                 (list(x), 3, 1.0), (x, 3.0, 1.0), (x, True, 1.0), (x, 3, 1),
                 (x, 3, 1.0, 1)]:
        assert f(*args)[0] == "jit", args


def _raising_kernels():
    from numba import njit

    @njit(cache=False)
    def two_arrays(x, n):
        if n == 1:
            raise ValueError("first site")
        if n == 2:
            raise KeyError("second site")
        return x * 2.0, np.arange(n), x.dtype, np.arange(n).dtype

    two_arrays(np.ones(3), 3)
    return {__name__: type("Two", (), {"two_arrays": two_arrays})}


def test_constants_unpickled_once_are_still_the_right_objects(tmp_path):
    """The AOT build unpickles each constant of the module once per process (the
    returned arrays' Python type, a returned dtype), as numba's JIT does: call after
    call the arrays are plain ndarrays with the JIT's values, each returned dtype is
    its own (float64, int64: two constants, two caches), and each raise site keeps
    its own exception, however the calls alternate."""
    tiny = _raising_kernels()
    where = str(tmp_path / "aot")
    info = numba_cache.build_aot(where, modules=tiny)
    module, _ = numba_cache.load_aot(where) or (None, None)
    if module is None:  # built for these kernel files only: load it directly
        from importlib import machinery, util

        path = os.path.join(where, info["file"])
        spec = util.spec_from_file_location(numba_cache.AOT_NAME, path, loader=(
            machinery.ExtensionFileLoader(numba_cache.AOT_NAME, path)))
        module = util.module_from_spec(spec)
        spec.loader.exec_module(module)
    f = getattr(module, info["modules"][__name__]["functions"]["two_arrays"]["symbol"])
    x = np.array([1.0, -2.0, 0.5])
    for n in (3, 5, 4):
        a, b, da, db = f(x, n)
        assert type(a) is np.ndarray and type(b) is np.ndarray
        assert (da, db) == (np.dtype(np.float64), np.dtype(np.int64))
        np.testing.assert_array_equal(a, 2.0 * x)
        np.testing.assert_array_equal(b, np.arange(n))
    for n, exc, text in [(1, ValueError, "first site"), (2, KeyError, "second site"),
                         (1, ValueError, "first site"), (2, KeyError, "second site")]:
        with pytest.raises(exc, match=text):
            f(x, n)
    assert type(f(x, 3)[0]) is np.ndarray


def _tiny_kernels():
    from numba import njit

    @njit(cache=False)
    def tiny_sum(x, n):
        return n + 1, x.sum() * 2.0

    tiny_sum(np.ones(3), 1)
    return {__name__: type("Tiny", (), {"tiny_sum": tiny_sum, "FACTOR": 2.0})}


def test_an_entry_also_called_from_compiled_code_with_a_constant_is_exported():
    """A kernel that calls an entry with a constant (``tiny_sum(x, 1)``) types it with
    a literal (``Literal[int](1)``) while the caller compiles: a second overload that
    Python never calls. The entry is still exported, with the signature Python's call
    compiled (the first build on a cold numba cache hit this)."""
    from numba import njit, types

    tiny = _tiny_kernels()
    tiny_sum = tiny[__name__].tiny_sum

    @njit(cache=False)
    def caller(x):
        return tiny_sum(x, 1)

    caller(np.ones(3))
    assert any(isinstance(t, types.Literal) for s in tiny_sum.signatures for t in s)
    spec, exports, skipped = numba_cache.aot_exports(tiny)
    assert skipped == []
    assert spec[__name__]["functions"]["tiny_sum"]["args"] == ["A:float64:1", "i8"]


def test_a_failed_build_leaves_no_module_and_says_so_in_one_line(monkeypatch, tmp_path,
                                                                  capsys):
    """No working C compiler: AotBuildError, nothing in the output directory, and
    ``lcpbench compile`` prints one line and exits 1."""
    from lcpbench import aot

    tiny = _tiny_kernels()
    monkeypatch.setenv("CC", "false")  # distutils' compiler: a command that always fails
    with pytest.raises(numba_cache.AotBuildError, match="numba.pycc"):
        numba_cache.build_aot(str(tmp_path / "a"), modules=tiny)
    assert os.listdir(tmp_path / "a") == []
    monkeypatch.setattr(aot, "build", lambda d: numba_cache.build_aot(d, modules=tiny))
    assert aot.run(str(tmp_path / "b")) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("lcpbench compile: no ahead-of-time module")

