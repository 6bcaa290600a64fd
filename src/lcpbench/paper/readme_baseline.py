"""README sections against the baseline (Figs. 26-27, Tables I-II), errata, differences.

Each function takes the stage results of :mod:`lcpbench.paper.baseline_figures`
(and, for :func:`differences`, the whole summary) and returns Markdown.
"""

from __future__ import annotations

import math

from ..problems.calibrations import PAPER_PRESSURE_RANGE
from ..problems.scenes import DEFAULT_EI, DEFAULT_LENGTH, DEFAULT_WEIGHT
from .data import PAPER, RULE_THRESHOLD
from .figures import onset_theta
from .markdown import TESTS, md_table, millinewtons, num, scene_list


def baseline_section(s: dict) -> str:
    f26, f27, t1, t2 = s["fig26"], s["fig27"], s["table1"], s["table2"]
    rows26 = [[f"{float(h):g}", num(v["max_disagreement_percent"], ".2g"),
               f"{v['converged']}/{v['scenes']}", f"{v['valid']}/{v['scenes']}",
               num(v["max_penetration"], ".2g"), f"{v['fd_converged']}/{v['scenes']}"]
              for h, v in f26["per_height"].items()]
    rows27 = [[f"{p['height']:g}", millinewtons(p["lcp_force"]), millinewtons(p["nl_force"]),
               p["nl_status"], num(p["nl_max_penetration"], ".2g"),
               num(p["max_shape_difference"], ".2g")] for p in f27["panels"]]
    rows1 = [[str(r["links"]), "3N + 2 = " + str(3 * r["links"] + 2),
              str(r["nonlinear_equations"]), str(r["lcp_unknowns"])] for r in t1["rows"]]
    paper = PAPER["table2"]
    pmap = dict(zip(paper["thetas"], zip(paper["nonlinear"], paper["lcp"])))
    rows2 = []
    for r in t2["rows"]:
        pn, pl = pmap.get(int(r["theta"]), (None, None))

        def cell(k, r=r):
            return f"{num(r[f'{k}_norm'], '.3g')}{'' if r[f'{k}_valid'] else ' ✗'}"

        rows2.append([f"{r['theta']:g}", num(pn, ".2f"), num(pl, ".2f"),
                      num(r["lcp_norm"], ".2f"), num(r["undamped_norm"], ".2f"),
                      cell("analytic"), cell("fd"), cell("fdlm")])
    ratio, lm = t2["analytic_over_lcp"], t2["fdlm_over_lcp"]
    p_ratio = [n / lc for n, lc in zip(paper["nonlinear"], paper["lcp"])]
    onset1, sag = onset_theta(1.0), 5 * DEFAULT_WEIGHT * DEFAULT_LENGTH**4 / (384 * DEFAULT_EI)
    below = "; ".join(f"{b['theta']:g}°: the arc rises {b['arc_height']:.2f} mm, force "
                      f"{millinewtons(b['total_force'], '.3g')}" for b in t2["below_40"])
    und = [(r["theta"], r["height"]) for r in t2["rows"] if not r["undamped_converged"]]
    und26 = [(t, h) for t, h, _ in f26["undamped_failures"]]
    first, last = t2["rows"][0], t2["rows"][-1]
    valid4 = ("Every scene in contact is valid there." if f26["valid_from_4mm"]
              else "Not every scene in contact is valid there.")
    return f"""## Figs. 26–27, Tables I–II: the LCP against the root-finding baseline

The baseline is the paper's appendix model (`lcpbench.model.baseline`). It
has one reaction, at the midspan node, and 3N + 2 exact equilibrium
equations. MINPACK solves them through scipy, with an analytic Jacobian or
with forward differences (what `fsolve` does unless it is given a
Jacobian). An answer counts as *valid* only if no node is beyond the wall
and R ≥ 0.

### Table I

{md_table(["N", "paper", "equations in our system", "LCP unknowns (N − 1)"], rows1)}

The paper counts 5 LCP equations (eqs. 3, 8, 11, 17, 18), against 3N + 2
for the nonlinear system. Our `BaselineSystem` has exactly 3N + 2 rows
(`{TESTS}::test_table1_counts_3N_plus_2`,
`tests/model/test_baseline.py::test_analytic_jacobian_matches_central_differences`).

### Fig. 26: disagreement in total force

Files: `fig26-disagreement.{{png,csv}}`. θ = 40°–180° by 10°, h = 1–7 mm,
N = {f26['links']}. The disagreement is |R_LCP − R_NL| / (R_LCP + R_NL) × 100,
as in the paper, taken over the scenes where the baseline solved its
equations.

{md_table(["h (mm)", "largest disagreement (%)", "baseline solved", "baseline valid",
            "baseline beyond the wall by up to (mm)", "finite differences (hybr) solved"],
           rows26)}

The paper (plot only): below 0.1 % for h ≥ 4 mm, larger at 3 mm and below.

Ours for h ≥ 4 mm: at most {num(f26['max_disagreement_from_4mm'], '.1e')} %.
{valid4} This is far below 0.1 % for two reasons:

* at these heights the LCP touches only at the midspan node, so the two
  models are the same equations, both solved to round-off;
* the paper's iteration stopped at 1e-3 rad, which by itself leaves about
  1e-4 of the force.

At h ≤ 3 mm the LCP touches in two patches away from midspan, which the
single-reaction model cannot represent. Its answer pokes through the wall
(invalid) and disagrees by the percentages above. The scenes at h ≥ 4 mm
counted invalid are those without contact, where the single-reaction model
needs a pulling wall.

Finite differences with the hybrid method (fsolve's default) solved
{f26['fd_converged']} of {f26['scenes']} scenes at N = {f26['links']}.
MINPACK stops after about 2 Jacobians of 3N + 3 evaluations each ("not
making good progress"), so Fig. 26 uses the analytic Jacobian.

The paper's undamped iteration (Fig. 3), run on the same grid, failed on:
{scene_list(f26['undamped_failures'])}. Elsewhere it reaches the LCP's
equilibrium (largest relative difference
{num(f26['undamped_max_relative_difference'], '.1e')}).

Shown by `{TESTS}::test_fig26_baseline_agrees_within_0p1_percent_from_4mm`
and `tests/model/test_baseline.py::test_total_force_agrees_with_the_lcp_model_within_0p1_percent`.

### Fig. 27: shapes at θ = 150°

Files: `fig27-shapes-baseline.{{png,csv}}`.

{md_table(["h (mm)", "LCP force", "baseline force", "baseline status",
            "baseline beyond the wall (mm)", "largest node distance LCP–baseline (mm)"],
           rows27)}

This matches the paper:

* at 3 mm the shapes are close. The baseline pokes
  {num(f27['panels'][0]['nl_max_penetration'], '.1g')} mm through the wall,
  which is invisible at the figure's scale;
* at 1 mm the baseline's chain bows out through the wall on either side of
  the midspan node. The LCP's chain stays inside and touches in two patches.

Shown by `{TESTS}::test_fig27_baseline_penetrates_at_1mm_and_lcp_does_not`
and `tests/model/test_baseline.py::test_breakdown_at_small_height_is_not_reported_as_a_valid_answer`.

### Table II: computation time at h = 1 mm, N = {t2['links']}

Files: `table2-times.{{png,csv,json}}`. Each study's times are divided by
its own fastest LCP solve: 24.7 ms in the paper, {t2['fastest_ms']:.3g} ms
in ours (θ = {t2['fastest_theta']:g}°). What was timed:

* LCP: `lcpbench.solve(scene)` with the default back-end
  (`{t2['backend']}`) and the paper's 1e-3 rad; the wall time of the call,
  median of {t2['lcp_repeats']};
* baselines: median of {t2['baseline_repeats']} (Levenberg–Marquardt: one
  run).

Repeats run round-robin over the angles. ✗ marks an answer that is not
valid: solved but beyond the wall, or not solved. The paper timed its
breakdown cases too. Machine: {t2['machine']}; load average
{t2['load_average']:.1f} while timing (the 2 cores were shared with another
benchmark).

{md_table(["θ (°)", "paper: nonlinear", "paper: LCP", "ours: LCP", "ours: LCP undamped",
            "ours: root finding, analytic", "ours: finite diff. (hybr)",
            "ours: finite diff. (LM)"], rows2)}

* **LCP trend.** Our LCP time grows by a factor of {last['lcp_norm']:.2f}
  from 40° to 180° (paper: 3.31). It follows the number of contact steps,
  {first['lcp_outer']} to {last['lcp_outer']}.
* **Absolute LCP time: {t2['fastest_ms']:.2g} ms instead of 24.7 ms.** Our
  step is assembled from the energy in banded form and solved by an active
  set, in O(N) per step. The paper used the dense A⁻¹ of eqs. (27)–(31) and
  a dense LCP solver. The machine also differs (the paper: Intel Core
  i7-9700K, MATLAB).
* **Nonlinear/LCP ratio: {min(ratio):.0f}–{max(ratio):.0f} with the
  analytic Jacobian and {min(lm):.0f}–{max(lm):.0f} with finite differences
  (LM), instead of {min(p_ratio):.0f}–{max(p_ratio):.0f}.** The LCP is still
  faster, by {math.log10(min(ratio)):.1f} to {math.log10(max(lm)):.1f}
  orders of magnitude, not 3 to 4. Two things explain the gap:
  * an analytic Jacobian costs one evaluation; finite differences cost
    3N + 3 = {3 * t2['links'] + 3};
  * MINPACK is not MATLAB's `fsolve`, whose default is a trust-region
    dogleg.

  Finite differences with Levenberg–Marquardt are our closest stand-in for
  the paper's solver, and they give the times nearest the paper's.
* **The paper's undamped iteration diverges in ours at h = 1 mm for
  {', '.join(f'{t:g}°' for t, _ in sorted(set(und) | {x for x in und26 if x[1] == 1}))
   or 'no angle'}.** A link passes the vertical, where the linearisation of
  eq. (20) is singular. The paper reports a time for 180° (3.31), so its run
  must have differed in something it does not print. All our numbers come
  from the globalised driver, a line search on the exact energy. It
  converges here, to an equilibrium certified on the exact geometry, and
  wherever both converge it reaches the same equilibrium as the undamped
  iteration. Shown by `table2-times.csv` (`undamped_converged`),
  `tests/model/test_driver.py::test_undamped_paper_iteration_fails_cleanly_where_the_linearisation_breaks`
  and `::test_undamped_and_globalised_agree_where_both_converge`.
* **"Bend angles less than 40° were not in contact" does not hold at
  h = 1 mm.** By eq. (2) the unconstrained arc rises above a 1 mm wall from
  θ = {onset1:.1f}° ({below}). The self-weight lowers a straight 30 mm span by
  5wℓ⁴/(384 EI) = {sag:.3f} mm, far too little to change that.
  We keep the paper's 40°–180° for the table. Shown by `table2-times.json`
  (`below_40`) and
  `{TESTS}::test_contact_below_40_degrees_at_1mm_follows_from_the_arc_height`.
"""


