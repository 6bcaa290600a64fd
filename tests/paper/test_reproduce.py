"""``lcpbench reproduce`` (issue 5, item 1), run once in quick mode.

Quick mode writes every file of the full run. The numbers are checked
against theory, the paper's own values and the trends the paper reports.
None of the expected values is taken from the code's output.
"""

import csv
import json
import math

import numpy as np
import pytest
from energy_oracle import energy_minimum

from lcpbench import ActuatorScene
from lcpbench.errors import ProblemError
from lcpbench.paper.data import QUICK
from lcpbench.paper.reproduce import reproduce
from lcpbench.studies.discretisation import discretisation_study

ELL, EI, W = 30.0, 32.01, 2.45e-4  # the paper's defaults (Sec. III-D, IV-B)
SAG = 5 * W * ELL**4 / (384 * EI)  # mid-span sag of a straight 30 mm beam under w (< 0.1 mm)

FILES = [
    "fig5-discretisation.png", "fig5-discretisation.csv", "fig5-discretisation.json",
    "fig6-shapes-theta.png", "fig6-shapes-theta.csv",
    "fig7-shapes-height.png", "fig7-shapes-height.csv",
    "fig8-forces.png", "fig8a-force-theta.csv", "fig8b-force-EI-theta150.csv",
    "fig8c-force-EI-h3.csv", "fig8.json",
    "fig10-cantilever.png", "fig10-cantilever.csv", "fig10-cantilever.json",
    "fig24-force-pressure.png", "fig24-force-pressure.csv", "fig24-force-pressure.json",
    "fig26-disagreement.png", "fig26-disagreement.csv",
    "fig27-shapes-baseline.png", "fig27-shapes-baseline.csv",
    "table1-equations.json", "table2-times.png", "table2-times.csv", "table2-times.json",
    "errata-gravity.json", "summary.json", "README.md",
]


def arc_height(theta_deg: float, length: float = ELL) -> float:
    """Rise of the unconstrained arc above its pins, from eq. (2): r(1 − cos θ/2), r = ℓ/θ."""
    t = math.radians(theta_deg)
    return length / t * (1 - math.cos(t / 2))


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    calls = []
    result = reproduce(out, quick=True, progress=lambda d, t, s: calls.append((d, t, s)))
    return out, result, calls


def _value(v: str):
    if v in ("True", "False"):
        return v == "True"
    try:
        return float(v)
    except ValueError:
        return v


def rows(out, name: str) -> list[dict]:
    with open(out / name, newline="") as f:
        return [{k: _value(v) for k, v in r.items()} for r in csv.DictReader(f)]


def load(out, name: str) -> dict:
    return json.loads((out / name).read_text())


def test_quick_run_writes_every_file_in_well_under_a_minute(run):
    out, result, calls = run
    for name in FILES:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
        if name.endswith(".png"):
            assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    assert set(FILES) <= set(result["files"])
    assert result["quick"] and result["elapsed_s"] > 0  # speed lives in benchmarks/
    assert calls[-1] == (len(calls), len(calls), "readme")
    assert [c[0] for c in calls] == list(range(1, len(calls) + 1))


def test_unknown_stage_is_refused(tmp_path):
    with pytest.raises(ProblemError, match="fig99"):
        reproduce(tmp_path, quick=True, stages=["fig99"])


def test_readme_puts_the_paper_beside_ours(run):
    out, _, _ = run
    text = (out / "README.md").read_text()
    for heading in ("Fig. 5", "Figs. 6 and 7", "Fig. 8", "Fig. 10", "Fig. 24", "Fig. 26",
                    "Fig. 27", "Table I", "Table II", "Errata"):
        assert heading in text, heading
    # the paper's printed values (Sec. III-G, Table II, Sec. III-D, Table I)
    for quoted in ("7.9 mN", "7.7 mN", "2.60 %", "24.7 ms", "140", "3N + 2", "1796.96",
                   "22847.96", "3.31", "0.1 %"):
        assert quoted in text, quoted
    assert "Quick mode" in text and "docs/errata.md" in text


