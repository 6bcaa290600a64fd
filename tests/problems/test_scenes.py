"""Scenes validate their inputs and model only what they contain."""

import math

import numpy as np
import pytest

from lcpbench import ActuatorScene, CantileverScene, ProblemError
from lcpbench.errors import LcpbenchError


@pytest.mark.parametrize(
    "kwargs,name",
    [
        (dict(length=0), "length"), (dict(length=-3), "length"), (dict(EI=0), "EI"),
        (dict(EI=-1), "EI"), (dict(links=0), "links"), (dict(links=3), "links"),
        (dict(links=2.5), "links"), (dict(links="many"), "links"), (dict(theta=0), "theta"),
        (dict(theta=360), "theta"), (dict(theta=-10), "theta"), (dict(height=0), "height"),
        (dict(height=-1), "height"), (dict(height=math.nan), "height"),
        (dict(theta=math.inf), "theta"), (dict(weight=-1e-4), "weight"),
        (dict(weight=math.nan), "weight"), (dict(EI=math.inf), "EI"),
    ],
)
def test_bad_actuator_input_names_the_parameter(kwargs, name):
    with pytest.raises(ProblemError, match=name) as info:
        ActuatorScene(**kwargs)
    assert isinstance(info.value, LcpbenchError)


@pytest.mark.parametrize("kwargs,name", [(dict(load=-1), "load"), (dict(height=0), "height"),
                                         (dict(links="auto"), "links")])
def test_bad_cantilever_input(kwargs, name):
    with pytest.raises(ProblemError, match=name):
        CantileverScene(**kwargs)


def test_no_contact_rows_for_nodes_that_cannot_reach_the_wall():
    scene = ActuatorScene(height=3.0, links=100)  # a = 0.3 mm: nodes within 3 mm of a pin
    chain = scene.chain()
    s = chain.free_nodes * chain.link_length
    reach = np.minimum(s, scene.length - s)
    assert np.all(np.isinf(chain.upper[reach < 3.0 - 1e-9]))
    assert np.all(chain.upper[reach >= 3.0 - 1e-9] == 3.0)
    assert np.all(np.isinf(chain.lower))
    far = ActuatorScene(height=16.0, links=100).chain()  # beyond ℓ/2: no node can reach
    assert np.all(np.isinf(far.upper))


def test_gravity_off_means_no_load_terms():
    assert not np.any(ActuatorScene(weight=0).chain().link_load)
    mu = 2.45e-4 * 30 / 140  # eq. (5)
    assert np.allclose(ActuatorScene().chain().link_load, -mu)


def test_unconstrained_arc_geometry():
    sc = ActuatorScene(theta=180)
    assert sc.radius == pytest.approx(30 / math.pi)
    assert sc.arc_height == pytest.approx(30 / math.pi)
