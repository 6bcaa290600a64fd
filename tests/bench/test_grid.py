"""Grids of scenes and the range syntax of `lcpbench sweep`."""

import pytest

from lcpbench.bench.grid import PAPER_GRID, Grid, parse_range, scene_from_key, scene_key
from lcpbench.errors import ProblemError
from lcpbench.problems.scenes import ActuatorScene


@pytest.mark.parametrize(("text", "expected"), [
    ("10:180:10", tuple(float(t) for t in range(10, 181, 10))),  # stop included
    ("2:7:1", (2.0, 3.0, 4.0, 5.0, 6.0, 7.0)),
    ("2:7", (2.0, 3.0, 4.0, 5.0, 6.0, 7.0)),  # step 1 by default
    ("0.1:0.3:0.1", (0.1, 0.2, 0.3)),  # no float drift past the stop
    ("5:5:1", (5.0,)),
    ("2,3,5", (2.0, 3.0, 5.0)),
    ("3", (3.0,)),
    ("3,3,2", (3.0, 2.0)),  # repeats dropped, order kept
])
def test_ranges(text, expected):
    assert parse_range(text, "x") == pytest.approx(expected)


@pytest.mark.parametrize("text", ["10:5:1", "a:b", "1:2:0", "1:2:-1", "", "1:2:3:4", "nan",
                                  "1:inf:1", "x,1", "0:1e9:1e-3"])
def test_bad_ranges_name_the_parameter(text):
    with pytest.raises(ProblemError, match="theta"):
        parse_range(text, "theta")


def test_integer_ranges():
    assert parse_range("40:160:40", "links", integer=True) == (40, 80, 120, 160)
    with pytest.raises(ProblemError, match="links must be integers"):
        parse_range("40.5", "links", integer=True)


def test_paper_grid_is_the_papers():
    # Sec. IV / Fig. 8a: theta 10-180 by 10, h 2-7 mm by 1, N = 140
    assert len(PAPER_GRID) == 18 * 6
    scenes = PAPER_GRID.scenes()
    assert len(scenes) == 108
    assert {s.links for s in scenes} == {140}
    assert min(s.theta for s in scenes) == 10 and max(s.theta for s in scenes) == 180


def test_grid_product_and_validation():
    g = Grid(theta=(90.0, 150.0), height=(2.0, 3.0), links=(20, 40), EI=(10.0,))
    scenes = g.scenes()
    assert len(scenes) == len(g) == 8
    assert len({scene_key(s) for s in scenes}) == 8
    with pytest.raises(ProblemError, match="height"):
        Grid(theta=(90.0,), height=(-1.0,)).scenes()  # the scene's own check
    with pytest.raises(ProblemError, match="empty"):
        Grid(theta=(), height=(3.0,))


def test_scene_key_round_trip():
    s = ActuatorScene(theta=150.0, height=3.0, links=40, EI=15.18, weight=0.0, channel=True)
    assert scene_from_key(scene_key(s)) == s
    # the same scene from slightly different float text has the same key
    t = ActuatorScene(theta=0.1 + 0.2, height=3.0)
    u = ActuatorScene(theta=0.3, height=3.0)
    assert scene_key(t) == scene_key(u)