def test_fig5_change_decays_at_rate_three(run):
    """A second-order chain: force error ∝ N^-2, so successive changes ∝ N^-3 (paper: ~3)."""
    out, _, _ = run
    curve = [r for r in rows(out, "fig5-discretisation.csv")
             if r["theta"] == 60 and r["height"] == 3 and r["links"] >= 40]
    n = np.array([r["links"] for r in curve])
    change = np.array([r["percent_change"] for r in curve])
    assert len(curve) >= 4 and np.all(np.diff(change) < 0)
    rate = -np.polyfit(np.log(n), np.log(change), 1)[0]
    assert rate == pytest.approx(3.0, abs=0.4)


def test_fig5_rule_is_the_discretisation_study(run):
    """The chosen N is the first whose change is below 0.01 % (Sec. III-D), per scene."""
    out, _, _ = run
    data = load(out, "fig5-discretisation.json")
    curves = rows(out, "fig5-discretisation.csv")
    for s in data["scenes"]:
        if s["chosen"] is None or s["chosen"] > data["curve_max_links"]:
            continue
        c = {r["links"]: r["percent_change"] for r in curves
             if r["theta"] == s["theta"] and r["height"] == s["height"]}
        assert c[s["chosen"]] < 0.01
        assert all(v >= 0.01 for n, v in c.items() if 10 < n < s["chosen"])
    study = discretisation_study(ActuatorScene(theta=60, height=3), solver="active-set",
                                 tol=1e-8)
    mine = next(s for s in data["scenes"] if s["theta"] == 60 and s["height"] == 3)
    assert mine["chosen"] == study.chosen
    assert data["grid_links"] == max(s["chosen"] for s in data["scenes"] if s["chosen"])


def test_fig6_7_shapes_flatten_and_stay_inside(run):
    """Sec. III-E: flattening grows as θ rises and h falls; the span grows as h falls."""
    out, result, _ = run
    for name in ("fig6-shapes-theta.csv", "fig7-shapes-height.csv"):
        nodes = rows(out, name)
        for key in {(r["theta"], r["height"]) for r in nodes}:
            sel = [r for r in nodes if (r["theta"], r["height"]) == key]
            x, y = np.array([r["x"] for r in sel]), np.array([r["y"] for r in sel])
            links = len(sel) - 1
            assert y[0] == 0 and abs(y[-1]) < 1e-9  # both pins on y = 0
            assert np.allclose(np.hypot(np.diff(x), np.diff(y)), ELL / links)  # rigid links
            assert y.max() <= key[1] + 1e-9  # never beyond the wall
    s = result["summary"]["fig6_7"]
    f7 = sorted(s["fig7"], key=lambda r: -r["height"])  # decreasing h
    assert np.all(np.diff([r["span"] for r in f7]) > 0)
    assert np.all(np.diff([r["touch_width"] for r in f7]) >= 0)
    assert all(r["span"] > r["free_span"] for r in f7 if r["total_force"] > 0)
    f6 = sorted(s["fig6"], key=lambda r: r["theta"])
    assert np.all(np.diff([r["touch_width"] for r in f6]) >= 0)
    assert f6[-1]["touch_width"] > 0  # θ = 180°, h = 2 mm lies on the wall over a length


def _monotone(rows_, group, along, strict_when_positive=True):
    for g in {r[group] for r in rows_}:
        sel = sorted((r for r in rows_ if r[group] == g), key=lambda r: r[along])
        f = np.array([r["total_force"] for r in sel])
        assert np.all(np.diff(f) >= 0), (group, g)
        if strict_when_positive:
            pos = f[f > 0]
            assert np.all(np.diff(pos) > 0), (group, g)


def test_fig8_force_rises_with_theta_and_EI_and_falls_with_h(run):
    """Sec. III-F: force rises with θ and EI; the lowest wall gives the largest force."""
    out, _, _ = run
    a = rows(out, "fig8a-force-theta.csv")
    assert all(r["converged"] for r in a)
    _monotone(a, "height", "theta")
    for th in {r["theta"] for r in a}:
        sel = sorted((r for r in a if r["theta"] == th), key=lambda r: -r["height"])
        f = np.array([r["total_force"] for r in sel])  # decreasing h
        assert np.all(np.diff(f) >= 0) and np.all(np.diff(f[f > 0]) > 0)
    _monotone(rows(out, "fig8b-force-EI-theta150.csv"), "height", "EI")
    _monotone(rows(out, "fig8c-force-EI-h3.csv"), "theta", "EI")


