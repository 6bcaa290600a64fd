"""One default ``lcpbench.solve`` (N = 140, θ = 150°, h = 3 mm, tol 1e-3): this tree
against main's, interleaved in one process (issue 19, target 2: the Python around the
kernels).

main's package is imported from ``--main`` (default /work/main/src) under the name
``lcpbench_main``; each package solves its own scene objects with its own kernels
(each finds the ahead-of-time module built for its kernel files, else numba's JIT;
the table says which served). Two scene kinds: the same scene object again (its
chain kept) and a new scene object each call (its construction not timed). Blocks of
``--block`` solves, the two trees alternating, the order swapped every repetition;
wall time (perf_counter) and CPU time (process_time) per solve, median and best over
``--repeat`` blocks. Then
the same with the kernels replayed (``python_overhead._Replay``: each kernel call
hands back its recorded outputs), which leaves the Python alone. One BLAS thread;
the load average before and after is printed.

    python benchmarks/one_call.py [--repeat 21] [--block 100] [--main /work/main/src]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse
import importlib
import importlib.util
import statistics
import subprocess
import sys
import time
from pathlib import Path

import lcpbench

sys.path.insert(0, str(Path(__file__).resolve().parent))
from python_overhead import _Replay  # noqa: E402

SCENE = dict(theta=150.0, height=3.0, links=140)
TOL = 1e-3


def import_main(src: str):
    """main's ``lcpbench`` package as ``lcpbench_main`` (its own modules, its own caches)."""
    spec = importlib.util.spec_from_file_location(
        "lcpbench_main", str(Path(src) / "lcpbench" / "__init__.py"),
        submodule_search_locations=[str(Path(src) / "lcpbench")])
    module = importlib.util.module_from_spec(spec)
    sys.modules["lcpbench_main"] = module
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def _solve_kernel(package: str):
    """The solve kernel's module of a tree: ``kernel_call.solve_kernel`` (since the kernel's
    Python side moved there), else the older ``compiled._kernel``."""
    try:
        return importlib.import_module(f"{package}.model.kernel_call").solve_kernel()
    except (ImportError, AttributeError):
        return importlib.import_module(f"{package}.model.compiled")._kernel()


def _judge_kernel(package: str):
    try:
        return importlib.import_module(f"{package}.model.judge")._kernel()
    except AttributeError:  # a tree before the judge's numpy twin was removed
        return importlib.import_module(f"{package}.model.judge_compiled")._kernel()


class Tree:
    """One tree's solve, scene class and kernel modules."""

    def __init__(self, label: str, package: str):
        self.label = label
        api = importlib.import_module(f"{package}.api")
        self.solve = api.solve
        self.Scene = importlib.import_module(f"{package}.problems.scenes").ActuatorScene
        self.first = self.solve(self.Scene(**SCENE), tol=TOL)  # loads the kernels
        self.kernels = (_solve_kernel(package), _judge_kernel(package))
        self.served = "AOT" if type(self.kernels[0]).__name__ == "AotKernels" else "JIT"

    def block(self, n: int, same: bool) -> tuple[float, float]:
        """(wall, CPU) seconds per solve of a block of n solves (scene objects made
        before)."""
        scenes = [self.Scene(**SCENE)] * n if same else [self.Scene(**SCENE) for _ in range(n)]
        solve = self.solve
        c0, t0 = time.process_time(), time.perf_counter()
        for s in scenes:
            r = solve(s, tol=TOL)
        wall, cpu = (time.perf_counter() - t0) / n, (time.process_time() - c0) / n
        assert r.converged
        return wall, cpu


def interleaved(trees: list[Tree], repeat: int, block: int, same: bool) -> tuple[dict, dict]:
    """({tree: wall times}, {tree: CPU times}) of ``repeat`` blocks each, alternating."""
    wall: dict = {t.label: [] for t in trees}
    cpu: dict = {t.label: [] for t in trees}
    for r in range(repeat):
        for t in (trees if r % 2 == 0 else trees[::-1]):
            w, c = t.block(block, same)
            wall[t.label].append(w)
            cpu[t.label].append(c)
    return wall, cpu


def replaying(trees: list[Tree]):
    """Context: every tree's kernel calls recorded once, then replayed."""
    reps = [_Replay(m, name) for t in trees
            for m, name in zip(t.kernels, ("solve_chain", "judge_answer"), strict=True)]

    class _Ctx:
        def __enter__(self):
            for rp in reps:
                setattr(rp.module, rp.name, rp)
            for t in trees:  # recorded: one solve each (the same answers then)
                t.solve(t.Scene(**SCENE), tol=TOL)
            for rp in reps:
                rp.next = 0
            return self

        def __exit__(self, *exc):
            for rp in reps:
                setattr(rp.module, rp.name, rp.real)

    return _Ctx()


def _row(what: str, times: tuple[dict, dict], main: str, mine: str) -> str:
    cells = []
    for kind in times:  # wall, then CPU
        med = {k: statistics.median(v) * 1e6 for k, v in kind.items()}
        best = {k: min(v) * 1e6 for k, v in kind.items()}
        cells.append(f"{med[main]:.1f} ({best[main]:.1f}) | {med[mine]:.1f} "
                     f"({best[mine]:.1f}) | {med[main] / med[mine]:.2f}")
    return f"| {what} | {' | '.join(cells)} |"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=21)
    ap.add_argument("--block", type=int, default=100)
    ap.add_argument("--main", default="/work/main/src")
    args = ap.parse_args(argv)
    load0 = os.getloadavg()
    import_main(args.main)
    head = subprocess.run(["git", "-C", args.main, "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()
    here = Path(lcpbench.__file__).resolve().parent.parent
    trees = [Tree(f"main {head}", "lcpbench_main"), Tree(f"this tree ({here})", "lcpbench")]
    a, b = (t.first for t in trees)
    assert (a.converged, a.reason, a.outer_iterations) == (b.converged, b.reason,
                                                           b.outer_iterations)
    assert a.total_force == b.total_force, (a.total_force, b.total_force)
    main_l, mine_l = trees[0].label, trees[1].label
    rows = []
    for same, what in ((True, "the same scene again"), (False, "a new scene object")):
        rows.append(_row(f"real kernels, {what}", interleaved(trees, args.repeat,
                                                              args.block, same),
                         main_l, mine_l))
    with replaying(trees):
        for same, what in ((True, "the same scene again"), (False, "a new scene object")):
            rows.append(_row(f"kernels replayed (the Python alone), {what}",
                             interleaved(trees, args.repeat, args.block, same),
                             main_l, mine_l))
    load1 = os.getloadavg()
    print(f"### One default solve: {main_l} against this tree, interleaved\n")
    print(f"N = 140, θ = 150°, h = 3 mm, tol 1e-3; µs per solve (wall, CPU), median (best) of "
          f"{args.repeat} blocks of {args.block}; kernels served: "
          f"main {trees[0].served}, this tree {trees[1].served}; one BLAS thread; "
          f"load average {load0[0]:.2f} before, {load1[0]:.2f} after.\n")
    print("| what | main wall µs | this tree wall µs | main / this | main CPU µs | "
          "this tree CPU µs | main / this |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
