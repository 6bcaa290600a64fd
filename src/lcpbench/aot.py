"""``lcpbench compile``: the kernels compiled ahead of time, for a fast first solve.

:func:`build` runs a few solves with numba's JIT (compiling the kernels into
numba's on-disk cache the first time, or loading them from it), so that every
kernel entry a solve calls from Python has been called with the argument types
it gets, then has :func:`lcpbench.numba_cache.build_aot` compile those entries,
with their dispatchers' signatures, into one extension module beside the cache
(``numba.pycc``; no numba at run time). A fresh process then runs its first
solve without importing numba (see :mod:`lcpbench.numba_cache`).

The solves: the paper's actuator (cold, and a continuation of three scenes,
which passes the warm-start arrays, in one line kernel call and scene by scene), its
channel, a cantilever, a loaded arc on its
wall (the wall-free search's first step), and a row of two
sections along its loading path (``start="ramp"``: the walk of height steps and the
SQP in the link angles), so the entries see the types of each kind of call the
kernels take.

    python -m lcpbench.aot [--dir DIR]     # or: lcpbench compile
"""

from __future__ import annotations

import argparse
import sys
import time

from . import numba_cache


def representative_solves() -> None:
    """The solves whose kernel calls give the signatures (see the module's docstring)."""
    from .api import solve
    from .problems.cantilever import CantileverScene
    from .problems.scenes import ActuatorScene
    from .problems.sections import SectionedScene
    from .studies.batch import solve_many
    from .studies.continuation import solve_sequence

    scene = ActuatorScene(theta=150, height=3.0)
    solve(scene)
    solve(ActuatorScene(theta=150, height=3.0, channel=True))
    solve(CantileverScene())
    # a loaded arc on the wall (h = 8 mm): the first step without walls decides whether
    # the load sags it off (model.wall_free_kernel.first_step_kind)
    solve(ActuatorScene(theta=150, height=8.0, links=40))
    solve_many([ActuatorScene(theta=t, height=3.0) for t in (140, 150, 160)])
    # a continuation scene by scene: Solved's predictions from Python
    # (model.predictor_kernel.predict_start; solve_many's lines call it compiled)
    solve_sequence([ActuatorScene(theta=t, height=3.0) for t in (140, 150, 160)])
    # the loading path: its height steps in one call (path_kernel.walk_heights), its
    # steps near the vertical by the SQP in the link angles (angle_kernel)
    solve(SectionedScene(sections=[(170.0, 15.0), (-170.0, 15.0)], height=2.0, links=140),
          start="ramp")


def build(out_dir: str | None = None) -> dict:
    """Build the AOT module of the current kernels (in ``out_dir``, default
    :func:`~lcpbench.numba_cache.aot_dir`); returns its manifest. This process runs
    the JIT kernels (an AOT module already loaded here is not used). Raises
    :class:`~lcpbench.numba_cache.AotBuildError` where it cannot build."""
    numba_cache.use_aot(False)  # the solves below must run the JIT dispatchers
    try:
        representative_solves()
    finally:
        numba_cache.use_aot(None)  # the next kernel_module call looks for the new module
    return numba_cache.build_aot(out_dir)


def main(argv: list[str] | None = None) -> int:
    """``python -m lcpbench.aot``: build, one line of outcome; 1 where it could not."""
    ap = argparse.ArgumentParser(prog="lcpbench compile", description=__doc__.split("\n\n")[0])
    ap.add_argument("--dir", default=None, help="output directory (default: beside numba's "
                    "cache of the kernels, <cache>/lcpbench-numba/<sha>/aot-<machine>)")
    return run(ap.parse_args(argv).dir)


def run(out_dir: str | None) -> int:
    """Build and report in one line (stdout; stderr and status 1 on failure)."""
    t0 = time.perf_counter()
    try:
        info = build(out_dir)
    except numba_cache.AotBuildError as exc:
        print(f"lcpbench compile: no ahead-of-time module ({exc}); solves load the kernels "
              f"through numba's JIT cache, as before", file=sys.stderr)
        return 1
    where = out_dir or numba_cache.aot_dir()
    names = [f"{m.rsplit('.', 1)[-1]}.{f}" for m, spec in info["modules"].items()
             for f in spec["functions"]]
    print(f"compiled {', '.join(names)} for {info['cpu']} into {where} "
          f"in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
