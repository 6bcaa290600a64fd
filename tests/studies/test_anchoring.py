"""The whole anchoring actuator against the single-section model: properties of the study."""

import json
import math

import numpy as np
import pytest

import lcpbench
from lcpbench.cli import main
from lcpbench.problems.sections import anchoring_actuator
from lcpbench.studies.anchoring import compare, section_states

LINKS = 40  # per section: the study's properties hold at any N; keep the tests fast
SECTION_WEIGHT = 30.0 * 2.45e-4  # N, one 30 mm section at the paper's w


def test_whole_actuator_is_symmetric_about_its_centre():
    """Three sections -θ, +θ, -θ between symmetric walls: a mirror-symmetric answer."""
    scene = anchoring_actuator(130.0, 5.5, links=3 * LINKS)
    res = lcpbench.solve(scene, tol=1e-10)
    assert res.converged
    states = section_states(scene, res)
    assert states[0].lower == pytest.approx(states[2].lower, rel=1e-9)
    assert states[0].upper == 0 and states[2].upper == 0 and states[1].lower == 0
    y = np.asarray(res.y)
    assert np.allclose(y, y[::-1], atol=1e-9)
    # the three wall forces and the two pin reactions balance the weight (vertical statics)
    assert states[1].upper > 0 and states[0].lower > 0


@pytest.mark.parametrize("gravity", ["-y", "+y"])
def test_above_the_knee_the_middle_section_is_pinned_pinned(gravity):
    """All three sections touch: the inflection nodes sit on the mid-line with ~no moment,
    the shape is the single section's, and the force differs by less than the weight the
    end sections could hang on the middle one (two sections' weight)."""
    row = compare("1", 5.5, 150.0, links=LINKS, gravity=gravity)
    assert row["converged"] and row["all_touch"]
    assert abs(row["inflection_height"]) < 0.05  # mm, of a 5.5 mm half-channel
    assert abs(row["inflection_moment"]) < 0.05  # N·mm; EI θ/ℓ is ~2 N·mm here
    assert row["shape_distance_percent"] < 0.5
    offset = row["difference_same_weight"]
    assert 0 < abs(offset) < 2 * SECTION_WEIGHT
    # weight away from the load cell: the end sections pull the middle one off it
    assert (offset < 0) == (gravity == "-y")


def test_below_the_knee_the_actuator_sags_onto_one_wall():
    """Where the single model has no contact, the 90 mm actuator lies on a wall under its
    own weight: the lower wall (weight away from the load cell) or the load cell (toward)."""
    away = compare("1", 5.5, 40.0, links=LINKS, gravity="-y")
    toward = compare("1", 5.5, 40.0, links=LINKS, gravity="+y")
    assert away["single_force"] == 0 and toward["single_force_same_weight"] == 0
    assert away["middle_force"] == 0 and away["ends_touch"] and not away["all_touch"]
    assert toward["middle_force"] > 0 and not toward["ends_touch"]
    # it presses with less than the whole actuator's weight
    assert toward["middle_force"] < 3 * SECTION_WEIGHT
    assert away["inflection_height"] < -0.5 < 0.5 < toward["inflection_height"]


def test_anchoring_study_quick_run_writes_its_files(tmp_path):
    from lcpbench.paper.anchoring import anchoring_study

    info = anchoring_study(tmp_path, quick=True)
    names = {"anchoring.csv", "anchoring-contact.csv", "anchoring-range-ends.csv",
             "anchoring.json", "README.md", "anchoring-force-pressure.png",
             "anchoring-shapes.png"}
    assert names <= {p.name for p in tmp_path.iterdir()}
    assert set(info["written"]) == names  # a fresh folder: every file is new
    summary = json.loads((tmp_path / "anchoring.json").read_text())
    assert summary["all_converged"] and summary["quick"]
    for c in summary["contact_pressures"]:  # all three touch after the single model does
        single, whole = c["single_contact_kpa"], c["all_touch_kpa_-y"]
        if single is not None and math.isfinite(single):
            assert whole >= single - 0.1
    assert "pinned-pinned assumption holds" in (tmp_path / "README.md").read_text()


def test_anchoring_cli_bad_out_is_one_line_exit_2(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["anchoring", "--out", str(blocker / "sub"), "--quick"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "out" in err[0]
