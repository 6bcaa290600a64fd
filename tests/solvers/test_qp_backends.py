"""Tests of the QP back-ends (OSQP, Clarabel, ProxQP, qpsolvers, cvxpy).

Every installed back-end is run on (a) small box QPs whose answers are
derived by hand, multipliers included; (b) random SPD box QPs against an
independent reference (L-BFGS-B, then an exact solve on the active set it
identifies, checked by KKT); (c) the settings translation; (d) infeasible
and unbounded input. Expected failures are listed as data in ``XFAIL``.
"""

from __future__ import annotations

import subprocess
import sys
import time
from importlib.util import find_spec
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize
import scipy.sparse as sp
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from known_answers import BOX_QP_KNOWN

from lcpbench.errors import ProblemError, SolverNotFound
from lcpbench.solvers import qp_clarabel, qp_cvxpy, qp_osqp, qp_proxsuite, qp_qpsolvers
from lcpbench.solvers.base import PROFILES, BoxQP, QPResult, QPWarm, Settings, Status

INF = np.inf

# --- the back-ends installed here ----------------------------------------------------------
BACKENDS: dict[str, tuple] = {}
if find_spec("osqp"):
    BACKENDS["osqp"] = (qp_osqp.solve_qp, {})
if find_spec("clarabel"):
    BACKENDS["clarabel"] = (qp_clarabel.solve_qp, {})
if find_spec("proxsuite"):
    BACKENDS["proxsuite-dense"] = (qp_proxsuite.solve_qp, {"variant": "dense"})
    BACKENDS["proxsuite-dense-C"] = (qp_proxsuite.solve_qp, {"variant": "dense", "box": False})
    BACKENDS["proxsuite-sparse"] = (qp_proxsuite.solve_qp, {"variant": "sparse"})
if find_spec("qpsolvers"):
    import qpsolvers

    for _name in qpsolvers.available_solvers:
        BACKENDS[f"qpsolvers-{_name}"] = (qp_qpsolvers.solve_qp, {"solver": _name})
if find_spec("cvxpy"):
    import cvxpy

    BACKENDS["cvxpy"] = (qp_cvxpy.solve_qp, {})
    for _name in ("CLARABEL", "OSQP", "PIQP", "PROXQP", "DAQP", "SCS", "HIGHS"):
        if _name in cvxpy.installed_solvers():
            BACKENDS[f"cvxpy-{_name}"] = (qp_cvxpy.solve_qp, {"solver": _name})

#: (back-end, case) -> why it is expected to fail (kept strict: an xpass fails).
XFAIL = {
    ("qpsolvers-quadprog", "psd"): "quadprog needs a positive definite P",
    ("qpsolvers-highs", "unbounded"):
        "HiGHS's QP solver reports kOptimal at an artificial x ~ -1e7 on an unbounded QP",
    ("cvxpy-HIGHS", "unbounded"): "same HiGHS behaviour through cvxpy ('optimal')",
    ("cvxpy-SCS", "1d-free"): "cvxpy hands SCS a 0-row cone problem; SCS wants m >= 1",
}
#: Back-ends that cannot take a QP without any finite bound (see XFAIL).
NEEDS_A_BOUND = {"cvxpy-SCS"}

#: Accuracy on the random QPs, as (x at 'mid', KKT at 'mid', x at 'high'), each
#: relative to the problem's scale; (1e-5, 1e-5, 1e-5) unless listed (KKT at 'high': 1e-7).
#: Interior-point (Clarabel, PIQP) and proximal (ProxQP) methods stop on
#: residuals and the duality gap, which bound y_i * gap_i, not the distance to
#: x*: on a weakly active bound (tiny y_i) x is off by up to
#: ~sqrt(tol / lambda_min(P)) ~ 1e-3 at 'mid' (seen: 1e-3 PIQP, 5e-4 Clarabel,
#: 2e-4 sparse ProxQP), and PIQP's unscaled bound violation reaches 2e-5. The
#: same bound at 'high' is sqrt(1e-9 / 0.5) ~ 4.5e-5 (seen: 3.8e-5, Clarabel, on a
#: bound active with a zero multiplier), hence 1e-4.
LOOSE_AT_MID = (5e-3, 5e-5, 1e-4)
ACCURACY = {name: LOOSE_AT_MID for name in BACKENDS
            if any(k in name.lower() for k in ("clarabel", "piqp", "proxsuite", "proxqp"))}
