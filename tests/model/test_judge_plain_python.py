"""The result judge as plain Python (``NUMBA_DISABLE_JIT=1``, the debugging path), where its
kernel chooses the formulation of its steps at run time (judge_kernel.judge_step), and the
judge kernel compiled, where each entry holds one formulation's steps.

Plain Python: in a fresh interpreter, the large-N driver's answer to a scene (N = 24; one
wall and a channel) is judged in node heights, and on the chain marked ``increments`` in
increments: converged both times, its total force that of the energy minimisation (the
oracle, run here), the same answer with its reactions scaled by 5 % refused both times,
and no numpy warning on the way.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from energy_oracle import energy_minimum, force_unit

from lcpbench import ActuatorScene

PLAIN = r"""
import json, sys
from dataclasses import replace
import numpy as np
from lcpbench import ActuatorScene
from lcpbench.model.judge import judge, judged_in
from lcpbench.model.large_driver import run_large
from lcpbench.model.step_solver import make_step_solver

out = {}
for name, channel, increments in (("heights", False, False), ("increments", False, True),
                                  ("heights channel", True, False),
                                  ("increments channel", True, True)):
    chain = ActuatorScene(150, 3.0, links=24, channel=channel).chain()
    if increments:
        chain = replace(chain, increments=True)
    d = run_large(chain, make_step_solver("auto"), tol=1e-6)
    sizes = [s.max_dalpha for s in d.steps]
    statuses = [s.status for s in d.steps]

    def judged(fu, fl):
        return judge(chain, d.alpha, fu, fl, tol=1e-6, driver_converged=d.converged,
                     driver_reason=d.reason, step_statuses=statuses, step_sizes=sizes,
                     certificate=None)

    j = judged(d.forces_upper, d.forces_lower)
    bad = judged(1.05 * d.forces_upper, 1.05 * d.forces_lower)
    out[name] = {"converged": bool(j.converged), "force": float(np.sum(d.forces_upper)),
                 "scaled_converged": bool(bad.converged), "rounds": j.judge_rounds,
                 "judged_in": judged_in(chain)}
print(json.dumps(out))
"""


def test_the_judge_as_plain_python_accepts_the_equilibrium_and_refuses_a_defect():
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", OPENBLAS_NUM_THREADS="1")
    # (numpy's warnings are errors: the plain path warns of nothing the compiled one hides)
    run = subprocess.run([sys.executable, "-W", "error::RuntimeWarning", "-c", PLAIN],
                         capture_output=True, text=True, env=env, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    got = json.loads(run.stdout.strip().splitlines()[-1])
    for name in ("heights", "increments", "heights channel", "increments channel"):
        scene = ActuatorScene(150, 3.0, links=24, channel=name.endswith("channel"))
        ref = energy_minimum(scene).total_force
        assert got[name]["judged_in"] == name.split()[0]
        assert got[name]["converged"], name
        assert got[name]["rounds"] >= 1  # the judge's own step settled
        assert abs(got[name]["force"] - ref) <= 1e-6 * force_unit(scene, ref), name
        assert not got[name]["scaled_converged"], name  # reactions 5 % off: refused


COMPILE = r"""
import lcpbench
from lcpbench import ActuatorScene
from lcpbench.numba_cache import jit_module
from lcpbench.problems.walls import WallProfile

bump = WallProfile.from_table([0.0, 15.0, 30.0], [3.0, 2.5, 3.0])
for scene in (ActuatorScene(150, 3.0, links=40), ActuatorScene(150, links=40, wall_profile=bump)):
    assert lcpbench.solve(scene).judge == "heights"
heights = jit_module("lcpbench.model.judge_kernel")
steps = jit_module("lcpbench.model.judge_exact_kernel")
print(len(heights._pivot.signatures), len(steps.increments_step.signatures))
"""


@pytest.mark.slow
def test_a_judge_in_heights_compiles_no_step_in_increments(tmp_path):
    # each entry of the judge kernel holds one formulation's steps: compiled from an empty
    # cache, the judges in heights (flat walls, judge_answer; a profile, judge_walls)
    # compile the heights pivots and never the step in increments (a run-time flag had
    # made them compile it too: +27 s on a cold first profile solve)
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path), LCPBENCH_AOT="0",
               OPENBLAS_NUM_THREADS="1")
    env.pop("NUMBA_DISABLE_JIT", None)
    run = subprocess.run([sys.executable, "-c", COMPILE], capture_output=True, text=True,
                         env=env, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    pivots, increments = map(int, run.stdout.split())
    assert pivots >= 1 and increments == 0
