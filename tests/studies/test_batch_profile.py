"""solve_many on scenes against a wall of any profile (issue 35, target 3): a line whose
scenes press one profiled wall is solved by the profile kernel one call per attempt,
its results built when read (lcpbench.studies.batch_compiled.profile_line); others
scene by scene.

Expected values come from the independent energy minimisation
(reference/energy.py: SLSQP on the exact walls h(x), no contact step) and from
theory (an arc that clears the wall with no load has no contact).
"""

import numpy as np
import pytest
from known_answers import stenosis

import lcpbench
from lcpbench.problems.scenes import ActuatorScene
from lcpbench.problems.walls import WallProfile
from lcpbench.reference.energy import minimise_energy

LINKS = 40
#: tests/model/test_profile.py's rule: 1e-6 relative total force (and shape, in ℓ)
REL = 1e-6


def bump():
    return WallProfile.from_table([0, 10, 14, 18, 30], [3.0, 3.0, 2.4, 3.0, 3.0])


def _matches_the_energy_minimisation(scene, res):
    ref = minimise_energy(scene)
    assert ref.success, ref.message
    assert res.converged, res.reason
    F0 = max(abs(ref.total_force), scene.EI / scene.length**2)
    assert abs(res.total_force - ref.total_force) <= REL * F0
    if scene.channel:
        assert abs(res.forces_lower.sum() - ref.forces_lower.sum()) <= REL * F0
    assert np.max(np.abs(res.y - ref.y)) <= REL * scene.length
    assert np.max(np.abs(res.x - ref.x)) <= REL * scene.length
    assert res.certificate.min_gap >= -1e-6 * scene.length  # on the exact wall h(x)


def test_planes_against_two_profiles_match_the_energy_minimisation():
    """Two planes (a stenosis given as a function, a PCHIP bump), θ in either order: each
    scene's answer is the energy minimiser's; the lines go through the profile line."""
    walls = (stenosis(), bump())
    thetas = (150.0, 120.0, 165.0, 135.0, 180.0)
    scenes = [ActuatorScene(theta=t, height=3.0, links=LINKS, wall_profile=walls[i % 2])
              for i, t in enumerate(thetas * 2)]
    results = lcpbench.solve_many(scenes, tol=1e-10)
    assert len(results) == len(scenes)
    assert {r.route for r in results} == {"line kernel"}  # (the path this file tests)
    for scene, res in zip(scenes, results, strict=True):
        assert res.scene is scene
        assert res.total_force > 0  # the scenes press the wall
        _matches_the_energy_minimisation(scene, res)
    for plane in (0, 1):  # solved by θ: the smallest θ of each plane starts cold
        mine = [(s.theta, r.extra["continuation"]) for i, (s, r) in
                enumerate(zip(scenes, results, strict=True)) if i % 2 == plane]
        first = min(mine)
        assert first[1] == "cold"
        assert {label for t, label in mine if t > first[0]} <= {"adaptive",
                                                                  "adaptive, failed; cold"}
    d = results[3].to_dict()  # the whole result, built when read
    assert d["converged"] and d["total_force"] == pytest.approx(results[3].total_force)


def test_lines_the_profile_line_does_not_take_are_solved_scene_by_scene():
    """A channel against a stenosis (the profile line takes one wall) and arcs that clear
    the wall (the wall-free search answers them): each answer the energy minimiser's;
    a clear arc with no load has no contact (theory)."""
    wall = stenosis()
    channel = [ActuatorScene(theta=t, height=3.0, links=LINKS, wall_profile=wall,
                             channel=True) for t in (140.0, 150.0)]
    clear = [ActuatorScene(theta=t, height=3.0, links=LINKS, wall_profile=wall,
                           weight=0.0) for t in (20.0, 30.0)]
    results = lcpbench.solve_many(channel + clear, tol=1e-10)
    for scene, res in zip(channel, results[:2], strict=True):
        assert res.route == "batch scene"
        _matches_the_energy_minimisation(scene, res)
    for res in results[2:]:
        assert res.converged, res.reason
        assert res.total_force == 0.0
        assert res.gaps.min() > 0


def test_a_batch_with_a_wall_without_a_table_is_refused_as_solve_refuses_it(monkeypatch):
    """A function profile with no table of cubic pieces (more than MAX_PIECES) cannot be
    judged: solve_many refuses the batch with solve()'s one clear error, naming the
    parameter and what to give instead (it said "no driver takes this chain")."""
    from lcpbench.errors import ProblemError
    from lcpbench.problems import profile_table

    monkeypatch.setattr(profile_table, "MAX_PIECES", 8)
    flat = ActuatorScene(theta=150.0, height=3.0, links=LINKS)
    for field in ("wall_profile", "lower_profile"):  # (a lower profile needs an upper one)
        walls = ({"wall_profile": stenosis()} if field == "wall_profile" else
                 {"wall_profile": bump(), "lower_profile": stenosis().mirrored()})
        walled = ActuatorScene(theta=150.0, height=3.0, links=LINKS, channel=True, **walls)
        for batch in ([flat, walled], [walled, walled]):
            with pytest.raises(ProblemError, match=rf"^{field}: .*more than 8 .*from_table"):
                lcpbench.solve_many(batch, tol=1e-3)
