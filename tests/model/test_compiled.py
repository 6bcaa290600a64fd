"""The compiled kernel (model/compiled_kernel.py) against independent oracles.

The answers are checked against quantities the kernel does not compute: the
equilibrium from first principles (forward kinematics, walls, signs, complementarity,
and stationarity by central differences of the exact energy: tests/energy_oracle.py),
the exact-geometry certificate (statics), beam theory for the cantilever, and the
symmetry of a symmetric scene. (The numpy reference engine these tests once compared
the kernel with, route against route, was removed.)
"""

import os
import subprocess
import sys

import numpy as np
import pytest
from energy_oracle import assert_solved
from hypothesis import given, settings
from hypothesis import strategies as st
from known_answers import CANTILEVER_THEORY_FORCE, PAPER_SCENE

from lcpbench import ActuatorScene, CantileverScene, ProblemError, solve
from lcpbench.api import solve_internal
from lcpbench.bench.grid import hard_scenes
from lcpbench.model.angle_step import heavy


def compiled(scene, **kw):
    """The solve, and whether the kernel must have run it (contact, not heavy)."""
    res = solve_internal(scene, engine="auto", **kw)
    ran = res.outer_iterations > 0 and "no contact" not in res.reason \
        and not heavy(scene.chain())
    return res, ran


def assert_certified(res, tol, *, oracle_links=500):
    """The exact-geometry certificate, independent of the kernel (model/result.py), and
    the equilibrium by central differences of the exact energy (tests/energy_oracle.py;
    up to ``oracle_links`` links: N differences of N-link energies cost ~N²)."""
    c = res.certificate
    assert res.converged, res.reason
    assert c.min_gap >= -1e-9 and c.min_force >= 0 and c.closure <= 1e-9
    assert c.relative_torque_residual <= max(10 * tol, 1e-6)
    if res.scene.links <= oracle_links:
        assert_solved(res, stationarity=max(10 * tol, 1e-6))


@pytest.mark.parametrize("scene", hard_scenes(), ids=lambda s: f"{s.theta:g}-{s.height:.3g}-"
                         f"{s.links}-{s.weight:g}-{s.EI:g}-{'ch' if s.channel else ''}")
@pytest.mark.parametrize("tol", [1e-3, 1e-8])
def test_hard_suite_is_certified(scene, tol):
    fast, ran = compiled(scene, tol=tol)
    # a heavy chain (wℓ³/EI >= 40) is solved by steps in the link angles, in numpy
    assert fast.engine == "compiled" or not ran
    # (N = 2000 by the energy oracle at the tight tol only: ~6 s a scene)
    assert_certified(fast, tol, oracle_links=10**4 if tol < 1e-6 else 500)


@pytest.mark.parametrize("scene", hard_scenes(), ids=lambda s: f"{s.theta:g}-{s.height:.3g}-"
                         f"{s.links}-{s.weight:g}-{s.EI:g}-{'ch' if s.channel else ''}")
def test_newton_in_the_kernel_is_certified(scene):
    """method="newton": H + T where positive definite from max|Δα| < NEWTON_SWITCH."""
    fast, ran = compiled(scene, tol=1e-8, method="newton")
    assert fast.engine == "compiled" or not ran
    assert_certified(fast, 1e-8)


def test_paper_scene_channel_and_cantilever_run_compiled():
    # wℓ³/EI = 34, below the steps in the link angles (model/angle_step.HEAVY = 40)
    heavy_channel = ActuatorScene(theta=60, height=0.3, channel=True, weight=0.04)
    for scene in (ActuatorScene(**PAPER_SCENE), ActuatorScene(theta=180, height=1.0, channel=True),
                  heavy_channel, CantileverScene()):
        fast, _ = compiled(scene, tol=1e-8)
        assert fast.engine == "compiled"
        assert_certified(fast, 1e-8)
    # the heavy chain lies on the lower wall of the channel, not on the upper one
    assert fast.forces_lower is None  # (the cantilever has no lower wall)
    channel = solve(heavy_channel, tol=1e-8)
    assert channel.total_force == 0 and channel.forces_lower.sum() > 0


def test_cantilever_tip_force_is_beam_theory():
    """Eqs. (34)-(37): the reaction of the wall on the tip at the paper's load."""
    res = solve(CantileverScene(), tol=1e-8)
    assert res.engine == "compiled"
    assert res.total_force == pytest.approx(CANTILEVER_THEORY_FORCE, rel=2e-2)
    assert np.argmax(res.forces) == res.forces.size - 1  # the tip carries it


def test_symmetric_scene_has_a_symmetric_answer():
    """Weightless, so the scene is symmetric about mid-span: so are the forces."""
    res = solve(ActuatorScene(theta=170, height=2.0, links=120, weight=0.0), tol=1e-10)
    assert res.engine == "compiled"
    f = res.forces
    assert np.max(np.abs(f - f[::-1])) <= 1e-9 * f.sum()