#: (back-end, profile) -> why the random tests fail on it. Strict: the examples are
#: derandomized (the same on every machine and run), so an xpass means the expectation
#: is out of date. cvxpy-PROXQP at 'high' is not listed: it passes the 10 examples
#: drawn here, though a separate run over 200 fresh random QPs of the same
#: strategy found 6 where it declares 'solved'
#: with complementarity up to 1.5e-4 and x off by 1.2e-4 -- the same missing
#: duality-gap check, at a smaller scale.
XFAIL_RANDOM = {
    ("cvxpy-PROXQP", "mid"):
        "cvxpy's ProxQP interface passes only eps_abs/eps_rel, so ProxQP runs without "
        "its duality-gap check and declares 'solved' up to 7e-2 away from x* at 'mid'",
}

def run(name: str, qp: BoxQP, profile: str = "mid", warm: QPWarm | None = None) -> QPResult:
    func, opts = BACKENDS[name]
    return func(qp, PROFILES[profile], warm, **opts)


def box_qp(P, c, lower, upper) -> BoxQP:
    return BoxQP(sp.csc_matrix(np.atleast_2d(np.asarray(P, float))), np.asarray(c, float),
                 np.asarray(lower, float), np.asarray(upper, float))


def kkt(qp: BoxQP, x: np.ndarray, y: np.ndarray) -> dict[str, float]:
    """KKT residuals of (x, y) with the signed convention P x + c + y = 0."""
    lo, up = qp.lower, qp.upper
    y_up, y_lo = np.maximum(y, 0.0), np.maximum(-y, 0.0)
    gap_up = np.where(np.isfinite(up), up - x, INF)
    gap_lo = np.where(np.isfinite(lo), x - lo, INF)
    return {
        "stationarity": float(np.abs(qp.P @ x + qp.c + y).max()),
        "bounds": float(max(0.0, (-gap_up).max(), (-gap_lo).max())),
        # a push from a side with no bound, or complementarity violated
        "complementarity": float(max(
            (y_up * np.where(np.isfinite(gap_up), np.abs(gap_up), 1.0)).max(),
            (y_lo * np.where(np.isfinite(gap_lo), np.abs(gap_lo), 1.0)).max())),
    }


# --- (a) hand-derived answers -------------------------------------------------------------
# Each case: P, c, lower, upper, x*, y* (y* from P x* + c + y* = 0 by hand).
HAND = BOX_QP_KNOWN


def _grid(cases):
    out = []
    for name in BACKENDS:
        for case in cases:
            marks = ()
            if (name, case) in XFAIL:
                marks = (pytest.mark.xfail(reason=XFAIL[name, case], strict=True),)
            out.append(pytest.param(name, case, id=f"{name}-{case}", marks=marks))
    return out


@pytest.mark.parametrize(("name", "case"), _grid(HAND))
def test_hand_derived(name, case):
    P, c, lo, up, x_star, y_star = HAND[case]
    qp = box_qp(P, c, lo, up)
    res = run(name, qp, "mid")
    assert res.status is Status.SOLVED, res.message
    np.testing.assert_allclose(res.x, x_star, atol=1e-5)
    np.testing.assert_allclose(res.y, y_star, atol=1e-5)
    # the sign convention itself, beyond closeness
    y = np.asarray(y_star)
    assert np.all(res.y[y > 0] > 0) and np.all(res.y[y < 0] < 0)


@pytest.mark.parametrize("name", list(BACKENDS))
def test_default_profile_and_time_units(name):
    """Solver defaults give a (loose) answer; times are seconds, not micro/milli."""
    P, c, lo, up, x_star, y_star = HAND["3d-mixed"]
    qp = box_qp(P, c, lo, up)
    t0 = time.perf_counter()
    res = run(name, qp, "default")
    wall = time.perf_counter() - t0
    assert res.status is Status.SOLVED, res.message
    np.testing.assert_allclose(res.x, x_star, atol=1e-2)
    np.testing.assert_allclose(res.y, y_star, atol=1e-2)
    assert res.time_source in ("solver", "wall")
    assert 0.0 <= res.solve_time <= wall + 1e-4
    assert 0.0 <= res.setup_time <= wall + 1e-4
    assert res.iterations >= 0


