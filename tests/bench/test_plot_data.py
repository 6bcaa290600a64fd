"""What the report's figures plot against what (issue 15, "pictures a scientist trusts").

The data behind each figure is checked, not its pixels: failed back-ends are
never given a made-up error, and scenes that differ in anything but θ are
never joined into one line.
"""

import json
import math

import numpy as np
import pytest

from lcpbench.bench.metrics import Evaluated
from lcpbench.bench.plot import (
    force_lines,
    indistinguishable,
    plot_forces,
    plot_shapes,
    plot_work_precision,
    shape_panels,
    work_precision_points,
)

pytest.importorskip("matplotlib")


def _scene(theta, height=3.0, EI=32.01, links=140):
    return json.dumps({"EI": EI, "channel": False, "height": height, "length": 30.0,
                       "links": links, "theta": theta, "weight": 2.45e-4}, sort_keys=True)


def _ref(theta, force, **kw):
    scene = _scene(theta, **kw)
    p = json.loads(scene)
    y = np.linspace(0, min(p["height"], 2.0), 5)
    return scene, {"scene": scene, "theta": theta, "height": p["height"], "converged": True,
                   "total_force": force, "x": np.linspace(0, 30, 5), "y": y}


def test_force_lines_join_only_scenes_equal_but_for_theta(tmp_path):
    # the hard suite's trap: two scenes at h = 3 mm with different EI, and N differs too
    refs = dict([_ref(150.0, 0.4), _ref(170.0, 0.5), _ref(180.0, 0.55),
                 _ref(150.0, 12.7, EI=1000.0), _ref(180.0, 1.1, height=0.6, links=2000)])
    lines, common = force_lines(refs)
    assert len(lines) == 3
    seen = set()
    for line in lines:
        assert line["thetas"] == sorted(line["thetas"])
        key = json.dumps(line["params"], sort_keys=True)
        assert key not in seen
        seen.add(key)
    by_label = {ln["label"]: ln for ln in lines}
    assert len(by_label) == 3  # no repeated legend entry
    main = by_label["h = 3 mm, N = 140, EI = 32.01 N·mm²"]
    assert main["thetas"] == [150.0, 170.0, 180.0]
    assert main["forces"] == pytest.approx([400.0, 500.0, 550.0])  # mN
    # the spike of the EI = 1000 scene stays on its own (a marker, not a line)
    assert by_label["h = 3 mm, N = 140, EI = 1000 N·mm²"]["thetas"] == [150.0]
    assert set(common) == {"length", "weight", "channel"}  # what the title may claim
    plot_forces(refs, [], tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 0


def _ev(backend, settings, scene, error, success, ms=1.0):
    row = {"backend": backend, "settings": settings, "method": "globalised", "scene": scene,
           "converged": success or math.isfinite(error), "wall_time": ms / 1e3, "tol": 1e-3}
    return Evaluated(row, error, success)


def test_work_precision_never_draws_a_failure_at_a_made_up_error(tmp_path):
    scenes = [_scene(t) for t in (10.0, 90.0, 150.0)]
    ev = [
        # PGS: converged only where there is no contact (error 0), failed on the others
        _ev("pgs", "default", scenes[0], 0.0, True, 2.0),
        _ev("pgs", "default", scenes[1], math.inf, False, 60e3),
        _ev("pgs", "default", scenes[2], math.inf, False, 60e3),
        # an exact back-end, with errors 1e-6, 2e-6, 4e-6 and times 3, 5, 9 ms
        *(_ev("exact", "default", s, e, True, t)
          for s, e, t in zip(scenes, (1e-6, 2e-6, 4e-6), (3.0, 5.0, 9.0))),
        *(_ev("exact", "high", s, e, True, t)
          for s, e, t in zip(scenes, (1e-12, 0.0, 3e-12), (6.0, 7.0, 8.0))),
    ]
    summary = [{"backend": "pgs", "settings": "default", "method": "globalised",
                "success": 1 / 3},
               {"backend": "exact", "settings": "default", "method": "globalised",
                "success": 1.0},
               {"backend": "exact", "settings": "high", "method": "globalised",
                "success": 1.0}]
    pts = work_precision_points(summary, ev, time_limit=60.0)
    (pgs,) = pts["pgs"]
    assert pgs["error"] == math.inf  # 2 of 3 failed: no median error, drawn as failed
    assert pgs["success"] == pytest.approx(1 / 3)
    # time: the report's score over every scene, shift 1 ms, the two failures at 60 s
    assert pgs["time"] == pytest.approx((3.0 * 60001.0 ** 2) ** (1 / 3) - 1)
    d, h = pts["exact"]
    assert (d["settings"], h["settings"]) == ("default", "high")  # line runs default -> high
    assert d["error"] == 2e-6 and d["time"] == pytest.approx((4 * 6 * 10) ** (1 / 3) - 1)
    assert h["error"] == 1e-12 and h["time"] == pytest.approx((7 * 8 * 9) ** (1 / 3) - 1)
    plot_work_precision(summary, ev, tmp_path / "wp.png")
    assert (tmp_path / "wp.png").stat().st_size > 0


def test_work_precision_merges_lines_that_cannot_be_told_apart():
    def pt(settings, error, time, success=1.0):
        return {"settings": settings, "error": error, "time": time, "success": success}

    pts = {
        "pgs": [pt("default", math.inf, 900.0, 0.38), pt("high", math.inf, 910.0, 0.38)],
        # 1 % off in time on one point: within 10^0.01 (2.3 %), the same line
        "psor": [pt("default", math.inf, 909.0, 0.38), pt("high", math.inf, 910.0, 0.38)],
        # 5 % off: a line of its own
        "sor-slow": [pt("default", math.inf, 945.0, 0.38), pt("high", math.inf, 910.0, 0.38)],
        # the same points but another success share: not the same
        "other": [pt("default", math.inf, 900.0, 0.40), pt("high", math.inf, 910.0, 0.38)],
        # a finite error against a failed one at the same time: not the same
        "exact": [pt("default", 1e-6, 900.0), pt("high", math.inf, 910.0, 0.38)],
    }
    groups = indistinguishable(pts)
    assert ["pgs", "psor"] in groups
    assert sorted(sum(groups, [])) == sorted(pts)  # every back-end once
    assert len(groups) == 4


def test_shapes_panels_keep_one_kind_of_scene(tmp_path):
    refs = dict([_ref(150.0, 0.4, height=h) for h in (2.0, 3.0)] + [_ref(90.0, 0.3)]
                + [_ref(150.0, 0.4, height=3.0, EI=1000.0)])
    shared, panels = shape_panels(refs)
    assert shared["EI"] == 32.01  # the EI = 1000 scene is left out, not mixed in
    (t_left, left, l_left), (t_right, right, l_right) = panels
    assert [r["height"] for r in left] == [2.0, 3.0] and {r["theta"] for r in left} == {150.0}
    assert l_left == ["h = 2 mm", "h = 3 mm"]  # with the unit
    assert {r["height"] for r in right} == {2.0} and "h = 2 mm" in t_right
    assert all(r["EI"] == 32.01 for r in (json.loads(x["scene"]) for x in left + right))
    plot_shapes(refs, tmp_path / "s.png")
    assert (tmp_path / "s.png").stat().st_size > 0


def test_reaction_arrows_group_neighbouring_nodes():
    from lcpbench.bench.plot import _nice, reaction_groups

    f = [0.0, 1.0, 3.0, 0.0, 0.0, 2.0, 0.0]
    x = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    a, b = reaction_groups(f, x)
    assert a["nodes"] == [1, 2] and a["force"] == 4.0 and a["x"] == pytest.approx(1.75)
    assert b["nodes"] == [5] and b["force"] == 2.0 and b["x"] == 5.0
    assert reaction_groups([0.0, 0.0], [0.0, 1.0]) == []
    # the scale bar: a round 1-2-5 value near half the largest arrow
    assert _nice(0.4022) == 0.2 and _nice(0.2011) == 0.1 and _nice(12.7) == 5.0


def test_solve_plot_arrows_carry_the_total(tmp_path):
    """Every contact node is in exactly one arrow, and the arrows add up to the total."""
    import lcpbench
    from lcpbench.bench.plot import plot_shape, reaction_groups

    res = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links=40))
    free = res.scene.chain().free_nodes
    groups = reaction_groups(res.forces, np.asarray(res.x)[free])
    nodes = [n for g in groups for n in g["nodes"]]
    assert sorted(nodes) == sorted(np.flatnonzero(np.asarray(res.forces) > 0).tolist())
    assert sum(g["force"] for g in groups) == pytest.approx(res.total_force, rel=1e-12)
    plot_shape(res, tmp_path / "s.png")
    assert (tmp_path / "s.png").stat().st_size > 0


