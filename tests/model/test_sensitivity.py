"""Sensitivities by implicit differentiation (model/sensitivity.py, issue 38 item 1).

Oracles: central differences of converged solves (each parameter moved up and
down, solved to tol 1e-12 or 1e-11 from the answer; the differences' own error,
O(δ²) and the solves' round-off over δ, is what the tolerances allow), and
dimensional analysis (a force is (EI/ℓ²) Φ(θ, h/ℓ, wℓ³/EI, kℓ⁴/EI), so
EI ∂F/∂EI = F − w F_w − k F_k exactly for the discrete chain).
"""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene, SectionedScene
from lcpbench.errors import ProblemError
from lcpbench.model.sensitivity import sensitivities

ATTR = {"theta_deg": "theta", "height_mm": "height", "EI": "EI", "weight": "weight",
        "length_mm": "length", "wall_stiffness": "wall_stiffness"}
#: relative step of the central differences (larger where the force moves little)
STEP = {"weight": 1e-3, "wall_stiffness": 1e-3}

SCENES = [
    pytest.param(ActuatorScene(theta=150, height=3.0, links=140), 1e-12, id="paper"),
    pytest.param(ActuatorScene(theta=150, height=1.0, links=140, channel=True), 1e-12,
                 id="channel"),
    pytest.param(ActuatorScene(theta=120, height=2.5, links=60), 1e-12, id="120-deg"),
    pytest.param(ActuatorScene(theta=150, height=3.0, links=140, wall_stiffness=0.5), 1e-11,
                 id="elastic"),
    pytest.param(ActuatorScene(theta=150, height=2.0, links=60, wall_stiffness=50.0,
                               channel=True), 1e-11, id="elastic-channel"),
]


def _central(scene, result, p, tol):
    attr = ATTR[p]
    v = getattr(scene, attr)
    h = STEP.get(p, 1e-5) * abs(v)
    start = None if p == "length_mm" else result  # (a start must have the same length)
    up = lcpbench.solve(dataclasses.replace(scene, **{attr: v + h}), tol=tol, start=start)
    dn = lcpbench.solve(dataclasses.replace(scene, **{attr: v - h}), tol=tol, start=start)
    assert up.converged and dn.converged, (up.reason, dn.reason)
    return up, dn, 2 * h


@pytest.mark.parametrize("scene,tol", SCENES)
def test_total_force_derivatives_are_the_central_differences(scene, tol):
    res = lcpbench.solve(scene, tol=tol)
    assert res.converged, res.reason
    sens = sensitivities(res)
    assert set(sens.wrt) == set(ATTR) - (set() if scene.wall_stiffness < np.inf
                                         else {"wall_stiffness"})
    assert sens.one_sided.size == 0  # a stable contact set: every derivative exact
    for p in sens.wrt:
        up, dn, span = _central(scene, res, p, tol)
        fd = (up.total_force - dn.total_force) / span
        assert sens.total_force[p] == pytest.approx(fd, rel=2e-5), p


@pytest.mark.parametrize("scene,tol", SCENES[:1] + SCENES[3:4])
def test_node_forces_and_heights_follow_the_central_differences(scene, tol):
    res = lcpbench.solve(scene, tol=tol)
    sens = sensitivities(res, wrt=("theta_deg", "height_mm"))
    free = scene.chain().free_nodes
    for p in sens.wrt:
        up, dn, span = _central(scene, res, p, tol)
        dF = (up.forces - dn.forces) / span
        dy = (np.asarray(up.y)[free] - np.asarray(dn.y)[free]) / span
        assert np.max(np.abs(sens.forces[p] - dF)) <= 1e-4 * np.max(np.abs(dF))
        assert np.max(np.abs(sens.heights[p] - dy)) <= 1e-5 * np.max(np.abs(dy))


@pytest.mark.parametrize("scene,tol", [SCENES[0], SCENES[3]])
def test_the_EI_derivative_satisfies_dimensional_analysis(scene, tol):
    """EI ∂F/∂EI = F − w ∂F/∂w − k ∂F/∂k: the EI derivative (from ∂k_joint/∂EI) and the
    weight and wall derivatives (from the loads and the springs) are computed apart."""
    res = lcpbench.solve(scene, tol=tol)
    s = sensitivities(res)
    k = scene.wall_stiffness
    rhs = res.total_force - scene.weight * s.total_force["weight"] - (
        k * s.total_force["wall_stiffness"] if k < np.inf else 0.0)
    assert scene.EI * s.total_force["EI"] == pytest.approx(rhs, rel=1e-9)


