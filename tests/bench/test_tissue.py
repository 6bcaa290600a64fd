"""The tissue grid (elastic walls, issue 17): its scenes, their keys, the sweep and the
report's figure."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from lcpbench import ActuatorScene
from lcpbench.bench.grid import TISSUE_STIFFNESS, scene_from_key, scene_key, tissue_grid
from lcpbench.bench.store import Store
from lcpbench.bench.tissue_plot import tissue_lines, tissue_table
from lcpbench.cli import build_parser, main
from lcpbench.cli._sweep_scenes import sweep_scenes
from lcpbench.cli.sweep import _apply_preset


def test_tissue_grid_is_the_papers_pressures_heights_and_four_stiffnesses():
    scenes = tissue_grid().scenes()
    assert len(scenes) == 10 * 3 * 4
    # eq. (40): θ = 0.81 P + 9.78, P = 2.5..25 psi in 2.5-psi steps (Sec. IV-C)
    psi = 6.894757293168361
    thetas = sorted({s.theta for s in scenes})
    np.testing.assert_allclose(thetas, [0.81 * 2.5 * i * psi + 9.78 for i in range(1, 11)],
                               atol=0.01)
    assert {s.height for s in scenes} == {4.5, 5.5, 6.5}
    assert {s.wall_stiffness for s in scenes} == set(TISSUE_STIFFNESS)
    assert all(s.channel for s in scenes)


def test_scene_keys_are_distinct_per_stiffness_and_read_back():
    scenes = tissue_grid().scenes()
    keys = [scene_key(s) for s in scenes]
    assert len(set(keys)) == len(keys)
    for s, k in zip(scenes, keys):
        back = scene_from_key(k)
        assert back.wall_stiffness == s.wall_stiffness and scene_key(back) == k


def test_a_rigid_scenes_key_is_the_key_it_had_before_elastic_walls():
    s = ActuatorScene(theta=150.0, height=3.0, links=140)
    assert json.loads(scene_key(s)) == {"theta": 150.0, "height": 3.0, "links": 140,
                                        "length": 30.0, "EI": 32.01, "weight": 2.45e-4,
                                        "channel": False}


def _args(*argv):
    args = build_parser().parse_args(["sweep", *argv])
    _apply_preset(args)
    return args


def test_sweep_tissue_options():
    scenes = sweep_scenes(_args("--grid", "tissue", "--height", "5.5",
                                 "--wall-stiffness", "0.5,inf", "--links", "20"))
    assert len(scenes) == 20 and {s.wall_stiffness for s in scenes} == {0.5, math.inf}
    plain = sweep_scenes(_args("--theta", "150", "--height", "3", "--wall-stiffness", "2"))
    assert [s.wall_stiffness for s in plain] == [2.0]


@pytest.mark.parametrize("argv,word", [
    (["--grid", "tissue", "--theta", "90"], "theta"),
    (["--wall-stiffness", "-1"], "wall"),
    (["--wall-stiffness", "nan"], "wall"),
    (["--wall-stiffness", "soft"], "wall-stiffness"),
    (["--grid", "hard", "--wall-stiffness", "1"], "wall-stiffness"),
])
def test_sweep_bad_tissue_input_is_one_line_exit_2(argv, word, capsys, tmp_path):
    code = main(["sweep", *argv, "--store", str(tmp_path / "s.sqlite")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and word in err[0]


def _ref(scene, forces, total=None):
    return {"scene": scene_key(scene), "converged": True,
            "total_force": float(np.sum(forces)) if total is None else total,
            "forces": np.asarray(forces, float)}


def test_tissue_lines_recover_pressure_and_pressure_per_length():
    """Input pressure by inverting eq. (40); contact pressure = max R / a."""
    s1 = ActuatorScene(theta=0.81 * 100 + 9.78, height=5.5, links=10, wall_stiffness=0.1)
    s2 = ActuatorScene(theta=0.81 * 150 + 9.78, height=5.5, links=10)
    refs = {r["scene"]: r for r in (_ref(s1, [0, 0.3, 0.6, 0.3, 0, 0, 0, 0, 0]),
                                    _ref(s2, [0, 0.2, 0, 0, 0, 0, 0, 0, 0.2]))}
    lines = tissue_lines(refs)
    assert list(lines) == [5.5]
    (P, F, peak), = lines[5.5][0.1]
    assert P == pytest.approx(100.0) and F == pytest.approx(1200.0)
    assert peak == pytest.approx(0.6 / 3.0)  # a = 30 mm / 10
    assert lines[5.5][math.inf][0][0] == pytest.approx(150.0)
    assert "| 5.5 | 0.1 |" in tissue_table(refs) and "rigid" in tissue_table(refs)
    # a store with rigid scenes only has no tissue section
    assert tissue_lines({r["scene"]: r for r in [_ref(s2, [0.1] * 9)]}) == {}


def test_tissue_sweep_into_a_store_and_its_report(tmp_path):
    pytest.importorskip("matplotlib")
    store = tmp_path / "t.sqlite"
    out = tmp_path / "out"
    code = main(["sweep", "--grid", "tissue", "--height", "6.5", "--links", "20",
                 "--wall-stiffness", "0.1", "--solvers", "active-set", "--store", str(store),
                 "--out", str(out), "--quiet", "--jobs", "1"])
    assert code == 0
    runs = Store(store).runs(arrays=False)
    assert len(runs) == 10 and all(r["backend"] == "active-set" for r in runs)
    assert all(json.loads(r["scene"])["wall_stiffness"] == 0.1 for r in runs)
    report = (out / "report.md").read_text()
    assert "## Elastic walls" in report and (out / "tissue.png").exists()