def test_fig8_no_force_while_the_arc_clears_the_wall(run):
    """The weight pulls away from the wall, so an arc below the wall cannot touch it."""
    out, _, _ = run
    for r in rows(out, "fig8a-force-theta.csv"):
        rise = arc_height(r["theta"])
        assert r["arc_height"] == pytest.approx(rise, rel=1e-12)
        if rise < r["height"]:
            assert r["total_force"] == 0
        if rise > r["height"] + 2 * SAG:
            assert r["total_force"] > 0


def test_fig8_undamped_and_globalised_agree_where_both_converge(run):
    """Both iterations stop at a fixed point of the same equilibrium equations: each
    force is the energy minimum's (tests/energy_oracle.py) to the success rule at the
    default tol 1e-3 (τ = 1e-3 F₀; measured ≤ 2e-4), and they agree with each other."""
    out, _, _ = run
    both = [r for r in rows(out, "fig8a-force-theta.csv") if r["undamped_converged"]]
    assert both
    for r in both:
        scene = ActuatorScene(theta=r["theta"], height=r["height"], links=QUICK.links)
        want = energy_minimum(scene).total_force
        F0 = max(want, scene.EI / scene.length**2)
        assert abs(r["total_force"] - want) <= 1e-3 * F0
        assert abs(r["undamped_total_force"] - want) <= 1e-3 * F0
        assert r["undamped_total_force"] == pytest.approx(r["total_force"], rel=1e-6,
                                                          abs=1e-12)


def test_cantilever_within_0p1_percent_and_the_paper_like_chain_gives_7p9_mN(run):
    """Sec. III-G: theory by eqs. (34)–(37); the paper's model gave 7.9 mN."""
    out, _, _ = run
    d = load(out, "fig10-cantilever.json")
    F, h = 0.001, 1.0
    f_c = 8 * EI * h / ELL**4  # eq. (34)
    theory = 3 * EI * ((F - f_c) * ELL**4 / (8 * EI)) / ELL**3  # eqs. (35)-(37)
    assert d["links"] == 140 and d["converged"]
    assert d["theory_force"] == pytest.approx(theory, rel=1e-12)
    assert abs(d["model_force"] / theory - 1) < 1e-3
    assert d["contact_nodes"] == [141]  # theory: the free end only
    assert round(1e3 * d["paper_like_force"], 1) == 7.9  # the paper's value
    assert d["order"] == pytest.approx(2.0, abs=0.1)
    assert d["order_paper_like"] == pytest.approx(1.0, abs=0.1)
    assert d["free_max_distance"] < 8e-3  # the paper's bound (Fig. 10a)
    assert d["held_max_y"] <= h + 1e-9


def test_fig24_band_contains_the_line_and_force_rises_with_pressure(run):
    """The band edges are the EI/w corners: force rises with EI and falls with w."""
    out, _, _ = run
    data = rows(out, "fig24-force-pressure.csv")
    fits = {"1": (0.81, 9.78), "2": (0.52, 7.84), "3": (0.65, 12.1)}  # eqs. (40)-(42)
    for r in data:
        m, b = fits[str(int(r["actuator"]))]
        assert r["theta"] == pytest.approx(m * r["pressure_kpa"] + b, rel=1e-12)
        assert r["converged"] and r["lower_wall_force"] == 0
        lo, hi = r["force_lo"], r["force_hi"]
        for v in (r["total_force"], r["force_min_min"], r["force_max_max"]):
            assert lo - 1e-12 <= v <= hi + 1e-12
    for key in {(r["actuator"], r["height"]) for r in data}:
        sel = sorted((r for r in data if (r["actuator"], r["height"]) == key),
                     key=lambda r: r["pressure_kpa"])
        assert np.all(np.diff([r["total_force"] for r in sel]) >= 0)


