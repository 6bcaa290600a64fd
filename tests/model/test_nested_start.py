"""The large-N driver's start from the same chain at fewer links (:mod:`lcpbench.model.nested_start`).

Expected values come from independent sources: the scene's own chain builder at
the coarse N, exact polynomials for the spline, the cold-started solve of the same
fine scene, and the fine answer itself for how close the start is.
"""

from __future__ import annotations

import numpy as np
import pytest

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.api import solve_internal
from lcpbench.model import large_n, nested_start
from lcpbench.model.chain import heights
from lcpbench.model.judge import force_tol
from lcpbench.model.outer import DriverOutput
from lcpbench.problems.sections import Section, SectionedScene

CHAIN_FIELDS = ("rest_alpha", "joint_stiffness", "joint_links", "rest_joint", "link_load",
                "free_nodes", "upper", "lower")


@pytest.mark.parametrize("theta,height,weight", [(150, 3.0, 0.0), (90, 1.5, 2e-4),
                                                 (180, 6.0, 0.0)])
def test_the_coarse_chain_is_the_one_the_scene_builds_at_fewer_links(theta, height, weight):
    fine = ActuatorScene(theta, height, links=8000, weight=weight).chain()
    want = ActuatorScene(theta, height, links=1000, weight=weight).chain()
    got = nested_start.coarse_chain(fine, 1000)
    assert got.links == want.links and got.link_length == pytest.approx(want.link_length)
    for f in CHAIN_FIELDS:
        a, b = np.asarray(getattr(got, f)), np.asarray(getattr(want, f))
        assert a.shape == b.shape, f
        assert np.array_equal(np.isfinite(a), np.isfinite(b)), f
        fin = np.isfinite(b)
        assert np.allclose(a[fin], b[fin], rtol=1e-12, atol=1e-15), f
    for f in ("force_scale", "length", "wall", "channel"):
        assert getattr(got, f) == getattr(want, f)


def test_the_spline_goes_through_its_nodes_and_is_exact_on_a_quadratic():
    # a quadratic has a constant y'': the one-sided end values and the inner equations
    # M_{j-1} + 4 M_j + M_{j+1} = 6 Δ²y_j all hold with M = y'', so the spline is y
    k = np.arange(11.0)
    x = np.linspace(0, 10, 41)
    assert np.allclose(nested_start._spline(0.5 * k**2 - 3 * k, x), 0.5 * x**2 - 3 * x,
                       atol=1e-12)
    y = np.sin(0.7 * k) + 0.1 * k**3
    assert np.allclose(nested_start._spline(y, k), y, rtol=0, atol=1e-13)


@pytest.mark.parametrize("theta,height", [(150, 3.0), (120, 5.0)])
def test_the_start_is_within_the_discretisation_error_of_the_fine_answer(theta, height):
    """Route against route: at N = 8000 the energy oracle costs ~25 s per answer; the
    fine answer is the expectation for a start that need only be within O(N_c⁻²)."""
    scene = ActuatorScene(theta, height, links=8000)
    chain = scene.chain()
    ans = lcpbench.solve(scene, tol=1e-9)
    assert ans.converged, ans.reason
    start = nested_start.nested_start(chain, _kernel_solve)
    assert start is not None
    # the coarse shape differs from the fine one by O(N_c⁻²) ~ 1e-6 of the arc's angles
    assert np.max(np.abs(start.alpha - ans.alpha)) <= 1e-4
    # its contacts are within N / N_c nodes of the fine contacts, and it has all of them
    held = np.flatnonzero(start.warm.active_upper)
    contacts = np.flatnonzero(ans.forces > 1e-6 * ans.total_force)  # free nodes
    assert held.size and contacts.size
    ratio = chain.links // nested_start.COARSE_LINKS
    for c in contacts:
        assert np.min(np.abs(held - c)) <= ratio
    # the start fits the fine chain: its heights are within the walls
    u = heights(chain, start.alpha)
    assert np.all(u <= chain.upper + 1e-9)


def _kernel_solve(coarse):
    from lcpbench.model.kernel_call import run_compiled

    out, _ = run_compiled(coarse, tol=1e-6)
    return out


