"""The Python around the compiled kernels (issue 19, targets 1 and 6), timed alone.

Each call of the solve kernel, of the judge kernel and of the line kernel
(``solve_many``'s, which writes into arrays: those are copied back) is first
recorded, then replayed: the same calls return the recorded outputs at once, so what is
left is the Python of ``lcpbench.solve`` / ``lcpbench.solve_many`` (checks,
chains, the wall-free test, the driver output, the verdict, the result),
whatever the kernels cost. The replayed run must give the recorded answers
(checked), so it took the same path. CPU time, best of ``repeat``.

    python benchmarks/python_overhead.py [--repeat 7]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse
import inspect
import time

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.grid import PAPER_GRID

SCENE = dict(theta=150.0, height=3.0, links=140)
TOL = 1e-3


def paper_scenes() -> list[ActuatorScene]:
    return [ActuatorScene(theta=t, height=h) for h in PAPER_GRID.height for t in PAPER_GRID.theta]


class _Replay:
    """A kernel function that records its outputs, then hands them back in order.

    ``fills``: the kernel writes into its arguments from this index on (the line
    kernel's output arrays): recorded as copies, copied back when replayed."""

    def __init__(self, module, name: str, fills: int | None = None):
        self.module, self.name, self.real = module, name, getattr(module, name)
        self.fills = fills
        self.calls: list = []
        self.next: int | None = None  # None: recording

    def __call__(self, *args):
        if self.next is None:
            out = self.real(*args)
            filled = [a.copy() for a in args[self.fills:]] if self.fills is not None else None
            self.calls.append((out, filled))
            return out
        out, filled = self.calls[self.next % len(self.calls)]
        for a, b in zip(args[self.fills:] if filled else (), filled or ()):
            a[...] = b
        self.next += 1
        return out


def _kernels():
    from lcpbench.model.judge import _kernel as judge_kernel
    from lcpbench.model.kernel_call import solve_kernel
    from lcpbench.studies.batch_line import _kernel as line_kernel

    return solve_kernel(), judge_kernel(), line_kernel()


def line_outputs(line_kernel) -> int:
    """The line kernel's first output argument (``batch_kernel.solve_line``'s ``o_code``)."""
    fn = getattr(line_kernel.solve_line, "py_func", line_kernel.solve_line)
    return list(inspect.signature(fn).parameters).index("o_code")


def replayed(fn, repeat: int, fresh) -> tuple[float, int]:
    """(best CPU seconds of ``fn(fresh())`` with the kernels replayed, kernel calls)."""
    solve_k, judge_k, line_k = _kernels()
    reps = [_Replay(solve_k, "solve_chain"), _Replay(judge_k, "judge_answer"),
            _Replay(line_k, "solve_line", fills=line_outputs(line_k))]
    for r in reps:
        setattr(r.module, r.name, r)
    try:
        expected = fn(fresh())  # recorded
        best = float("inf")
        for _ in range(repeat):
            for r in reps:
                r.next = 0
            arg = fresh()
            c0 = time.process_time()
            got = fn(arg)
            best = min(best, time.process_time() - c0)
            forces = [x.total_force for x in (got if isinstance(got, list) else [got])]
            want = [x.total_force for x in (expected if isinstance(expected, list)
                                            else [expected])]
            if forces != want:
                raise RuntimeError("the replayed run left the recorded path")
        return best, sum(len(r.calls) for r in reps)
    finally:
        for r in reps:
            setattr(r.module, r.name, r.real)


def measure(repeat: int = 7) -> dict:
    """Python per solve and per batch scene (µs, kernels replayed) and the real
    batch over fresh scene objects (scenes/s, CPU)."""
    scene = ActuatorScene(**SCENE)
    lcpbench.solve(scene)  # loads the kernels
    block = 200

    def solves(scenes):
        return [lcpbench.solve(s, tol=TOL) for s in scenes][-1]

    same, _ = replayed(solves, repeat, lambda: [scene] * block)
    fresh, _ = replayed(solves, repeat, lambda: [ActuatorScene(**SCENE) for _ in range(block)])
    # new scene objects that differ (the paper grid): nothing shared between them but N
    grid, _ = replayed(solves, repeat, paper_scenes)
    batch, calls = replayed(lambda s: lcpbench.solve_many(s, tol=TOL), repeat, paper_scenes)
    real = []
    for _ in range(repeat):
        scenes = paper_scenes()  # new objects: no chain kept from an earlier run
        c0 = time.process_time()
        lcpbench.solve_many(scenes, tol=TOL)
        real.append(time.process_time() - c0)
    n = len(paper_scenes())
    return {"solve_same_scene_us": same / block * 1e6, "solve_fresh_scene_us": fresh / block * 1e6,
            "solve_paper_scenes_us": grid / len(paper_scenes()) * 1e6,
            "batch_per_scene_us": batch / n * 1e6, "batch_kernel_calls": calls,
            "batch_fresh_scenes_per_cpu_s": n / min(real), "repeat": repeat,
            "load_average": list(os.getloadavg())}


def markdown(res: dict) -> list[str]:
    return ["### The Python around the kernels (kernels replayed; CPU, best of "
            f"{res['repeat']})", "",
            "| what | µs |", "|---|---|",
            f"| `lcpbench.solve`, the same scene again (its chain kept) | "
            f"{res['solve_same_scene_us']:.1f} |",
            f"| `lcpbench.solve`, a new scene object each call (scene not counted) | "
            f"{res['solve_fresh_scene_us']:.1f} |",
            f"| `lcpbench.solve`, each of the 108 paper scenes, new objects (scene not "
            f"counted) | {res['solve_paper_scenes_us']:.1f} |",
            f"| `solve_many`, 108 paper scenes, per scene ({res['batch_kernel_calls']} kernel "
            f"calls) | {res['batch_per_scene_us']:.1f} |", "",
            f"`solve_many` over new scene objects with the real kernels: "
            f"{res['batch_fresh_scenes_per_cpu_s']:.0f} scenes per CPU second.", ""]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    res = measure(ap.parse_args(argv).repeat)
    print("\n".join(markdown(res)))
    print(f"load average {res['load_average']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
