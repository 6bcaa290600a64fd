"""The result judge's compiled kernel: this tree's against an earlier one's (issue 19, 2 and 6).

In one process, one BLAS thread, numba's JIT for both (the AOT module is keyed
by the kernels' sources, so it serves at most one of the two), interleaved:

1. ``judge_answer`` alone on the answer of one default solve (N = 140, θ = 150°,
   h = 3 mm, tol 1e-3): called from Python, and ``--loop`` calls in a row inside
   one compiled loop (no dispatch, warm caches);
2. ``lcpbench.solve`` of that scene, the judge kernel swapped in
   :mod:`lcpbench.model.judge` (both behind the same adapter);
3. ``lcpbench.solve_many`` over the paper's 108 scenes (θ 10-180 by 10, h 2-7),
   CPU time, with the line kernel (:mod:`lcpbench.model.batch_kernel`) compiled
   against each judge: this tree's ``batch_kernel.py`` with its judge import and
   call line pointed at the earlier kernel; and each with the judge called a
   second time per scene (its answer unused), so that twice − once is what the
   judge costs inside the line kernel, where it runs between solves (colder
   caches than in a loop of judge calls).

The earlier kernel is REF's ``src/lcpbench/model/judge_kernel.py`` (default
``main``), with the modules it imports, extracted from git (``git archive REF``)
into a temporary directory and imported from there under the package name
``lcpbench_before`` (empty package modules: only the kernels' own files run; their
numba cache there too). REF's ``judge_answer`` must take the arguments this tree's
takes (since cu, cl were added; the first comparison, against 782a192, took other
arguments and returned 9 arrays, and can no longer run). Both judges must give
the same verdicts and, to round-off, the same numbers (checked before timing).

    python benchmarks/judge_cost.py [--before REF] [--repeat 41] [--loop 200]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import importlib
import importlib.util
import inspect
import io
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
import types
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
LINE = ROOT / "src/lcpbench/model/batch_kernel.py"
IMPORT = "from .judge_kernel import SETTLED, STATS, judge_answer"
CALL = "judged = judge_answer("
BEFORE = "lcpbench_before"
TOL = 1e-3
BATCH = {False: "solve_many, 108 scenes (CPU µs per scene)",
         True: "solve_many, the judge called twice per scene (CPU µs per scene)"}
JUDGED = "the judge inside the line kernel (twice − once in the same round, µs per scene)"


def _load(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    sys.modules[name] = module
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def before_kernels(ref: str, where: Path, judge_answer):
    """REF's judge kernel module, imported as ``lcpbench_before.model.judge_kernel`` from
    REF's ``src/lcpbench`` extracted into ``where``; its ``judge_answer`` must take the
    arguments of this tree's (``judge_answer``)."""
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "src/lcpbench"],
                         check=True, capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(tar)) as t:
        t.extractall(where, filter="data")
    root = where / "src" / "lcpbench"
    for name, path in ((BEFORE, root), (f"{BEFORE}.model", root / "model"),
                       (f"{BEFORE}.linalg", root / "linalg")):
        pkg = types.ModuleType(name)
        pkg.__path__ = [str(path)]
        sys.modules[name] = pkg
    judge = importlib.import_module(f"{BEFORE}.model.judge_kernel")
    theirs, ours = (inspect.signature(getattr(f, "py_func", f))
                    for f in (judge.judge_answer, judge_answer))
    if theirs != ours:
        raise SystemExit(f"{ref}'s judge_answer{theirs} does not take this tree's arguments "
                         f"{ours}: compare against a later ref")
    return judge


def line_kernel(where: Path, judge: str | None, twice: bool):
    """This tree's line kernel, its judge ``judge`` (a module name; None: this tree's),
    with the judge called a second time per scene where ``twice`` (its answer unused:
    the difference of the two is what the judge costs inside the line kernel)."""
    line = LINE.read_text()
    if IMPORT not in line or CALL not in line:
        raise SystemExit(f"{LINE} no longer has the judge's import or call line this script "
                         f"rewrites ({IMPORT!r}, {CALL!r})")
    if judge is not None:
        line = line.replace(IMPORT, f"from {judge} import SETTLED, STATS, judge_answer")
    start = line.index(CALL)
    end = line.index(".copy())", start) + len(".copy())")
    call = line[start:end]
    if twice:
        call = call.replace(CALL, "_extra = judge_answer(") + "\n        " + call
    name = f"batch_kernel_{'before' if judge else 'after'}_{'twice' if twice else 'once'}"
    (where / f"{name}.py").write_text(line[:start] + call + line[end:])
    # relative imports (the solve kernel, the verdict) from lcpbench.model, as the original
    return _load(f"lcpbench.model.{name}", where / f"{name}.py")