@pytest.mark.parametrize("name", list(BACKENDS))
def test_warm_start_accepted(name):
    """A warm start from the answer is taken (or ignored) and the answer stays."""
    P, c, lo, up, x_star, y_star = HAND["2d-upper-lower"]
    qp = box_qp(P, c, lo, up)
    cold = run(name, qp, "mid")
    warm = run(name, qp, "mid", QPWarm(np.array(x_star), np.array(y_star)))
    assert warm.status is Status.SOLVED, warm.message
    np.testing.assert_allclose(warm.x, x_star, atol=1e-5)
    if name in ("osqp", "proxsuite-dense-C", "proxsuite-sparse"):  # x and y are used
        assert warm.iterations <= cold.iterations


# --- (b) random SPD box QPs against an independent answer ---------------------------------
def reference(qp: BoxQP) -> tuple[np.ndarray, np.ndarray]:
    """L-BFGS-B, then the exact solution on the active set it finds (KKT-checked)."""
    P = qp.dense()
    bounds = list(zip(np.where(np.isfinite(qp.lower), qp.lower, None),
                      np.where(np.isfinite(qp.upper), qp.upper, None), strict=True))
    x0 = np.clip(np.zeros(qp.size), qp.lower, qp.upper)
    opt = scipy.optimize.minimize(lambda x: 0.5 * x @ P @ x + qp.c @ x, x0,
                                  jac=lambda x: P @ x + qp.c, method="L-BFGS-B",
                                  bounds=bounds, options={"ftol": 1e-15, "gtol": 1e-12,
                                                          "maxiter": 10_000})
    x = opt.x
    at_up = np.isfinite(qp.upper) & (x >= qp.upper - 1e-7)
    at_lo = np.isfinite(qp.lower) & (x <= qp.lower + 1e-7) & ~at_up
    x = np.where(at_up, qp.upper, np.where(at_lo, qp.lower, x))
    free = ~(at_up | at_lo)
    if free.any():
        rhs = -(qp.c[free] + P[np.ix_(free, ~free)] @ x[~free])
        x[free] = np.linalg.solve(P[np.ix_(free, free)], rhs)
    y = -(P @ x + qp.c)
    y[free] = 0.0
    r = kkt(qp, x, y)
    assert max(r.values()) < 1e-9, f"reference failed its own KKT check: {r}"
    return x, y


@st.composite
def random_box_qps(draw):
    n = draw(st.integers(1, 8))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    M = rng.uniform(-1.0, 1.0, (n, n))
    P = M.T @ M + 0.5 * np.eye(n)
    c = rng.uniform(-3.0, 3.0, n)
    kind = rng.integers(0, 4, n)  # 0 none, 1 upper, 2 lower, 3 both
    a, b = rng.uniform(-1.0, 0.0, n), rng.uniform(0.0, 1.0, n)
    lower = np.where((kind == 2) | (kind == 3), a, -INF)
    upper = np.where((kind == 1) | (kind == 3), b, INF)
    return box_qp(P, c, lower, upper)


def _check_random(name: str, qp: BoxQP, profile: str) -> None:
    x_ref, y_ref = reference(qp)
    res = run(name, qp, profile)
    assert res.status is Status.SOLVED, res.message
    x_mid, kkt_mid, x_high = ACCURACY.get(name, (1e-5, 1e-5, 1e-5))
    x_tol, kkt_tol = (x_mid, kkt_mid) if profile == "mid" else (x_high, 1e-7)
    # the tolerances are absolute AND relative: compare on the problem's scale
    scale = max(1.0, np.abs(qp.c).max(), np.abs(y_ref).max())
    np.testing.assert_allclose(res.x, x_ref, atol=x_tol * max(1.0, np.abs(x_ref).max()))
    np.testing.assert_allclose(res.y, y_ref, atol=x_tol * scale)
    r = kkt(qp, res.x, res.y)
    assert r["stationarity"] <= kkt_tol * scale, r
    assert r["bounds"] <= kkt_tol, r
    assert r["complementarity"] <= kkt_tol * scale, r