def _rows_moved(scene, p, d):
    """``scene`` (a row of sections) with parameter ``p`` moved by ``d``: θ, EI or w of
    one section, the wall height, or every section's length scaled (ℓ by d)."""
    secs = list(scene.sections)
    if p == "height_mm":
        return dataclasses.replace(scene, height=scene.height + d)
    if p == "length_mm":
        f = 1 + d / scene.length
        return dataclasses.replace(scene, length=None, sections=[
            dataclasses.replace(s, length=s.length * f) for s in secs])
    name, k = p.split("[")
    k, attr = int(k[:-1]), {"theta_deg": "theta", "EI": "EI", "weight": "weight"}[name]
    secs[k] = dataclasses.replace(secs[k], **{attr: getattr(secs[k], attr) + d})
    return dataclasses.replace(scene, sections=secs)


def _rows_value(scene, p):
    if p in ("height_mm", "length_mm"):
        return scene.height if p == "height_mm" else scene.length
    name, k = p.split("[")
    return getattr(scene.sections[int(k[:-1])],
                   {"theta_deg": "theta", "EI": "EI", "weight": "weight"}[name])


ROWS = [
    pytest.param(SectionedScene(sections=[(150.0, 15.0, 30.0), (120.0, 15.0, 40.0, 5e-4)],
                                height=2.0, links=60), id="two-sections-one-wall"),
    pytest.param(SectionedScene(sections=[(150.0, 15.0), (-150.0, 15.0)], height=1.0,
                                links=80, channel=True), id="s-shape-channel"),
    pytest.param(SectionedScene(sections=[(100.0, 10.0, 20.0), (160.0, 10.0), (90.0, 10.0,
                                                                             50.0)],
                                height=2.5, links=60, channel=True), id="three-sections"),
]


@pytest.mark.parametrize("scene", ROWS)
def test_rows_of_sections_follow_the_central_differences(scene):
    """Every parameter of a row (θ, EI, w per section; h; all lengths scaled): the total
    force, the per-node forces on both walls and the heights against central differences
    of independent solves at tol 1e-12 (relative step 1e-5; 1e-3 for a weight)."""
    res = lcpbench.solve(scene, tol=1e-12)
    assert res.converged, res.reason
    s = sensitivities(res)
    assert s.one_sided.size == 0
    free = scene.chain().free_nodes
    lower = (lambda r: r.forces_lower) if scene.channel else (lambda r: np.zeros_like(r.forces))
    for p in s.wrt:
        d = (1e-3 if p.startswith("weight") else 1e-5) * abs(_rows_value(scene, p))
        start = None if p == "length_mm" else res
        up = lcpbench.solve(_rows_moved(scene, p, d), tol=1e-12, start=start)
        dn = lcpbench.solve(_rows_moved(scene, p, -d), tol=1e-12, start=start)
        assert up.converged and dn.converged
        fd = (up.total_force - dn.total_force) / (2 * d)
        assert s.total_force[p] == pytest.approx(fd, rel=1e-6, abs=1e-9 * res.total_force), p
        dF = (up.forces - dn.forces) / (2 * d)
        dL = (lower(up) - lower(dn)) / (2 * d)
        dy = (np.asarray(up.y)[free] - np.asarray(dn.y)[free]) / (2 * d)
        scale = max(np.max(np.abs(dF)), np.max(np.abs(dL)))
        assert np.max(np.abs(s.forces[p] - dF)) <= 1e-5 * scale, p
        if scene.channel:
            assert np.max(np.abs(s.forces_lower[p] - dL)) <= 1e-5 * scale, p
        assert np.max(np.abs(s.heights[p] - dy)) <= 1e-5 * np.max(np.abs(dy)), p


def test_one_section_row_is_the_actuator():
    """A row of one section is ActuatorScene's chain: the same derivatives by name.

    Route against route: the same chain by construction, so the same numbers are
    promised; each route's derivatives are checked against central differences in the
    tests above."""
    one = lcpbench.solve(SectionedScene(sections=[(150.0, 30.0)], height=3.0, links=60),
                         tol=1e-12)
    act = lcpbench.solve(ActuatorScene(theta=150, height=3.0, links=60), tol=1e-12)
    a, b = sensitivities(one), sensitivities(act)
    for row, flat in (("theta_deg[0]", "theta_deg"), ("EI[0]", "EI"), ("weight[0]", "weight"),
                      ("height_mm", "height_mm"), ("length_mm", "length_mm")):
        assert a.total_force[row] == pytest.approx(b.total_force[flat], rel=1e-9), row


def test_a_chain_off_the_wall_has_no_force_to_move():
    res = lcpbench.solve(ActuatorScene(theta=40, height=6.0, links=30), tol=1e-10)
    assert res.converged and res.total_force == 0.0
    s = sensitivities(res)
    assert all(v == 0.0 for v in s.total_force.values())


