"""Validation against Euler–Bernoulli theory (Sec. III-G) and the discretisation study."""

import numpy as np
import pytest
from known_answers import CANTILEVER_THEORY_FORCE

from lcpbench import ActuatorScene, CantileverScene, solve
from lcpbench.studies.discretisation import auto_links, discretisation_study
from lcpbench.studies.validation import cantilever_validation, observed_order


def test_cantilever_within_0p1_percent_of_beam_theory_at_N140():
    v = cantilever_validation(140)
    assert v["theory_force"] == pytest.approx(CANTILEVER_THEORY_FORCE, rel=1e-3)  # eqs. (34)-(37)
    assert abs(v["relative_error"]) < 1e-3  # the paper's own model was 2.6 % off
    assert v["contact_nodes"] == [141]  # theory: a single reaction at the free end


def test_cantilever_converges_at_second_order_in_N():
    links = [20, 40, 80, 160, 320]
    forces = [solve(CantileverScene(links=n), tol=1e-11).total_force for n in links]
    assert observed_order(links, forces) == pytest.approx(2.0, abs=0.1)  # Richardson, no limit


def test_cantilever_matches_theory_in_the_small_deflection_limit_at_second_order():
    """Scaling load and gap by 1e-4 removes the geometric nonlinearity the theory ignores."""
    make = lambda n: CantileverScene(links=n, load=1e-7, height=1e-4)  # noqa: E731
    theory = make(10).theory_force()
    links = [20, 40, 80, 160]
    forces = [solve(make(n), tol=1e-12).total_force for n in links]
    assert observed_order(links, forces, theory) == pytest.approx(2.0, abs=0.1)
    assert abs(forces[-1] / theory - 1) < 1e-4


def test_cantilever_below_the_critical_load_touches_nothing():
    sc = CantileverScene(links=60, load=0.9 * 8 * 32.01 * 1.0 / 30**4)  # F < F_c of eq. (34)
    assert sc.theory_force() == 0
    res = solve(sc, tol=1e-10)
    assert res.converged and res.total_force == 0 and res.certificate.min_gap > 0


def test_free_cantilever_deflection_follows_eq33():
    sc = CantileverScene(links=200, load=1e-6, height=100.0)
    res = solve(sc, tol=1e-12)
    theory = sc.theory_deflection(res.x)
    assert np.allclose(res.y, theory, rtol=0, atol=2e-4 * theory.max())


def test_discretisation_study_follows_the_sec_IIID_rule():
    study = discretisation_study(ActuatorScene(theta=150, height=3), start=40, step=10)
    assert study.chosen is not None
    assert study.percent_change[-1] < 0.01
    assert all(c >= 0.01 for c in study.percent_change[:-1])
    assert study.chosen == study.links[-1]


def test_auto_links_is_the_study_rule():
    """auto_links picks the first N whose force changed by < 0.01 % from N - 10
    (Sec. III-D), checked against solves at that N and the N before it."""
    scene = ActuatorScene(theta=150, height=3, links="auto")
    n = auto_links(scene)
    study = discretisation_study(ActuatorScene(theta=150, height=3))
    assert n == study.chosen
    f_n = solve(scene.with_links(n), tol=1e-8).total_force
    f_prev = solve(scene.with_links(n - 10), tol=1e-8).total_force
    assert abs(f_n - f_prev) / max(abs(f_n), abs(f_prev)) < 1e-4