def errata_section(e: dict) -> str:
    rows = [[f"{r['theta']:g}", f"{r['height']:g}", millinewtons(r["force"]),
             millinewtons(r["force_printed_gamma"]), f"{100 * r['relative_change']:+.2f} %",
             millinewtons(r["force_no_weight"])] for r in e["rows"]]
    return f"""## Errata: what the misprints would change

docs/errata.md lists two misprints. They were found by comparing the
paper-faithful dense assembly with the energy-based one
(`tests/model/test_assembly.py`).

* **Eq. (13).** γ carries a stray factor a/2, so the self-weight would enter
  the step multiplied by a/2 (in mm). We use the corrected γ. The paper does
  not say whether its code carried the misprint. If it did, its forces would
  be larger than ours by the amounts below (`errata-gravity.json`). The
  printed γ amounts to the corrected model with w replaced by w·a/2. Figs. 8
  and 24 are plots, so the text cannot settle it.

{md_table(["θ (°)", "h (mm)", "ours", "with the printed γ", "change", "without weight"],
           rows)}

* **Eqs. (25)–(27).** 1/a multiplies v, which is already an angle. This
  misprint does not reach any number: eq. (31), from which K and z are
  built, is printed correctly.
"""


def differences(s: dict) -> str:
    f5, c, t2, f26, f24, e = (s["fig5"], s["cantilever"], s["table2"], s["fig26"],
                              s["fig24"], s["errata"])
    paper = PAPER["table2"]
    p_ratio = [n / lc for n, lc in zip(paper["nonlinear"], paper["lcp"])]
    und = sorted({t for t, h, _ in f26["undamped_failures"] if h == 1}
                 | {r["theta"] for r in t2["rows"] if not r["undamped_converged"]})
    late = sum(o["force_at_knee"] == 0 for o in f24["onset"])
    never = [o for o in f24["onset"] if o["onset_pressure_kpa"] > PAPER_PRESSURE_RANGE[1]]
    ch = [100 * r["relative_change"] for r in e["rows"]]
    ok140 = math.isfinite(f5["max_change_at_140"]) and f5["max_change_at_140"] < RULE_THRESHOLD
    never_txt = (" and never touches for " + ", ".join(
        f"actuator {o['actuator']} at {o['height']:g} mm" for o in never)) if never else ""
    passes = " N = 140 passes the paper's own test (every change at 140 is below 0.01 %)." \
        if ok140 else ""
    return f"""1. **Sec. III-D / Fig. 5.** The rule picks N = {num(f5['grid_links'], 'd')}, not 140.{passes}
   The rule's pick is set by near-grazing scenes and by contact patches that move by a
   node as N changes. The change decays at rate {num(f5['rate_median'], '.2f')}, matching
   the paper's "about three".
2. **Sec. III-G / Fig. 10.** Our cantilever gives {millinewtons(c['model_force'])} against
   {millinewtons(c['theory_force'])} from beam theory ({100 * c['relative_error']:+.3f} %). The
   paper gives 7.9 against 7.7 mN (2.60 %). The difference is the clamp and where the
   load acts. With the clamp as an ordinary joint (EI/a) and the loads at the nodes, we
   get the paper's 7.9 mN ({millinewtons(c['paper_like_force'])}).
3. **Table II, absolute times.** Our fastest LCP solve takes {t2['fastest_ms']:.2g} ms,
   not 24.7 ms. The baseline is {min(t2['analytic_over_lcp']):.0f}–{
   max(t2['analytic_over_lcp']):.0f}× slower with the analytic Jacobian and {
   min(t2['fdlm_over_lcp']):.0f}–{max(t2['fdlm_over_lcp']):.0f}× slower with finite
   differences (LM). The paper reports {min(p_ratio):.0f}–{max(p_ratio):.0f}×. Three
   things differ: our step is banded and O(N), our Jacobian is analytic, and we use
   MINPACK rather than MATLAB.
4. **Table II, h = 1 mm: the paper's undamped iteration diverges in ours at
   {', '.join(f'{t:g}°' for t in und) or 'no angle'}.** Our globalised driver converges
   there. Where both converge, they agree.
5. **Table II, "no contact below 40°" at h = 1 mm.** By eq. (2) the arc reaches the
   wall from θ = {onset_theta(1.0):.1f}°. Ours has forces at 20° and 30°.
6. **Fig. 26.** For h ≥ 4 mm the disagreement is at most
   {num(f26['max_disagreement_from_4mm'], '.0e')} %, far inside the paper's 0.1 %. At
   these heights the two models are the same equations, and we solve both to round-off
   rather than to 1e-3 rad. Finite differences with the hybrid method (fsolve's default)
   solve {f26['fd_converged']} of {f26['scenes']} scenes, so Fig. 26 uses the analytic
   Jacobian.
7. **Fig. 24.** With ℓ = 30 mm and eqs. (40)–(42), our model gives no force at the
   paper's knee pressure in {late} of {len(f24['onset'])} cases{never_txt}. The paper
   used a measured section length that it does not print.
8. **Errata.** We use the corrected γ of eq. (13). If the paper's code carried the
   misprint, its forces would be {min(ch):+.1f} % to {max(ch):+.1f} % off ours in the
   scenes we checked; the largest change is near first contact. The figures are plots,
   so the text cannot settle this. The eq. (25) misprint changes nothing.
9. **Sec. III-F.** "EI from 10 to 100 N·mm" is a slip for N·mm²."""