def test_refusals_name_the_problem():
    paper = lcpbench.solve(ActuatorScene(theta=150, height=3.0, links=40))
    with pytest.raises(ProblemError, match="wrt"):
        sensitivities(paper, wrt=("pressure",))
    with pytest.raises(ProblemError, match="wrt"):
        sensitivities(paper, wrt=("wall_stiffness",))  # a rigid wall has none
    rows = lcpbench.solve(SectionedScene(sections=[(150.0, 15.0), (-150.0, 15.0)],
                                         height=3.0, links=40))
    with pytest.raises(ProblemError, match=r"theta_deg\[0\]"):
        sensitivities(rows, wrt=("theta_deg",))  # a row has one θ per section
    stopped = lcpbench.solve(ActuatorScene(theta=150, height=3.0, links=40), max_outer=1,
                             tol=1e-12)
    assert not stopped.converged
    with pytest.raises(ProblemError, match="converged"):
        sensitivities(stopped)


def test_the_cli_adds_them_to_the_json_for_a_row_of_sections():
    import json

    run = subprocess.run([sys.executable, "-m", "lcpbench.cli", "solve", "--theta", "150",
                          "--height", "3", "--links", "40", "--tol", "1e-10", "--json",
                          "--sensitivities"], capture_output=True, text=True, check=True)
    got = json.loads(run.stdout)["sensitivities"]
    assert set(got["total_force"]) == {"theta_deg", "height_mm", "EI", "weight", "length_mm"}
    assert got["units"]["height_mm"] == "mm"
    assert got["total_force"]["height_mm"] < 0  # a higher wall is pressed less
    run = subprocess.run([sys.executable, "-m", "lcpbench.cli", "solve", "--sections",
                          "150:15,-150:15", "--height", "1", "--channel", "--links", "40",
                          "--json", "--sensitivities"], capture_output=True, text=True,
                         check=True)
    got = json.loads(run.stdout)["sensitivities"]
    assert got["units"]["EI[1]"] == "N mm²" and got["units"]["theta_deg[0]"] == "deg"
    assert len(got["forces_lower"]["theta_deg[1]"]) == 39


def test_at_first_touch_the_derivative_is_one_sided_and_listed():
    """With the wall at the height of first touch (the free shape's apex, without
    weight), the apex node touches it without force: a change of contact set. Its
    derivative is taken with the node free, the side where the wall moves away: the
    one-sided difference upward (no force either side) is 0, and the node is listed;
    downward the wall presses the node, a different derivative."""
    import math

    theta, links = 150.0, 40
    a, t = 30.0 / links, math.radians(theta)
    apex = a / (2 * math.sin(t / (2 * links))) * (1 - math.cos(t / 2))  # the rest polygon
    scene = ActuatorScene(theta=theta, height=apex, links=links, weight=0.0)
    res = lcpbench.solve(scene, tol=1e-12)
    assert res.converged and res.total_force <= 1e-9
    s = sensitivities(res, wrt=("height_mm",))
    assert s.one_sided.size >= 1
    h = 1e-6 * apex
    up = lcpbench.solve(dataclasses.replace(scene, height=apex + h), tol=1e-12)
    down = lcpbench.solve(dataclasses.replace(scene, height=apex - h), tol=1e-12)
    assert s.total_force["height_mm"] == pytest.approx((up.total_force - res.total_force) / h,
                                                       abs=1e-6)
    assert (res.total_force - down.total_force) / h < -1e-3  # the other side presses


@pytest.mark.parametrize("links", [140, 560])
def test_the_cantilever_follows_its_closed_form(links):
    """Sec. III-G's cantilever, its tip on the wall: linear beam theory gives the tip
    reaction R = 3qL/8 − 3EIh/L³ (the free cantilever's tip deflection qL⁴/8EI less h,
    over the tip compliance L³/3EI), so dR/dEI = −3h/L³, dR/dq = 3L/8, dR/dh = −3EI/L³
    and dR/dL = 3q/8 + 9EIh/L⁴ exactly. With 8 < qL⁴/(EIh) < 72 only the tip touches
    (the propped beam's slope at the tip stays toward the wall); h/L = 3e-4 keeps the
    chain's geometric nonlinearity ~1e-7 relative, and the chain (the clamp's half-link
    spring 2EI/a) is second-order accurate: a relative error below 1/N² (0.5/N² seen)."""
    from lcpbench.problems.cantilever import CantileverScene

    L, EI, h = 30.0, 32.01, 0.01
    q = 20.0 * EI * h / L**4
    res = lcpbench.solve(CantileverScene(load=q, height=h, links=links), tol=1e-11)
    assert res.converged, res.reason
    assert np.count_nonzero(res.forces > 0) == 1 and res.forces[-1] > 0  # the tip alone
    s = sensitivities(res)
    theory = {"EI": -3 * h / L**3, "load": 3 * L / 8, "height_mm": -3 * EI / L**3,
              "length_mm": 3 * q / 8 + 9 * EI * h / L**4}
    assert set(s.total_force) == set(theory)
    for name, want in theory.items():
        assert s.total_force[name] == pytest.approx(want, rel=1.0 / links**2 + 1e-6), name
