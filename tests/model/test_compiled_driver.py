"""The driver around any back-end with lcpbench's parts compiled (model/compiled_driver.py).

The kernel of the judge's residuals (model/driver_kernel.py) is checked against the numpy
reference it stands for, then whole solves, for an LCP and QP back-ends, on the
actuator with nodes that cannot reach the wall (condensed out of the LCP), the two-wall
channel and the cantilever: every converged answer is the scene's equilibrium by an
oracle that shares no code with the driver (tests/energy_oracle.py).
"""

from dataclasses import fields

import numpy as np
import pytest
from energy_oracle import assert_solved

from lcpbench import ActuatorScene, CantileverScene, solve
from lcpbench.model import compiled_driver
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.step import ContactStep
from lcpbench.model.step_solver import make_step_solver, step_lcp, step_residuals
from lcpbench.problems.walls import WallProfile
from lcpbench.solvers.registry import get_backend

SCENES = {
    "actuator": ActuatorScene(theta=150.0, height=3.0, links=30),
    "channel": ActuatorScene(theta=160.0, height=2.0, links=24, channel=True),
    "cantilever": CantileverScene(links=20),
}


def _steps(scene):
    """The kernel's step at a bent, not-at-rest configuration, and the same step as a
    plain ContactStep (its forms and residuals by the numpy methods, no kernel hooks)."""
    chain = scene.chain()
    alpha = chain.rest_alpha * 0.9 + 0.01 * np.sin(np.arange(chain.links))
    step = assemble_step(chain, alpha)
    ref = ContactStep(**{f.name: getattr(step, f.name) for f in fields(ContactStep)})
    return chain, ref, step


@pytest.mark.parametrize("name", SCENES)
def test_kernel_residuals_match_the_numpy_reference(name):
    """Route against route: the kernel's residuals of a step answer (lcpbench's
    residuals of the heights of an LCP answer) against step_residuals' numpy reference on
    the same step (which Newton steps use); they have no oracle of their own (the step
    itself is checked against the paper's equations and finite differences of the exact
    energy in tests/model/test_assembly.py, and the whole solves below against the
    energy oracle)."""
    chain, ref, step = _steps(SCENES[name])
    fb, *_ = step_lcp(step)
    assert name == "cantilever" or fb.condense.size  # (the actuator condenses nodes out)
    zeta = np.abs(np.random.default_rng(1).normal(size=fb.q.size)) * 0.1
    ua = step.from_lcp(fb, zeta)
    (ra, Ra), (rb, Rb) = step_residuals(ref, ua), step_residuals(step, ua)
    assert ra.keys() <= rb.keys()
    for key, value in ra.items():
        assert np.isclose(value, rb[key], rtol=1e-9, atol=1e-12), key
    assert np.allclose(Ra, Rb, rtol=1e-9, atol=1e-9 * np.max(np.abs(Ra)))
    # heights that are not finite: the reference's answer (no residuals to speak of)
    bad = ua.copy()
    bad[0] = np.nan
    assert step_residuals(step, bad)[0]["natural"] == np.inf


# Lemke: an LCP back-end, exact pivoting; Clarabel and OSQP: QP back-ends (OSQP
# warm-started from the last step). The oracle: the scene's equilibrium from first
# principles (tests/energy_oracle.py), which shares no code with the driver.
@pytest.mark.parametrize("backend", ["lemke", "clarabel", "osqp"])
@pytest.mark.parametrize("name", SCENES)
def test_solve_reaches_the_equilibrium(backend, name):
    if not get_backend(backend).available():
        pytest.skip(f"{backend} not installed")
    scene = SCENES[name]
    fast = solve(scene, solver=backend, tol=1e-6, settings="high")
    assert fast.engine == compiled_driver.ENGINE
    assert fast.converged or name == "channel", fast.reason
    if fast.converged:  # (interior-point and ADMM answers: signs to 1e-6 F₀)
        assert_solved(fast, stationarity=1e-5, sign_tol=1e-6)


def test_an_iterative_lcp_back_end_with_a_warm_start():
    scene = ActuatorScene(theta=150.0, height=3.0, links=12)
    fast = solve(scene, solver="pgs", tol=1e-4)
    assert fast.engine == compiled_driver.ENGINE and fast.converged, fast.reason
    assert_solved(fast, sign_tol=1e-6)  # (an iterative back-end: signs to 1e-6 F₀)


def test_where_it_applies():
    chain = SCENES["actuator"].chain()
    lemke = make_step_solver("lemke")
    assert compiled_driver.takes(chain, lemke, "globalised")
    assert compiled_driver.takes(chain, lemke, "newton")
    assert compiled_driver.takes(chain, make_step_solver("lemke", scaled=False),
                                 "globalised")  # the forms in the problem's units
    assert not compiled_driver.takes(chain, make_step_solver("active-set"), "globalised")
    soft = ActuatorScene(theta=150.0, height=3.0, links=30, wall_stiffness=10.0).chain()
    assert compiled_driver.takes(soft, lemke, "globalised")  # elastic walls: a parameter
    assert compiled_driver.takes(chain, lemke, "undamped")  # any back-end, the default's too
    assert compiled_driver.takes(chain, make_step_solver("active-set"), "undamped")
    bump = WallProfile.from_table([0, 10, 14, 18, 30], [3.0, 3.0, 2.4, 3.0, 3.0])
    profiled = ActuatorScene(theta=150.0, links=30, wall_profile=bump).chain()
    assert compiled_driver.takes(profiled, lemke, "globalised")  # profiles: a parameter
    assert compiled_driver.takes(profiled, make_step_solver("active-set"), "newton")
    assert not compiled_driver.takes(profiled, make_step_solver("active-set"), "globalised")


@pytest.mark.parametrize("name", ["actuator", "channel"])
def test_newton_steps_with_another_back_end_reach_the_equilibrium(name):
    """method="newton" with another back-end: the exact Hessian H + T near the answer
    (model/newton.py) in the compiled driver; the answer is the scene's equilibrium by
    the energy oracle, and the last steps are full."""
    res = solve(SCENES[name], solver="lemke", method="newton", tol=1e-10)
    assert res.engine == compiled_driver.ENGINE and res.converged, res.reason
    assert res.steps[-1].step_length == 1.0
    assert_solved(res)


@pytest.mark.parametrize("solver", ["lemke", "active-set"])
@pytest.mark.parametrize("name", ["actuator", "channel"])
def test_the_undamped_scheme_reaches_the_equilibrium(name, solver):
    """The paper's undamped scheme (α ← α̂ after every step) as an option of the compiled
    driver: where it converges its answer is the scene's equilibrium by the energy
    oracle, in full steps."""
    res = solve(SCENES[name], solver=solver, method="undamped", tol=1e-9)
    assert res.engine == compiled_driver.ENGINE and res.converged, res.reason
    assert all(s.step_length == 1.0 for s in res.steps)
    assert_solved(res)


def test_the_undamped_scheme_stops_where_a_link_passes_the_vertical():
    """θ = 180° against a wall 0.6 mm away: full Gauss–Newton steps push a link past the
    vertical, where eq. (20)'s 1/cos α is singular; the answer is refused, not wrong."""
    res = solve(ActuatorScene(theta=180, height=0.6, links=140), solver="lemke",
                method="undamped")
    assert res.engine == compiled_driver.ENGINE
    assert not res.converged and "vertical" in res.reason

