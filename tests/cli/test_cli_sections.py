"""``--sections`` on ``lcpbench solve`` and ``lcpbench sweep --grid anchoring`` (issue 17)."""

from __future__ import annotations

import json

import pytest
from energy_oracle import energy_minimum

import lcpbench
from lcpbench.bench.grid import anchoring_scenes, scene_from_key, scene_key, scene_params
from lcpbench.bench.rows import scene_columns
from lcpbench.cli import main
from lcpbench.problems.scenes import ActuatorScene
from lcpbench.problems.sections import (
    Section,
    SectionedScene,
    anchoring_actuator,
    parse_sections,
    sections_text,
)


def test_solve_sections_json_is_the_library_answer(capsys):
    """Route against route: the CLI is a front end to the same call, so the
    library's answer is the expectation; what is tested is that the options pass
    through and the answer is printed."""
    code = main(["solve", "--sections", "150:30,-90:20:40", "--height", "3", "--links", "50",
                 "--json"])
    data = json.loads(capsys.readouterr().out)
    scene = SectionedScene(sections=[(150, 30), (-90, 20, 40.0)], height=3, links=50)
    res = lcpbench.solve(scene)
    assert code == 0 and data["converged"]
    assert data["total_force"] == pytest.approx(res.total_force, rel=1e-12)
    assert [s["theta"] for s in data["scene"]["sections"]] == [150.0, -90.0]
    assert len(data["x"]) == 51


def test_solve_anchoring_preset_takes_theta_from_the_calibration(capsys):
    code = main(["solve", "--sections", "anchoring", "--pressure", "137.9", "--height", "5.5",
                 "--links", "60", "--gravity", "toward", "--json"])
    data = json.loads(capsys.readouterr().out)
    theta = 0.81 * 137.9 + 9.78  # actuator 1, eq. (40)
    assert code == 0
    assert [s["theta"] for s in data["scene"]["sections"]] == pytest.approx(
        [-theta, theta, -theta])
    assert data["scene"]["channel"] is True and data["scene"]["gravity"] == "+y"


