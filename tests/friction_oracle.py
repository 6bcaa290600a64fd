"""Coulomb's law read off a frictional answer, node by node (issue 39): independent of
lcpbench's judge, from the answer's normal and tangential forces and slips only."""

import numpy as np


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
