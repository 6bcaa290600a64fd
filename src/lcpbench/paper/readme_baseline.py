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
from .markdown import TESTS, md_table, millinewtons, num, render, scene_list


def baseline_section(s: dict) -> str:
    """The Figs. 26-27 and Tables I-II section: the LCP against the appendix's baseline.

    Parameters
    ----------
    s : dict
        The run's summary (stages ``fig26``, ``fig27``, ``table1``, ``table2``).

    Returns
    -------
    str
        Markdown, filled in from ``templates/baseline.md``.
    """
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
    head_table26 = [
        'h (mm)',
        'largest disagreement (%)',
        'baseline solved',
        'baseline valid',
        'baseline beyond the wall by up to (mm)',
        'finite differences (hybr) solved',
    ]
    head_table27 = [
        'h (mm)',
        'LCP force',
        'baseline force',
        'baseline status',
        'baseline beyond the wall (mm)',
        'largest node distance LCP–baseline (mm)',
    ]
    head_table2 = [
        'θ (°)',
        'paper: nonlinear',
        'paper: LCP',
        'ours: LCP',
        'ours: LCP undamped',
        'ours: root finding, analytic',
        'ours: finite diff. (hybr)',
        'ours: finite diff. (LM)',
    ]
    und_h1 = sorted(set(und) | {x for x in und26 if x[1] == 1})
    return render(
        "baseline.md",
        table1=md_table(['N', 'paper', 'equations in our system', 'LCP unknowns (N − 1)'], rows1),
        TESTS=TESTS,
        fig26_links=f26['links'],
        table26=md_table(head_table26, rows26),
        max_disagreement_from_4mm=num(f26['max_disagreement_from_4mm'], '.1e'),
        valid4=valid4,
        fd_converged=f26['fd_converged'],
        scenes=f26['scenes'],
        undamped_failures=scene_list(f26['undamped_failures']),
        undamped_max_relative_difference=num(f26['undamped_max_relative_difference'], '.1e'),
        table27=md_table(head_table27, rows27),
        nl_max_penetration=num(f27['panels'][0]['nl_max_penetration'], '.1g'),
        table2_links=t2['links'],
        fastest_ms_3g=f"{t2['fastest_ms']:.3g}",
        fastest_theta=f"{t2['fastest_theta']:g}",
        backend=t2['backend'],
        lcp_repeats=t2['lcp_repeats'],
        baseline_repeats=t2['baseline_repeats'],
        machine=t2['machine'],
        load_average=f"{t2['load_average']:.1f}",
        table2=md_table(head_table2, rows2),
        lcp_growth=f"{last['lcp_norm']:.2f}",
        first_outer=first['lcp_outer'],
        last_outer=last['lcp_outer'],
        fastest_ms_2g=f"{t2['fastest_ms']:.2g}",
        ratio_min=f'{min(ratio):.0f}',
        ratio_max=f'{max(ratio):.0f}',
        lm_min=f'{min(lm):.0f}',
        lm_max=f'{max(lm):.0f}',
        paper_ratio_min=f'{min(p_ratio):.0f}',
        paper_ratio_max=f'{max(p_ratio):.0f}',
        decades_min=f'{math.log10(min(ratio)):.1f}',
        decades_max=f'{math.log10(max(lm)):.1f}',
        fd_evaluations=3 * t2['links'] + 3,
        undamped_failures_h1=', '.join(f'{t:g}°' for t, _ in und_h1) or 'no angle',
        onset_theta_h1=f'{onset1:.1f}',
        below=below,
        sag=f'{sag:.3f}',
    )


def errata_section(e: dict) -> str:
    """The errata section: what the eq. (13) misprint of γ would change.

    Parameters
    ----------
    e : dict
        What :func:`~lcpbench.paper.baseline_figures.errata_gravity` returned.

    Returns
    -------
    str
        Markdown, filled in from ``templates/errata.md``.
    """
    rows = [[f"{r['theta']:g}", f"{r['height']:g}", millinewtons(r["force"]),
             millinewtons(r["force_printed_gamma"]), f"{100 * r['relative_change']:+.2f} %",
             millinewtons(r["force_no_weight"])] for r in e["rows"]]
    head_table = [
        'θ (°)',
        'h (mm)',
        'ours',
        'with the printed γ',
        'change',
        'without weight',
    ]
    return render(
        "errata.md",
        table=md_table(head_table, rows),
    )


def differences(s: dict) -> str:
    """The numbered list of where our numbers differ from the paper's, and why.

    Parameters
    ----------
    s : dict
        The run's summary (every stage).

    Returns
    -------
    str
        Markdown, filled in from ``templates/differences.md``.
    """
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
    return render(
        "differences.md",
        grid_links=num(f5['grid_links'], 'd'),
        passes=passes,
        rate_median=num(f5['rate_median'], '.2f'),
        model_force=millinewtons(c['model_force']),
        theory_force=millinewtons(c['theory_force']),
        relative_error=f"{100 * c['relative_error']:+.3f}",
        paper_like_force=millinewtons(c['paper_like_force']),
        fastest_ms=f"{t2['fastest_ms']:.2g}",
        analytic_ratio_min=f"{min(t2['analytic_over_lcp']):.0f}",
        analytic_ratio_max=f"{max(t2['analytic_over_lcp']):.0f}",
        fdlm_ratio_min=f"{min(t2['fdlm_over_lcp']):.0f}",
        fdlm_ratio_max=f"{max(t2['fdlm_over_lcp']):.0f}",
        paper_ratio_min=f'{min(p_ratio):.0f}',
        paper_ratio_max=f'{max(p_ratio):.0f}',
        undamped_failures_h1=', '.join(f'{t:g}°' for t in und) or 'no angle',
        onset_theta=f'{onset_theta(1.0):.1f}',
        max_disagreement_from_4mm=num(f26['max_disagreement_from_4mm'], '.0e'),
        fd_converged=f26['fd_converged'],
        scenes=f26['scenes'],
        late_cases=late,
        onset_cases=len(f24['onset']),
        never_txt=never_txt,
        errata_change_min=f'{min(ch):+.1f}',
        errata_change_max=f'{max(ch):+.1f}',
    )