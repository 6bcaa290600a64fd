"""`lcpbench anchor` (issue 39, item 6): the pull-out force on the command line."""

from __future__ import annotations

import json

import pytest

from lcpbench.cli import main

BASE = ["anchor", "--height", "5.5", "--channel", "--links", "30"]


def _json(argv, capsys):
    code = main([*BASE, *argv, "--json"])
    return code, json.loads(capsys.readouterr().out)


def test_anchor_json_keys_units_and_the_gross_slip_identity(capsys):
    code, d = _json(["--theta", "150", "--friction", "0.3"], capsys)
    assert code == 0 and d["converged"]
    for key in ("pull_out_force", "normal_force_total", "solves", "capacity",
                "normal_forces", "tangential_forces", "stick_to_slip"):
        assert key in d
    assert d["units"]["pull_out_force"] == "N" and d["units"]["normal_force_total"] == "N"
    # at pull-out every contact node slides: P* = μ ΣN(P*) (Coulomb, flat walls), in N;
    # ΣN is the last held state's (pull P_h), and ΣN falls as the pull grows:
    # P_h <= P* <= μ ΣN(P_h)
    P, Ph = d["pull_out_force"], d["held_pull"]
    muN = 0.3 * d["normal_force_total"]  # μ as given, ΣN as printed
    assert 0 < Ph <= P <= muN * (1 + 1e-9) and P == pytest.approx(muN, rel=1e-5)
    # newtons, not millinewtons: the paper's scene presses its walls with ~0.1-1 N
    assert 1e-3 < d["normal_force_total"] < 1.0
    assert d["normal_force_total"] == pytest.approx(sum(d["normal_forces"]), rel=1e-12)
    assert 1 <= d["solves"] <= 20  # the budget


def test_anchor_pressure_goes_through_the_paper_calibration(capsys):
    """--pressure P is --theta 0.81 P + 9.78 (actuator 1, eq. 40 of the paper)."""
    _, by_p = _json(["--pressure", "137.9", "--friction", "0.2"], capsys)
    _, by_t = _json(["--theta", str(0.81 * 137.9 + 9.78), "--friction", "0.2"], capsys)
    assert by_p["pressure"] == 137.9 and by_t["pressure"] is None
    assert by_p["pull_out_force"] == pytest.approx(by_t["pull_out_force"], rel=1e-9)


def test_anchor_without_contact_holds_no_pull(capsys):
    """17.24 kPa bends the actuator to 24°, far from walls 5.5 mm away: no N, no T."""
    code, d = _json(["--pressure", "17.24", "--friction", "0.5"], capsys)
    assert code == 0 and d["pull_out_force"] == 0.0 and d["normal_force_total"] == 0.0


def test_anchor_text_says_mN_and_solves(capsys):
    code = main([*BASE, "--theta", "150", "--friction", "0.3"])
    out = capsys.readouterr().out
    assert code == 0 and "pull-out force" in out and "mN" in out and "frictional" in out


def test_anchor_plot_writes_the_figure(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    f = tmp_path / "anchor.png"
    code = main([*BASE, "--theta", "150", "--friction", "0.3", "--plot", str(f)])
    assert code == 0 and f.stat().st_size > 1000


@pytest.mark.parametrize("argv,words", [
    (["--theta", "150"], "--friction"),
    (["--theta", "150", "--friction", "0"], "nothing holds the chain"),
    (["--theta", "150", "--friction", "-0.1"], "friction must be"),
    (["--theta", "150", "--friction", "x"], "--friction"),
    (["--theta", "150", "--pressure", "100", "--friction", "0.3"], "not both"),
    (["--theta", "150", "--friction", "0.3", "--wall-stiffness", "-1"], "wall_stiffness"),
    (["--theta", "150", "--friction", "0.3", "--links", "auto"], "--links auto"),
    (["--theta", "150", "--friction", "nan"], "friction must be"),
])
def test_anchor_bad_input_is_one_line_exit_2(argv, words, capsys):
    code = main([*BASE, *argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0]


def test_solve_friction_plot_writes_the_figure(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    f = tmp_path / "forces.png"
    code = main(["solve", "--theta", "150", "--height", "3", "--links", "30", "--friction",
                 "0.3", "--left-end", "slider", "--right-end", "slider", "--pull", "0.05",
                 "--plot", str(f)])
    assert code == 0 and f.stat().st_size > 1000


def test_anchor_takes_the_papers_three_section_actuator(capsys):
    """--sections anchoring: the 3-section actuator in its channel holds a pull; at
    pull-out its contact nodes slide, so P* = μ ΣN (Coulomb on flat walls), as for one
    section."""
    code, d = _json(["--theta", "150", "--friction", "0.3", "--sections", "anchoring"],
                    capsys)
    assert code == 0 and d["converged"]
    P, Ph = d["pull_out_force"], d["held_pull"]
    muN = 0.3 * d["normal_force_total"]  # μ as given, ΣN as printed
    assert 0 < Ph <= P <= muN * (1 + 1e-9) and P == pytest.approx(muN, rel=1e-5)


def test_solve_friction_on_sections_is_not_dropped(capsys):
    """Friction given with --sections is solved with friction: every node's tangential
    force within its cone, |T| <= μ N, N the node's normal force on either wall of the
    channel (with sliders at both ends and no pull, friction
    alone holds the row along x: ΣT = 0)."""
    code = main(["solve", "--sections", "anchoring", "--theta", "150", "--height", "5.5",
                 "--links", "30", "--friction", "0.3", "--left-end", "slider",
                 "--right-end", "slider", "--json"])
    d = json.loads(capsys.readouterr().out)
    assert code == 0 and d["converged"]
    N = [up + lo for up, lo in zip(d["forces"], d["forces_lower"], strict=True)]
    T = d["tangential_forces"]
    assert len(T) == len(N) and sum(N) > 0
    assert all(abs(t) <= 0.3 * n + 1e-9 for t, n in zip(T, N, strict=True))
    assert abs(sum(T)) <= 1e-6 * sum(N)


def test_anchor_on_elastic_walls_passes_the_stiffness_through(capsys):
    """--wall-stiffness K: the same pull-out as lcpbench.pull_out of the elastic scene,
    which holds the gross-slip identity P* = μ ΣN (flat walls, elastic or not)."""
    from lcpbench import ActuatorScene, pull_out

    code, d = _json(["--theta", "150", "--friction", "0.3", "--wall-stiffness", "0.1"], capsys)
    assert code == 0 and d["converged"] and d["scene"]["wall_stiffness"] == 0.1
    ref = pull_out(ActuatorScene(theta=150, height=5.5, channel=True, links=30, friction=0.3,
                                 left_end="slider", right_end="slider", wall_stiffness=0.1))
    assert d["pull_out_force"] == ref.force
    assert d["capacity"] == pytest.approx(0.3 * d["normal_force_total"], rel=1e-9)
    assert d["pull_out_force"] == pytest.approx(d["capacity"], rel=1e-6)
    assert "wall k=0.1" in (main([*BASE, "--theta", "150", "--friction", "0.3",
                                  "--wall-stiffness", "0.1"]) == 0 and capsys.readouterr().out)


def test_solve_friction_refuses_a_pressure_limit(capsys):
    code = main(["solve", "--theta", "150", "--height", "3", "--links", "30", "--friction",
                 "0.3", "--right-end", "slider", "--wall-stiffness", "0.1",
                 "--pressure-limit", "0.03"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--pressure-limit" in err[0]
