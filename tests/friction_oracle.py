"""Coulomb's law read off a frictional answer, node by node (issue 39): independent of
lcpbench's judge, from the answer's normal and tangential forces and slips only."""

import numpy as np

import lcpbench
from lcpbench.model.friction_solvers import step_runner


def coulomb_holds(res, rtol=1e-9, slip=1e-6):
    """Coulomb's law read off each node (independent of the judge): a node slides when
    |s| > ``slip`` ℓ (a solved step leaves ~1e-8 ℓ on a sticking node's slip)."""
    N = res.forces + (res.forces_lower if res.forces_lower is not None else 0.0)
    mu_up, mu_lo = res.scene.wall_friction
    limit = mu_up * res.forces + (mu_lo * res.forces_lower if res.forces_lower is not None
                                  else 0.0)
    return coulomb_on(res.tangential_forces, res.slip, limit,
                      max(float(np.sum(N)), abs(res.pull)), slip * res.scene.length, rtol)


def coulomb_on(T, s, limit, F, slip_length, rtol):
    """Coulomb's law node by node for tangential forces ``T``, slips ``s`` and cone limits
    ``limit`` (μN), to ``rtol`` of the force scale ``F``: a node slides when |s| >
    ``slip_length``. Returns the sliding nodes."""
    assert np.all(np.abs(T) <= limit + rtol * F)
    sliding = np.abs(s) > slip_length
    assert np.all(np.abs(np.abs(T[sliding]) - limit[sliding]) <= rtol * F)
    assert np.all(T[sliding] * s[sliding] <= rtol * F * np.abs(s[sliding]))
    inside = np.abs(T) < limit - rtol * F
    assert np.all(np.abs(s[inside]) <= slip_length)
    return sliding


def frictionless_by_the_frictional_path(base, lcp, tol):
    """``base`` with μ = 0, a pin and a slider, solved from the rest arc by the frictional
    outer loop with the step solver ``lcp``, against lcpbench's frictionless solve of
    ``base`` (an independent route: no friction pairs, no warm start, no polish): forces
    per node to 1e-10 of the largest and α to 1e-10. Returns the frictional result."""
    from dataclasses import replace

    import lcpbench
    from lcpbench.model.friction_driver import FrictionState, solve_state
    from lcpbench.model.friction_result import build_result

    ref = lcpbench.solve(base, tol=tol)
    scene = replace(base, right_end="slider")
    chain = scene.chain()
    rest = FrictionState(chain.rest_alpha.copy())
    ans = solve_state(scene, rest, rest.positions(chain)[0], tol=tol, lcp=lcp)
    assert ans.converged, ans.reason
    res = build_result(scene, {}, ans, rest.positions(chain)[0], tol)
    scale = np.max(ref.forces)
    np.testing.assert_allclose(res.forces, ref.forces, rtol=0, atol=1e-10 * scale)
    if base.channel:
        np.testing.assert_allclose(res.forces_lower, ref.forces_lower, rtol=0,
                                   atol=1e-10 * scale)
    np.testing.assert_allclose(res.alpha, ref.alpha, rtol=0, atol=1e-10)
    return res


def recorded(scene, states, tol=1e-8):
    """Every step of a path solved by Lemke's runner (the default's), with its answer:
    the steps a test hands to the exact oracle. ``tol`` None: ``solve_path``'s default."""
    steps, run = [], step_runner("lemke")

    def keep(fs):
        sol = run(fs)
        steps.append((fs, sol))
        return sol

    keep.takes_step, keep.newton = True, True
    res = lcpbench.solve_path(scene, states, tol=tol, lcp=keep)
    return res, steps