@pytest.mark.parametrize("theta,height", [(150, 3.0), (180, 1.0), (90, 4.0)])
def test_the_nested_answer_is_the_cold_answer(monkeypatch, theta, height):
    # the same equilibrium from either start (the cold start is an independent path)
    """Route against route: at N = 6000 the energy oracle costs ~N² energy terms per answer
    (minutes for three scenes); the cold start is an independent path to the same
    equilibrium, and the nested start itself is checked against the discretisation error
    above."""
    scene = lambda: ActuatorScene(theta, height, links=6000)  # noqa: E731
    nested = lcpbench.solve(scene(), tol=1e-9)
    monkeypatch.setattr(nested_start, "COARSE_LINKS", 0)
    cold = lcpbench.solve(scene(), tol=1e-9)
    assert nested.converged and cold.converged, (nested.reason, cold.reason)
    F0 = cold.judgement.force_unit
    assert abs(nested.total_force - cold.total_force) <= force_tol(1e-9) * F0 + 1e-12
    assert np.max(np.abs(nested.alpha - cold.alpha)) <= 1e-8


def _two_sections(links):
    return SectionedScene([Section(75.0, 60.0), Section(75.0, 60.0, EI=64.0)], height=3.0,
                          links=links)


def test_a_sectioned_bar_gets_the_stiffness_of_each_section():
    # two sections of EI 32.01 and 64 N·mm²: the coarse joints take the EI of their own
    # section (the seam falls on a node of both chains: no joint blends the two)
    chain = _two_sections(8000).chain()
    assert large_n.applies(chain)
    coarse = nested_start.coarse_chain(chain, 1000)
    want = _two_sections(1000).chain()
    EI, EI_want = coarse.joint_stiffness * coarse.link_length, want.joint_stiffness * \
        want.link_length
    seam = np.flatnonzero(np.abs(EI - EI_want) > 1e-9 * EI_want)
    assert seam.size == 0
    assert np.allclose(coarse.rest_joint, want.rest_joint, rtol=1e-12)


def test_the_nested_answer_of_a_sectioned_bar_is_the_cold_answer(monkeypatch):
    """Route against route: as above, at N = 6000 the energy oracle is out of reach; the
    cold start is an independent path to the same equilibrium."""
    nested = lcpbench.solve(_two_sections(6000), tol=1e-9)
    monkeypatch.setattr(nested_start, "COARSE_LINKS", 0)
    cold = lcpbench.solve(_two_sections(6000), tol=1e-9)
    assert nested.converged and cold.converged, (nested.reason, cold.reason)
    F0 = cold.judgement.force_unit
    assert abs(nested.total_force - cold.total_force) <= force_tol(1e-9) * F0 + 1e-12


def test_no_start_when_the_coarse_solve_fails_or_the_chain_is_small():
    chain = ActuatorScene(150, 3.0, links=6000).chain()
    failed = DriverOutput(chain.rest_alpha[:1000], np.zeros(999), np.zeros(999), False,
                          "no convergence", [])
    assert nested_start.nested_start(chain, lambda coarse: failed) is None
    assert nested_start.nested_start(chain, lambda coarse: None) is None
    small = ActuatorScene(150, 3.0, links=3000).chain()
    called = []
    assert nested_start.nested_start(small, lambda c: called.append(c)) is None
    assert not called


def test_no_start_past_the_vertical_or_for_a_heavy_chain():
    # θ > 180°: the end links start beyond the vertical (the coarse solve raised in a
    # factorisation there); wℓ³/EI >= MODERATE: height steps crawl at both sizes
    called = []
    for scene in (ActuatorScene(190, 3.0, links=6000),
                  ActuatorScene(200, 2.0, links=6000, channel=True),
                  ActuatorScene(150, 3.0, links=6000, weight=0.05)):
        assert nested_start.nested_start(scene.chain(), called.append) is None
    assert not called
    # the cold start is refused there, and the answer comes by the loading path instead
    res = lcpbench.solve(ActuatorScene(190, 3.0, links=6000))
    assert res.converged and "theta > 180" in res.retried("ramped")
    assert "followed the load from zero" in res.retried("ramped")


def test_the_coarse_solve_uses_the_built_in_active_set_whatever_the_back_end(monkeypatch):
    # under engine="compiled" a back-end the compiled driver does not take (OSQP,
    # unscaled) raised ProblemError at 1000 links (at large N it runs the increment
    # path); the coarse solve is a start only, so it runs the built-in solve: it
    # converges, and the fine solve returns a verdict, not an exception
    coarse_answers = []
    real = nested_start.interpolated_start

    def spy(chain, coarse, out):
        coarse_answers.append(out)
        return real(chain, coarse, out)

    monkeypatch.setattr(nested_start, "interpolated_start", spy)
    res = solve_internal(ActuatorScene(150, 3.0, links=5000), solver="osqp",
                         engine="compiled", scaled=False)
    assert len(coarse_answers) == 1 and coarse_answers[0].converged
    assert isinstance(res.converged, bool) and res.reason