@pytest.mark.parametrize("args,needle", [
    (["--sections", "abc"], "sections must be THETA:LENGTH"),
    (["--sections", "150:30,"], "item 2 is ''"),
    (["--sections", "150:30:1:2:3"], "item 1"),
    (["--sections", "150:30", "--theta", "40"], "drop --theta"),
    (["--sections", "150:nan"], "sections[0].length"),
    (["--sections", "150,150", "--links", "7"], "N = 6 or 8"),
    (["--sections", "150", "--links", "auto"], "--links auto is for one section"),
    (["--sections", "anchoring", "--links", "100"], "N = 99 or 102"),
    (["--gravity", "toward"], "--gravity needs --sections"),
])
def test_bad_sections_are_one_line_exit_2(args, needle, capsys):
    assert main(["solve", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err


def test_sections_text_reads_back():
    scene = SectionedScene(sections=[(150, 30), (-90, 20, 40.0, 1e-3)], height=3, links=50)
    again = parse_sections(sections_text(scene))
    assert again == scene.sections
    assert parse_sections("30", length=12.0, EI=5.0, weight=0.0) == (Section(30, 12.0, 5.0, 0.0),)


def test_store_keys_tell_the_kinds_apart_and_read_back():
    one = lcpbench.ActuatorScene(theta=150, height=5.5, links=420, length=90.0, channel=True)
    whole = anchoring_actuator(150.0, 5.5, links=420)
    keys = {scene_key(one), scene_key(whole)}
    assert len(keys) == 2
    assert scene_from_key(scene_key(whole)) == whole
    assert scene_key(scene_from_key(scene_key(whole))) == scene_key(whole)
    cols = scene_columns(scene_key(whole))
    assert cols == {"theta": 150.0, "height": 5.5, "links": 420, "length": 90.0,
                    "EI": whole.EI, "weight": whole.weight, "channel": True}
    assert scene_params(scene_key(whole))["sections"] == 3
    assert scene_params(scene_key(one)) == json.loads(scene_key(one))


def test_anchoring_grid_is_theta_by_height():
    scenes = anchoring_scenes(theta=(90.0, 150.0), height=(4.5, 6.5), links=(60,))
    assert len(scenes) == 4 and len({scene_key(s) for s in scenes}) == 4
    assert [(s.theta, s.height) for s in scenes] == [(90.0, 4.5), (150.0, 4.5), (90.0, 6.5),
                                                     (150.0, 6.5)]


def test_sweep_grid_anchoring_runs_into_the_store(tmp_path, capsys):
    from lcpbench.bench.store import Store

    store = tmp_path / "s.sqlite"
    code = main(["sweep", "--grid", "anchoring", "--theta", "150", "--height", "5.5",
                 "--links", "60", "--sections-count", "3", "--solvers", "active-set", "--store", str(store),
                 "--no-report", "--quiet", "--jobs", "1"])
    assert code == 0, capsys.readouterr().err
    with Store(store, create=False) as s:
        runs = s.runs(arrays=False)
        refs = s.refs(arrays=False)
    assert len(runs) == 1 and runs[0]["converged"]
    assert scene_from_key(runs[0]["scene"]) == anchoring_actuator(150.0, 5.5, links=60)
    expected = lcpbench.solve(anchoring_actuator(150.0, 5.5, links=60))
    assert runs[0]["total_force"] == pytest.approx(expected.total_force, rel=1e-6)
    assert list(refs) == [runs[0]["scene"]] and refs[runs[0]["scene"]]["converged"]


@pytest.mark.parametrize("args,needle", [
    (["--baseline", "analytic"], "no baseline"),
    (["--continuation"], "--continuation runs along theta"),
    (["--links", "100"], "N = 99 or 102"),
])
def test_sweep_grid_anchoring_bad_input(args, needle, tmp_path, capsys):
    code = main(["sweep", "--grid", "anchoring", *args, "--store", str(tmp_path / "s.sqlite"),
                 "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and needle in err[-1] and len(err) == 1, err


def test_anchoring_grid_default_is_sections_by_height_by_pressure():
    """The default --grid anchoring: 1 and 3 sections x 3 heights x the paper's pressures,
    theta from actuator 1's calibration (eq. 40), the middle section toward the upper wall."""
    from lcpbench.bench.grid import TISSUE_PRESSURES
    from lcpbench.cli import build_parser
    from lcpbench.cli._sweep_scenes import sweep_scenes
    from lcpbench.problems.calibrations import get_calibration

    args = build_parser().parse_args(["sweep", "--grid", "anchoring"])
    scenes = sweep_scenes(args)
    assert len(scenes) == 2 * 3 * len(TISSUE_PRESSURES)
    assert {len(s.sections) for s in scenes} == {1, 3}
    assert len({scene_key(s) for s in scenes}) == len(scenes)
    cal = get_calibration(1)
    for s in scenes:
        middle = s.sections[len(s.sections) // 2]
        assert middle.theta > 0 and s.channel
        assert any(abs(middle.theta - cal.theta(p)) < 1e-8 for p in TISSUE_PRESSURES)
        assert [sec.theta for sec in s.sections] == [
            middle.theta * (-1) ** abs(k - len(s.sections) // 2) for k in range(len(s.sections))]


def test_one_section_of_the_anchoring_grid_is_the_single_section_model_in_the_channel():
    # the single-section model's equilibrium by direct minimisation of its energy
    # (tests/energy_oracle.py); the grid's one-section scene solved at tol 1e-9 must be
    # it to the success rule, 100 tol = 1e-7
    one = anchoring_actuator(120.0, 4.5, sections=1, links=60)
    single = energy_minimum(ActuatorScene(theta=120.0, height=4.5, links=60, channel=True))
    a = lcpbench.solve(one, tol=1e-9)
    assert a.converged and single.total_force > 0
    assert a.total_force == pytest.approx(single.total_force, rel=1e-7)


@pytest.mark.parametrize("args,needle", [
    (["--grid", "anchoring", "--sections-count", "2"], "sections must be odd"),
    (["--grid", "anchoring", "--theta", "150", "--pressure", "100"], "not both"),
    (["--grid", "anchoring", "--pressure", "a,b"], "pressure must be"),
    (["--pressure", "100"], "--pressure is for --grid anchoring"),
    (["--grid", "tissue", "--sections-count", "3"], "--sections-count is for --grid anchoring"),
])
def test_anchoring_grid_axes_bad_input(args, needle, tmp_path, capsys):
    code = main(["sweep", *args, "--store", str(tmp_path / "s.sqlite"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and needle in err[-1], err