#: Heaviness wℓ³/EI of the random chains: weightless, the paper's (0.2) and 100x it.
#: Heavier chains crawl for up to 200 outer iterations of backtracking (issue 19,
#: target 8), a path that round-off decides, so they are not compared here.
HEAVINESS = [0.0, 0.2, 20.0]


@st.composite
def actuators(draw):
    EI = draw(st.sampled_from([1.0, 32.01, 500.0]))
    return ActuatorScene(theta=draw(st.floats(30, 180)), height=draw(st.floats(0.5, 8.0)),
                         links=draw(st.integers(8, 300)), EI=EI,
                         weight=draw(st.sampled_from(HEAVINESS)) * EI / 30.0**3,
                         channel=draw(st.booleans()))


cantilevers = st.builds(
    CantileverScene,
    load=st.floats(1e-4, 5e-2),
    height=st.floats(0.2, 3.0),
    links=st.integers(8, 300),
)


@settings(max_examples=40, deadline=None)
@given(scene=st.one_of(actuators(), cantilevers), tol=st.sampled_from([1e-3, 1e-8]))
def test_random_scenes_are_certified(scene, tol):
    fast, ran = compiled(scene, tol=tol)
    assert fast.engine == "compiled" or not ran
    if fast.converged:
        assert_certified(fast, tol)
    else:  # never silently: a reason, and no force error bound that claims accuracy
        assert fast.reason and fast.reason != "converged"


def test_continuation_start_is_certified_and_helps():
    a = ActuatorScene(theta=150, height=3.0, links=140)
    b = ActuatorScene(theta=152, height=3.0, links=140)
    fast = solve(b, start=solve(a), tol=1e-8)
    assert fast.engine == "compiled"
    assert_certified(fast, 1e-8)
    assert fast.outer_iterations < solve(b, tol=1e-8).outer_iterations  # the start helped
    # Newton: a warm start's first step is a Newton step
    fast = solve(b, start=solve(a), tol=1e-8, method="newton")
    assert fast.engine == "compiled"
    assert_certified(fast, 1e-8)


def test_a_kernel_stop_falls_back_to_the_compiled_driver():
    """A weightless chain pressed flat (h = 1 mm, N = 100, tol 1e-9): the kernel's dual
    walk meets a repeated working set (round-off) and stops; the compiled driver takes
    the solve over with the default back-end's step solver (the primal safeguard, then
    the dense Lemke step), and its answer is the equilibrium."""
    scene = ActuatorScene(theta=150, height=1.0, links=100, weight=0.0)
    fast = solve(scene, tol=1e-9)
    assert fast.engine == ("compiled driver (the compiled kernel stopped: a working set "
                           "repeated (round-off))")
    assert_certified(fast, 1e-9)


def test_engine_argument():
    scene = ActuatorScene(theta=150, height=3.0, links=40)
    with pytest.raises(ProblemError, match="engine must be one of"):
        solve_internal(scene, engine="fast")
    from lcpbench.problems.walls import WallProfile

    bump = WallProfile.from_table([0, 10, 14, 18, 30], [3.0, 3.0, 2.4, 3.0, 3.0])
    assert solve_internal(ActuatorScene(theta=150, links=40, wall_profile=bump),
                          solver="lemke", engine="compiled").engine == "compiled driver"
    assert solve_internal(scene, solver="lemke", method="newton",
                          engine="compiled").engine == "compiled driver"
    assert solve_internal(scene, method="undamped", engine="compiled").engine == \
        "compiled driver"  # the undamped scheme: an option of the compiled driver
    assert solve_internal(scene, engine="compiled").engine == "compiled"
    # another back-end: the driver around it compiled (model.compiled_driver)
    assert solve_internal(scene, solver="lemke", engine="compiled").engine == "compiled driver"
    assert solve(scene, solver="lemke").engine == "compiled driver"
    with pytest.raises(ProblemError, match="engine='numpy' was removed"):
        solve_internal(scene, solver="lemke", engine="numpy")
    assert solve_internal(scene, engine="compiled", method="newton").engine == "compiled"


def test_import_does_not_load_numba_and_the_first_solve_does():
    """With the JIT kernels (``LCPBENCH_AOT=0``; the ahead-of-time kernels load no
    numba at all: tests/model/test_aot.py)."""
    code = ("import sys, lcpbench; a = 'numba' in sys.modules; "
            "r = lcpbench.solve(lcpbench.ActuatorScene(links=20)); "
            "print(a, 'numba' in sys.modules, r.engine)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env={**os.environ, "LCPBENCH_AOT": "0"}).stdout.split()
    assert out == ["False", "True", "compiled"]