def test_force_line_labels_tell_close_heights_apart():
    # the hard suite's grazing scenes: two heights equal to 6 digits
    refs = dict([_ref(120.0, 0.0, height=7.162037), _ref(120.0, 0.001, height=7.162045)])
    lines, _ = force_lines(refs)
    assert len({ln["label"] for ln in lines}) == 2


@pytest.mark.parametrize("kw", [dict(theta=180, height=7.0, channel=True),
                                dict(theta=150, height=3.0, channel=True),
                                dict(theta=150, height=3.0), dict(theta=10, height=7.0)])
def test_solve_plot_has_no_white_bands_and_keeps_labels_inside(tmp_path, kw):
    """The figure takes the data's aspect: the equal-aspect axes fill it (a channel at
    h = 7 mm used to fill half its width), and every force label stays in the axes."""
    import lcpbench
    from lcpbench.bench.plot import plot_shape

    res = lcpbench.solve(lcpbench.ActuatorScene(links=40, **kw))
    fig = plot_shape(res, tmp_path / "s.png")
    ax = fig.axes[0]
    box = ax.get_position()  # after the draw of savefig: the box equal aspect left
    assert box.width > 0.8 and box.height > 0.6
    # equal aspect still: mm per inch the same along x and y
    w_in, h_in = fig.get_size_inches()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    assert (x1 - x0) / (box.width * w_in) == pytest.approx((y1 - y0) / (box.height * h_in),
                                                           rel=1e-6)
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    for text in ax.texts:
        b = text.get_window_extent(renderer)
        assert b.y0 >= frame.y0 - 1 and b.y1 <= frame.y1 + 1, text.get_text()