def _random_grid(profile: str):
    return [pytest.param(name, id=name, marks=(
        (pytest.mark.xfail(reason=XFAIL_RANDOM[name, profile], strict=True),)
        if (name, profile) in XFAIL_RANDOM else ())) for name in BACKENDS]


@pytest.mark.parametrize("name", _random_grid("mid"))
@settings(max_examples=20, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(qp=random_box_qps())
def test_random_spd_mid(name, qp):
    assume(name not in NEEDS_A_BOUND or qp.constrained_rows().size > 0)
    _check_random(name, qp, "mid")


@pytest.mark.parametrize("name", _random_grid("high"))
@settings(max_examples=10, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(qp=random_box_qps())
def test_random_spd_high(name, qp):
    assume(name not in NEEDS_A_BOUND or qp.constrained_rows().size > 0)
    _check_random(name, qp, "high")


@pytest.mark.parametrize("name", list(BACKENDS))
def test_pentadiagonal_interior_high(name):
    """140-row contact-like QP, K = DᵀD (D = 3000 x second difference, cond 6e7),
    whose optimum is interior: x* = -K⁻¹c exactly. Catches HiGHS stopping at
    x = 0 when the bounds are given as column bounds (see qp_qpsolvers)."""
    n = 140
    D = 3000.0 * sp.diags([np.ones(n - 1), -2 * np.ones(n), np.ones(n - 1)], [-1, 0, 1])
    K = sp.csc_matrix(D.T @ D)
    c = 1e-2 * np.random.default_rng(0).standard_normal(n)
    x_star = np.linalg.solve(K.toarray(), -c)
    assert x_star.max() < 0.5  # the bound is inactive
    res = run(name, BoxQP(K, c, np.full(n, -INF), np.full(n, 0.5)), "high")
    assert res.status is Status.SOLVED, res.message
    np.testing.assert_allclose(res.x, x_star, atol=1e-5 * np.abs(x_star).max())
    np.testing.assert_allclose(res.y, 0.0, atol=1e-8)


# --- (c) settings translation -------------------------------------------------------------
def test_translate_osqp():
    assert qp_osqp.translate(PROFILES["default"]) == {}
    assert qp_osqp.translate(PROFILES["low"]) == {
        "eps_abs": 1e-3, "eps_rel": 1e-3, "polishing": False, "max_iter": 4000}
    assert qp_osqp.translate(PROFILES["mid"]) == {
        "eps_abs": 1e-6, "eps_rel": 1e-6, "polishing": True, "max_iter": 25_000}
    assert qp_osqp.translate(PROFILES["high"]) == {
        "eps_abs": 1e-9, "eps_rel": 1e-9, "polishing": True, "max_iter": 100_000}
    assert qp_osqp.translate(Settings("x", 1e-6, max_iter=77, time_limit=2.0)) == {
        "eps_abs": 1e-6, "eps_rel": 1e-6, "polishing": True, "max_iter": 77, "time_limit": 2.0}


def test_translate_clarabel():
    assert qp_clarabel.translate(PROFILES["default"]) == {}
    # the IPM's gap tolerance 1e-3 x lcpbench's natural-residual eps (qp_clarabel.GAP_FACTOR)
    for prof, eps in (("low", 1e-3), ("mid", 1e-6), ("high", 1e-9)):
        tol = 1e-3 * eps
        assert qp_clarabel.translate(PROFILES[prof]) == pytest.approx({
            "tol_gap_abs": tol, "tol_gap_rel": tol, "tol_feas": tol})
        assert qp_clarabel.translate(PROFILES[prof], 1.0) == pytest.approx({
            "tol_gap_abs": eps, "tol_gap_rel": eps, "tol_feas": eps})
    floor = qp_clarabel.translate(Settings("x", 1e-14, max_iter=50))
    assert floor["tol_feas"] == qp_clarabel.MIN_TOL and floor["max_iter"] == 50


def test_translate_proxsuite():
    assert qp_proxsuite.translate(PROFILES["default"]) == {}
    for prof, tol in (("low", 1e-3), ("mid", 1e-6), ("high", 1e-9)):
        assert qp_proxsuite.translate(PROFILES[prof]) == {
            "eps_abs": tol, "eps_rel": tol, "check_duality_gap": True,
            "eps_duality_gap_abs": tol, "eps_duality_gap_rel": tol}
    assert qp_proxsuite.translate(Settings("x", None, max_iter=9)) == {"max_iter": 9}


def test_translate_qpsolvers():
    T = qp_qpsolvers.translate
    assert T(PROFILES["default"], "daqp") == {}
    assert T(PROFILES["mid"], "daqp") == {"primal_tol": 1e-6, "dual_tol": 1e-6}
    # an interior point gets a tighter gap than eps: first qp_qpsolvers._FIRST_FACTORS,
    # then (where the first does not end SOLVED) _FACTORS
    assert T(PROFILES["high"], "piqp") == pytest.approx({
        "eps_abs": 1e-12, "eps_rel": 1e-12, "eps_duality_gap_abs": 1e-12,
        "eps_duality_gap_rel": 1e-12})
    assert T(PROFILES["high"], "piqp", first=False) == pytest.approx({
        "eps_abs": 1e-11, "eps_rel": 1e-11, "eps_duality_gap_abs": 1e-11,
        "eps_duality_gap_rel": 1e-11})
    assert T(PROFILES["default"], "piqp") == {}
    assert T(PROFILES["high"], "scs") == pytest.approx({"eps_abs": 1e-10, "eps_rel": 1e-10})
    assert T(PROFILES["high"], "scs", first=False) == {"eps_abs": 1e-9, "eps_rel": 1e-9}
    assert T(PROFILES["default"], "scs") == {}
    assert T(PROFILES["low"], "scs") == pytest.approx({"eps_abs": 1e-4, "eps_rel": 1e-4})
    assert T(PROFILES["low"], "highs") == {
        "primal_feasibility_tolerance": 1e-3, "dual_feasibility_tolerance": 1e-3,
        "qp_regularization_value": 1e-7}
    assert T(PROFILES["high"], "highs")["qp_regularization_value"] == 1e-9
    assert T(PROFILES["high"], "gurobi") == {"FeasibilityTol": 1e-9, "OptimalityTol": 1e-9}
    assert T(PROFILES["high"], "osqp") == qp_osqp.translate(PROFILES["high"])
    # through qpsolvers (which drops an AlmostSolved answer) Clarabel's tolerances are eps
    assert T(PROFILES["mid"], "clarabel") == {"tol_gap_abs": 1e-6, "tol_gap_rel": 1e-6,
                                              "tol_feas": 1e-6}
    assert T(PROFILES["mid"], "proxqp") == qp_proxsuite.translate(PROFILES["mid"])
    assert T(PROFILES["high"], "quadprog") == {}  # exact active set: ignores tol
    assert T(Settings("x", None, max_iter=5), "scs") == {"max_iters": 5}
    assert T(Settings("x", None, max_iter=5), "daqp") == {"iter_limit": 5}
    with pytest.raises(SolverNotFound):
        T(PROFILES["mid"], "no-such-solver")


def test_translate_cvxpy():
    T = qp_cvxpy.translate
    assert T(PROFILES["default"], "OSQP") == {}
    assert T(PROFILES["mid"], "OSQP") == {
        "eps_abs": 1e-6, "eps_rel": 1e-6, "polishing": True, "max_iter": 25_000}
    assert T(PROFILES["high"], "clarabel") == qp_clarabel.translate(PROFILES["high"], 1.0)
    assert T(PROFILES["low"], "SCS") == {"eps_abs": 1e-3, "eps_rel": 1e-3}
    assert T(PROFILES["mid"], "PROXQP") == {"eps_abs": 1e-6, "eps_rel": 1e-6}
    assert T(PROFILES["high"], "DAQP") == {"primal_tol": 1e-9, "dual_tol": 1e-9}
    assert T(PROFILES["high"], "MOSEK") == {}


def test_known_solvers_cover_qpsolvers():
    qps = pytest.importorskip("qpsolvers")
    installed = set(qp_qpsolvers.installed_solvers())
    assert set(qps.available_solvers) <= installed
    text = Path(qps.solvers.__file__).read_text()
    for name in qp_qpsolvers.KNOWN_SOLVERS:
        assert f'available_solvers.append("{name}")' in text
    assert text.count("available_solvers.append(") == len(qp_qpsolvers.KNOWN_SOLVERS)


# --- (d) infeasible and unbounded input ---------------------------------------------------
@pytest.mark.parametrize("name", list(BACKENDS))
def test_empty_box_is_infeasible(name):
    qp = box_qp(np.eye(2), [1.0, -1.0], [0.0, 1.0], [1.0, 0.5])  # row 1: 1 > 0.5
    res = run(name, qp, "mid")
    assert res.status is Status.INFEASIBLE
    assert np.isnan(res.x).all()


@pytest.mark.parametrize(("name", "case"), _grid(["unbounded"]))
def test_unbounded_is_not_solved(name, case):
    # ½ x0² - x0 + x1 with x1 unbounded below and P singular in x1
    qp = box_qp(np.diag([1.0, 0.0]), [-1.0, 1.0], [-1.0, -INF], [1.0, INF])
    res = run(name, qp, "mid")
    assert res.status is not Status.SOLVED, res.x


# --- lazy imports, versions, errors -------------------------------------------------------
def test_modules_import_no_native_library():
    code = ("import sys; import lcpbench.solvers.qp_osqp, lcpbench.solvers.qp_clarabel, "
            "lcpbench.solvers.qp_proxsuite, lcpbench.solvers.qp_qpsolvers, "
            "lcpbench.solvers.qp_cvxpy; "
            "bad = [m for m in ('osqp', 'clarabel', 'proxsuite', 'qpsolvers', 'cvxpy') "
            "if m in sys.modules]; assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_versions():
    for mod, dist in ((qp_osqp, "osqp"), (qp_clarabel, "clarabel"), (qp_proxsuite, "proxsuite"),
                      (qp_qpsolvers, "qpsolvers"), (qp_cvxpy, "cvxpy")):
        v = mod.version()
        assert (v is None) == (find_spec(dist) is None)


def test_qpsolvers_unknown_and_missing_solver():
    qp = box_qp([[1.0]], [1.0], [-1.0], [1.0])
    with pytest.raises(SolverNotFound, match="daqp"):
        qp_qpsolvers.solve_qp(qp, PROFILES["mid"], solver="nonesuch")
    with pytest.raises(SolverNotFound):
        qp_qpsolvers.solve_qp(qp, PROFILES["mid"])
    missing = [s for s in qp_qpsolvers.KNOWN_SOLVERS if s not in qp_qpsolvers.installed_solvers()]
    if missing:
        res = qp_qpsolvers.solve_qp(qp, PROFILES["mid"], solver=missing[0])
        assert res.status is Status.FAILED and "pip install" in res.message


def test_bad_input_raises():
    with pytest.raises(ValueError):
        qp_osqp.solve_qp(box_qp(np.eye(2), [1.0, 1.0], [0.0], [1.0]), PROFILES["mid"])
    with pytest.raises(ProblemError, match="variant"):
        qp_proxsuite.solve_qp(box_qp([[1.0]], [1.0], [0.0], [1.0]), PROFILES["mid"],
                              variant="banded")


def test_max_iter_is_a_status():
    qp = box_qp([[2.0, 1.0], [1.0, 2.0]], [-4.0, 4.0], [-INF, -1.0], [1.0, INF])
    res = qp_osqp.solve_qp(qp, Settings("tight", 1e-9, max_iter=3), check_termination=1,
                           polishing=False)
    assert res.status is Status.MAX_ITER and res.iterations == 3
    res = qp_clarabel.solve_qp(qp, Settings("tight", 1e-9, max_iter=1))
    assert res.status is Status.MAX_ITER