def test_fig24_no_force_before_the_arc_reaches_the_wall(run):
    out, _, _ = run
    for r in rows(out, "fig24-force-pressure.csv"):
        if arc_height(r["theta"]) < r["height"]:
            assert r["total_force"] == r["force_hi"] == 0
    for o in load(out, "fig24-force-pressure.json")["onset"]:
        assert arc_height(o["onset_theta"]) == pytest.approx(o["height"], rel=1e-9)


def test_fig26_baseline_agrees_within_0p1_percent_from_4mm(run):
    """Appendix: disagreement below 0.1 % for h >= 4 mm (Fig. 26)."""
    out, _, _ = run
    data = rows(out, "fig26-disagreement.csv")
    high = [r for r in data if r["height"] >= 4 and r["lcp_force"] > 0]
    assert high
    for r in high:
        assert r["analytic_valid"]
        assert r["analytic_disagreement_percent"] < 0.1


def test_fig27_baseline_penetrates_at_1mm_and_lcp_does_not(run):
    """Fig. 27(b): the single-reaction shape bows out beyond the wall; the LCP stays inside."""
    out, _, _ = run
    low = [r for r in rows(out, "fig26-disagreement.csv") if r["height"] == 1]
    assert low and not any(r["analytic_valid"] for r in low)
    shape = [r for r in rows(out, "fig27-shapes-baseline.csv") if r["height"] == 1]
    y_nl = np.array([r["y_nonlinear"] for r in shape])
    y_lcp = np.array([r["y_lcp"] for r in shape])
    assert y_nl.max() > 1.0 + 1e-3 and y_lcp.max() <= 1.0 + 1e-9
    assert y_nl[len(shape) // 2] == pytest.approx(1.0, abs=1e-8)  # eq. (45): midspan at h


def test_table1_counts_3N_plus_2(run):
    out, _, _ = run
    for r in load(out, "table1-equations.json")["rows"]:
        assert r["nonlinear_equations"] == 3 * r["links"] + 2
        assert r["lcp_unknowns"] == r["links"] - 1


def test_table2_normalised_to_the_fastest_lcp(run):
    out, _, _ = run
    data = rows(out, "table2-times.csv")
    assert all(r["lcp_converged"] and r["height"] == 1 for r in data)
    best = min(r["lcp_s"] for r in data)
    assert min(r["lcp_norm"] for r in data) == 1.0
    for r in data:
        for k in ("lcp", "analytic", "fd", "fdlm"):
            assert r[f"{k}_norm"] == pytest.approx(r[f"{k}_s"] / best)
    assert {r["theta"] for r in data} <= set(range(40, 181))


def test_contact_below_40_degrees_at_1mm_follows_from_the_arc_height(run):
    """Table II's note says θ < 40° does not touch at h = 1 mm; eq. (2) says 20° and 30° do."""
    out, _, _ = run
    below = {r["theta"]: r for r in load(out, "table2-times.json")["below_40"]}
    assert arc_height(10) < 1.0 and below[10]["total_force"] == 0
    for th in (20, 30):
        assert arc_height(th) > 1.0 + 2 * SAG and below[th]["total_force"] > 0


def test_a_second_run_leaves_files_whose_numbers_did_not_change(run):
    """Issue 15: reproduce must not rewrite committed files for round-off changes. The
    shapes of Figs. 6-7 are deterministic, so a rerun writes none of their files; the
    summary carries this run's times, so it is written."""
    import os

    out, _, _ = run
    names = ["fig6-shapes-theta.csv", "fig7-shapes-height.csv", "fig6-shapes-theta.png",
             "fig7-shapes-height.png"]
    for name in names:
        os.utime(out / name, (1e9, 1e9))
    again = reproduce(out, quick=True, stages=["fig6_7"])
    assert set(names) <= set(again["unchanged"])
    assert "summary.json" in again["written"]
    for name in names:
        assert (out / name).stat().st_mtime == 1e9
    assert not [p for p in out.iterdir() if p.name.startswith(".staging")]
