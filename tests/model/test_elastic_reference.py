"""Elastic walls against an independent direct minimisation of the total energy.

The reference below shares no code with lcpbench's model: it writes the exact
energy of the Hencky chain pinned at both ends as a function of its interior
node heights y (each link's angle α_i = arcsin((y_{i+1} − y_i)/a), the right
pin sliding on y = 0), adds the Winkler walls' energy Σ ½ k a (y_i − h)₊²
(and (−h − y_i)₊² in a channel), and minimises it without constraints by
Newton's method (gradient by hand, the smooth part's Hessian by central
differences of it, the penalty's exactly) with a backtracking line search,
down to a gradient at round-off. Its wall forces are R_i = k a (y_i − h)₊.
lcpbench solves the same scenes through its linearised contact steps (the
LCP with compliance) and must give the same total force to 1e-6.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import lcpbench
from lcpbench.problems.scenes import ActuatorScene


def _parts(scene: ActuatorScene):
    n = int(scene.links)
    a = scene.length / n
    th = math.radians(scene.theta)
    ks = scene.EI / a
    return n, a, th, ks


def _angles(scene, u):
    n, a, _, _ = _parts(scene)
    y = np.concatenate(([0.0], u, [0.0]))
    s = np.diff(y) / a
    return y, np.arcsin(s), s


def reference_energy(scene: ActuatorScene, u: np.ndarray) -> float:
    n, a, th, ks = _parts(scene)
    y, al, _ = _angles(scene, u)
    phi = np.diff(al)
    load = -scene.weight * a  # per link, +y up, acting away from the wall
    centre = 0.5 * (y[:-1] + y[1:])
    k = scene.wall_stiffness * a
    pen = np.maximum(u - scene.height, 0.0) ** 2
    if scene.channel:
        pen = pen + np.maximum(-scene.height - u, 0.0) ** 2
    return 0.5 * ks * float(np.sum((phi + th / n) ** 2)) - load * float(centre.sum()) \
        + 0.5 * k * float(pen.sum())


def _smooth_gradient(scene, u):
    n, a, th, ks = _parts(scene)
    _, al, s = _angles(scene, u)
    m = ks * (np.diff(al) + th / n)  # joint moments, joints 0..n-2
    dE_dal = np.zeros(n)
    dE_dal[1:] += m
    dE_dal[:-1] -= m
    w = dE_dal / (a * np.sqrt(1.0 - s**2))  # dα_i/dy_{i+1} = +1/(a cos α_i)
    grad_y = np.zeros(n + 1)
    grad_y[1:] += w
    grad_y[:-1] -= w
    load = -scene.weight * a
    grad_y[1:-1] -= load  # −Σ P (y_i + y_{i+1})/2: each interior node is in two links
    return grad_y[1:-1]


def _penalty_gradient(scene, u):
    k = scene.wall_stiffness * scene.length / int(scene.links)
    g = k * np.maximum(u - scene.height, 0.0)
    if scene.channel:
        g -= k * np.maximum(-scene.height - u, 0.0)
    return g


def _penalty_curvature(scene, u):
    k = scene.wall_stiffness * scene.length / int(scene.links)
    on = u > scene.height
    if scene.channel:
        on |= u < -scene.height
    return k * on


def reference_minimiser(scene: ActuatorScene, max_iter: int = 200):
    """(node heights, total force of the upper wall, of the lower wall)."""
    n, a, th, _ = _parts(scene)
    rest = th / 2 - (np.arange(n) + 0.5) * th / n
    u = np.cumsum(a * np.sin(rest))[:-1]
    u = np.clip(u, -scene.height, scene.height)
    h_fd = 1e-6 * a
    for _ in range(max_iter):
        g = _smooth_gradient(scene, u) + _penalty_gradient(scene, u)
        H = np.empty((u.size, u.size))
        for j in range(u.size):
            e = np.zeros(u.size)
            e[j] = h_fd
            H[:, j] = (_smooth_gradient(scene, u + e) - _smooth_gradient(scene, u - e)) / (2 * h_fd)
        H = 0.5 * (H + H.T) + np.diag(_penalty_curvature(scene, u))
        d = np.linalg.solve(H, -g)
        E0, t = reference_energy(scene, u), 1.0
        while t > 1e-12:
            trial = u + t * d
            if np.all(np.abs(np.diff(np.concatenate(([0.0], trial, [0.0])))) < a) and \
                    reference_energy(scene, trial) <= E0 + 1e-4 * t * (g @ d) + 1e-15 * abs(E0):
                break
            t *= 0.5
        u = u + t * d
        if np.max(np.abs(d)) < 1e-13 * scene.length:
            break
    k = scene.wall_stiffness * a
    return u, k * float(np.sum(np.maximum(u - scene.height, 0.0))), \
        k * float(np.sum(np.maximum(-scene.height - u, 0.0)))


# 24 scenes: bend angle, wall height, Winkler k (N/mm per mm), channel, gravity
SCENES = [
    (150.0, 3.0, 0.01, False, True), (150.0, 3.0, 0.1, False, True),
    (150.0, 3.0, 1.0, False, True), (150.0, 3.0, 10.0, False, True),
    (150.0, 3.0, 100.0, False, True), (150.0, 3.0, 1e3, False, True),
    (120.0, 2.0, 0.05, False, True), (120.0, 2.0, 0.5, False, False),
    (120.0, 4.0, 2.0, False, True), (90.0, 1.5, 0.2, False, True),
    (90.0, 2.5, 5.0, False, False), (170.0, 4.5, 0.3, False, True),
    (170.0, 5.5, 3.0, False, True), (170.0, 6.5, 30.0, False, True),
    (180.0, 6.0, 0.1, False, True), (60.0, 1.0, 1.0, False, True),
    (150.0, 3.0, 0.1, True, True), (150.0, 3.0, 1.0, True, True),
    (150.0, 3.0, 10.0, True, False), (120.0, 2.0, 0.3, True, True),
    (170.0, 4.5, 2.0, True, True), (90.0, 1.5, 0.02, True, True),
    (150.0, 2.0, 0.02, False, True), (100.0, 3.0, 0.2, False, True),
]


def _scene(theta, h, k, channel, gravity, links=40):
    return ActuatorScene(theta=theta, height=h, links=links, wall_stiffness=k,
                         channel=channel, weight=2.45e-4 if gravity else 0.0)


@pytest.mark.parametrize("theta,h,k,channel,gravity", SCENES,
                         ids=[f"{t:g}deg-h{h:g}-k{k:g}{'-ch' if c else ''}{'' if g else '-nog'}"
                              for t, h, k, c, g in SCENES])
def test_elastic_walls_match_direct_energy_minimisation(theta, h, k, channel, gravity):
    scene = _scene(theta, h, k, channel, gravity)
    u_ref, F_ref, F_lo_ref = reference_minimiser(scene)
    # the reference is a minimum: its gradient vanishes to round-off of the torques
    g = _smooth_gradient(scene, u_ref) + _penalty_gradient(scene, u_ref)
    assert np.max(np.abs(g)) < 1e-9 * max(F_ref, scene.EI / scene.length**2)
    assert F_ref > 0.0, "every scene here touches its wall"
    res = lcpbench.solve(scene, tol=1e-10, max_outer=400)
    assert res.converged, res.reason
    F0 = max(F_ref, scene.EI / scene.length**2)
    assert abs(res.total_force - F_ref) <= 1e-6 * F0
    if channel:
        assert abs(float(np.sum(res.forces_lower)) - F_lo_ref) <= 1e-6 * F0
    # node heights and indentations agree too
    assert np.max(np.abs(res.y[1:-1] - u_ref)) <= 1e-6 * scene.height
    assert np.max(res.indentation) == pytest.approx(
        max(float(np.max(u_ref - h)), float(np.max(-h - u_ref)) if channel else 0.0),
        rel=1e-5, abs=1e-9)


@pytest.mark.parametrize("backend", ["lemke", "qpsolvers-highs"])  # an LCP and a QP
@pytest.mark.parametrize("theta,h,k,channel,gravity", [SCENES[0], SCENES[-1]])
def test_another_back_end_on_elastic_walls_matches_the_minimisation(theta, h, k, channel,
                                                                    gravity, backend):
    """Elastic walls with a back-end other than the default run the compiled driver (the
    springs a parameter of its assembly, judge and line search; the back-end given the
    step's elastic forms): its force is the direct minimisation's."""
    from lcpbench.model.compiled_driver import ENGINE
    from lcpbench.solvers.registry import available_backends

    if backend not in available_backends():
        pytest.skip(f"{backend} is not installed")
    scene = _scene(theta, h, k, channel, gravity)
    _, F_ref, F_lo_ref = reference_minimiser(scene)
    res = lcpbench.solve(scene, solver=backend, tol=1e-8, max_outer=400)
    assert res.converged, res.reason
    assert res.engine == ENGINE
    F0 = max(F_ref, scene.EI / scene.length**2)
    assert abs(res.total_force - F_ref) <= 1e-6 * F0
    if channel:
        assert abs(float(np.sum(res.forces_lower)) - F_lo_ref) <= 1e-6 * F0
