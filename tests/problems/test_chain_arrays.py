"""The chain a scene builds, array by array, against its definition (eqs. 2, 5, 12, 18).

The scenes build their chains from templates kept per (N, ℓ) and (N, ℓ, h, channel)
(:mod:`lcpbench.problems.templates`) and keep a few values derived from them
(:meth:`~lcpbench.problems.scenes.Chain.derived`). Each array is compared here with
its definition written out with numpy, and each kept value with the chain's own
property or the sum it stands for; a second scene of the same N and ℓ (the templates
reused) and an array written into (the chain's own copy) change nothing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lcpbench import ActuatorScene
from lcpbench.problems.sections import SectionedScene
from lcpbench.problems.walls import WallProfile

STENOSIS = WallProfile.from_table([0, 10, 14, 18, 30], [3.0, 3.0, 2.4, 3.0, 3.0])


def _defined(theta: float, h: float, n: int, length: float, EI: float, w: float,
             channel: bool) -> dict:
    """A pinned-pinned chain of N links over ℓ at bend angle θ (degrees), walls at ±h."""
    th, a = math.radians(theta), length / n
    k = np.arange(n)
    s = np.arange(1, n) * a  # arc length of the interior nodes 2..N
    can = np.minimum(s, length - s) >= h * (1 - 1e-12)
    return {
        "link_length": a,
        "rest_alpha": th / 2 - (k + 0.5) * th / n,  # the arc's tangents, eq. (2)
        "joint_stiffness": np.full(n - 1, EI / a),  # eq. (18)
        "joint_links": np.column_stack([k[:-1], k[1:]]),
        "rest_joint": np.full(n - 1, -th / n),
        "link_load": np.full(n, -w * a),  # μ = wℓ/N, away from the wall (eq. 5)
        "free_nodes": np.arange(1, n),
        "upper": np.where(can, h, np.inf),
        "lower": np.where(can, -h, -np.inf) if channel else np.full(n - 1, -np.inf),
        "force_scale": EI / length**2,
    }


def _kept_values_are_their_definitions(chain) -> None:
    d = chain.__dict__
    if "_nodal_load" in d:
        assert np.array_equal(d["_nodal_load"], chain.nodal_load)
    if "_total_load" in d:
        assert d["_total_load"] == float(np.sum(np.abs(chain.link_load)))


@pytest.mark.parametrize("kw", [
    dict(theta=150.0, height=3.0, links=140),
    dict(theta=97.3, height=2.1, links=33, EI=12.0, weight=0.01, length=41.3, channel=True),
    dict(theta=300.0, height=0.2, links=57, weight=0.0),
    dict(theta=np.float64(120), height=4, links=np.int64(80)),  # checked, normalised
])
def test_actuator_chain_is_its_definition(kw):
    for _ in range(2):  # the second scene: the same N and ℓ, templates reused
        scene = ActuatorScene(**kw)
        chain = scene.chain()
        want = _defined(float(scene.theta), scene.height, scene.links, scene.length,
                        scene.EI, scene.weight, scene.channel)
        for name, value in want.items():
            np.testing.assert_allclose(getattr(chain, name), value, rtol=4e-16, atol=0,
                                       err_msg=name)
        assert chain.upper_stiffness is None and chain.lower_stiffness is None
        _kept_values_are_their_definitions(chain)
        chain.upper[:] = -1.0  # the chain's own copy: no other chain sees it
        chain.joint_links[:] = 0


@pytest.mark.parametrize("channel", [False, True])
def test_elastic_walls_are_k_times_the_share_on_the_wall_rows(channel):
    n, k, h = 60, 250.0, 2.5
    chain = ActuatorScene(theta=150.0, height=h, links=n, wall_stiffness=k,
                          channel=channel).chain()
    a = 30.0 / n
    rows = np.isfinite(chain.upper)  # an interior node's share of wall length is a
    want = np.where(rows, k * a, np.inf)
    np.testing.assert_allclose(chain.upper_stiffness, want, rtol=1e-15)
    if channel:
        np.testing.assert_array_equal(chain.lower_stiffness, chain.upper_stiffness)
        assert chain.lower_stiffness is not chain.upper_stiffness
    else:
        assert chain.lower_stiffness is None


def test_a_profiled_wall_is_its_height_at_the_arcs_nodes():
    scene = ActuatorScene(theta=150.0, height=3.0, links=70, wall_profile=STENOSIS)
    chain = scene.chain()
    a = 30.0 / 70
    x = np.cumsum(a * np.cos(chain.rest_alpha))[:-1]  # nodes 2..N of the rest arc
    s = np.arange(1, 70) * a
    can = np.minimum(s, 30.0 - s) >= 2.4 * (1 - 1e-12)  # rows reaching the lowest point
    np.testing.assert_allclose(chain.upper, np.where(can, STENOSIS(x), np.inf), rtol=1e-15)
    assert np.all(chain.lower == -np.inf)


@pytest.mark.parametrize("gravity", ["-y", "+y"])
def test_sections_of_one_ei_and_weight_are_the_actuators_arrays(gravity):
    """Two sections of one EI and w: the stiffness and load arrays of the actuator's
    definition, the walls and joints of the pinned frame; the rest shape the joined arcs
    (checked in test_sections)."""
    scene = SectionedScene(sections=[(120.0, 15.0), (-120.0, 15.0)], height=2.0, links=80,
                           channel=True, gravity=gravity)
    chain = scene.chain()
    want = _defined(120.0, 2.0, 80, 30.0, scene.EI, scene.weight, True)
    sign = 1.0 if gravity == "-y" else -1.0
    for name in ("joint_stiffness", "joint_links", "free_nodes", "upper", "lower"):
        np.testing.assert_array_equal(getattr(chain, name), want[name], err_msg=name)
    np.testing.assert_array_equal(chain.link_load, sign * want["link_load"])
    _kept_values_are_their_definitions(chain)
    zero = SectionedScene(sections=[(60.0, 10.0, 5.0, 0.0), (60.0, 10.0, 5.0, -0.0)],
                          height=2.0, links=20).chain()
    assert np.array_equal(np.signbit(zero.link_load), np.repeat([True, False], 10))
    _kept_values_are_their_definitions(zero)