def compiled_loop(judge_answer):
    from numba import njit

    @njit
    def loop(reps, args):
        s = 0.0
        for _ in range(reps):
            s += judge_answer(*args)[1][0]
        return s

    return loop


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", default="main", help="git ref of the earlier judge kernel")
    ap.add_argument("--repeat", type=int, default=41)
    ap.add_argument("--loop", type=int, default=200, help="calls per compiled-loop sample")
    ap.add_argument("--batches", type=int, default=7, help="solve_many rounds (108 scenes each)")
    opts = ap.parse_args(argv)
    load0 = os.getloadavg()
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from perf_targets import paper_scenes

    import lcpbench
    from lcpbench import ActuatorScene, numba_cache
    from lcpbench.model import judge as judge_module
    from lcpbench.model.kernel_call import kernel_args, run_compiled

    numba_cache.use_aot(False)
    new_judge = numba_cache.kernel_module("lcpbench.model.judge_kernel", "judge_answer")
    new_line = numba_cache.kernel_module("lcpbench.model.batch_kernel", "solve_line")
    tmp = Path(tempfile.mkdtemp(prefix="judge_cost_"))
    old_judge = before_kernels(opts.before, tmp, new_judge.judge_answer)
    before = f"{BEFORE}.model.judge_kernel"
    lines = {("before", False): line_kernel(tmp, before, False),
             ("before", True): line_kernel(tmp, before, True),
             ("after", False): new_line, ("after", True): line_kernel(tmp, None, True)}

    scene = ActuatorScene(theta=150.0, height=3.0, links=140)
    chain = scene.chain()
    args = kernel_args(chain)
    jargs = judge_module.chain_args(chain, args)
    out, _ = run_compiled(chain, tol=TOL, args=args)
    sizes = np.array([s.max_dalpha for s in out.steps])
    call = (out.alpha, *jargs, out.forces_upper, out.forces_lower, TOL, sizes)
    adapters = {"before": old_judge, "after": new_judge}
    ro, rn = adapters["before"].judge_answer(*call), adapters["after"].judge_answer(*call)
    assert ro[0] == rn[0] and np.allclose(ro[1], rn[1], rtol=1e-6, atol=1e-12, equal_nan=True)
    np.testing.assert_array_equal(ro[2], rn[2])

    def use_judge(which, twice=False):
        judge_module._KERNEL[:] = [adapters[which]]
        numba_cache._LOADED["lcpbench.model.batch_kernel"] = lines[which, twice]

    scenes = paper_scenes()
    verdicts = {}
    for which in adapters:  # compile, warm, and the same answers from both
        use_judge(which)
        lcpbench.solve(scene, tol=TOL)
        got = lcpbench.solve_many(scenes, tol=TOL)
        verdicts[which] = [(r.converged, r.total_force) for r in got]
        use_judge(which, True)
        lcpbench.solve_many(scenes, tol=TOL)
    same = all(a[0] == b[0] and abs(a[1] - b[1]) <= 1e-9 * max(1.0, abs(a[1]))
               for a, b in zip(verdicts["before"], verdicts["after"], strict=True))
    if not same:
        raise SystemExit("solve_many: the two judges do not give the same verdicts")
    loops = {w: compiled_loop(m.judge_answer) for w, m in (("before", old_judge),
                                                           ("after", new_judge))}
    for loop in loops.values():
        loop(2, call)

    def timed(fn, reps=1, clock=time.perf_counter):
        t0 = clock()
        for _ in range(reps):
            fn()
        return (clock() - t0) / reps

    rows: dict[str, dict[str, list[float]]] = {}
    for r in range(opts.repeat):
        order = list(adapters) if r % 2 == 0 else list(adapters)[::-1]
        for which in order:
            use_judge(which)
            row = rows.setdefault(which, {})
            row.setdefault("judge_answer from Python (µs)", []).append(
                1e6 * timed(lambda f=adapters[which].judge_answer: f(*call), 20))
            row.setdefault(f"judge_answer, {opts.loop} in a compiled loop (µs)", []).append(
                1e6 * timed(lambda f=loops[which]: f(opts.loop, call)) / opts.loop)
            row.setdefault("lcpbench.solve (µs)", []).append(
                1e6 * timed(lambda: lcpbench.solve(scene, tol=TOL), 10))
            if r < opts.batches:
                for twice in (False, True):
                    use_judge(which, twice)
                    cpu = timed(lambda: lcpbench.solve_many(scenes, tol=TOL), 1,
                                time.process_time)
                    row.setdefault(BATCH[twice], []).append(1e6 * cpu / len(scenes))
                row.setdefault(JUDGED, []).append(row[BATCH[True]][-1] - row[BATCH[False]][-1])
    judge_module._KERNEL.clear()
    numba_cache._LOADED.pop("lcpbench.model.batch_kernel", None)
    load1 = os.getloadavg()
    print(f"judge kernel: {opts.before} (before) against this tree (after); N = 140, tol 1e-3; "
          f"medians (min) over {opts.repeat} interleaved rounds ({opts.batches} for "
          f"solve_many); numba JIT, one BLAS thread")
    print("\n| | before | after | after / before |\n|---|---|---|---|")
    for name in rows["before"]:
        b, a = rows["before"][name], rows["after"][name]
        mb, ma = statistics.median(b), statistics.median(a)
        print(f"| {name} | {mb:.1f} ({min(b):.1f}) | {ma:.1f} ({min(a):.1f}) | {ma / mb:.2f} |")
    name = BATCH[False]
    print(f"\nsolve_many: {1e6 / statistics.median(rows['before'][name]):.0f} -> "
          f"{1e6 / statistics.median(rows['after'][name]):.0f} scenes per CPU second "
          f"(same verdicts and forces: {same})")
    print(f"load average {load0[0]:.2f} (start), {load1[0]:.2f} (end); "
          f"{os.cpu_count()} CPUs")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
