"""The paper's numbers as data, and the grids of a ``reproduce`` run.

Every number quoted from *Novel Contact Modeling for High Aspect Ratio Soft
Robots* (``paper/contact-model-paper.txt``) that the regenerated README sets
beside ours lives in :data:`PAPER`, keyed by the figure, table or section it
comes from:

===============  =================================================================
key              source in the paper
===============  =================================================================
``fig5``         Sec. III-D and Fig. 5: the 0.01 % rule, N = 140, rate "about three"
``cantilever``   Sec. III-G, eqs. (33)-(37), Fig. 10: 7.9 mN against 7.7 mN, 2.60 %
``table1``       Table I: 3N + 2 nonlinear equations against 5 for the LCP
``table2``       Table II: normalised times at h = 1 mm, N = 140; 24.7 ms fastest
``fig26``        Fig. 26 and its text: below 0.1 % disagreement from h = 4 mm
``fig24``        Fig. 24, Secs. IV-C and V-E: knee pressures, 1 gf, 20 gf, errors
===============  =================================================================

:class:`Plan` holds the grids of one run: :data:`FULL` is the paper's,
:data:`QUICK` a coarse smoke run for the tests.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

DEFAULT_OUT = Path("results") / "paper"
SOLVER = "active-set"  # exact; the figures must not depend on a cached selection
TOL = 1e-8  # rad: the figures show the model, not the driver's truncation
PAPER_TOL = 1e-3  # rad, eq. (32): what Table II times
RULE_THRESHOLD = 0.01  # percent, Sec. III-D
GF = 9.80665e-3  # N per gram-force

#: What the paper prints (quoted from its text; "plot only" where it gives none).
PAPER = {
    "fig5": {"links": 140, "threshold_percent": 0.01, "step": 10, "rate": 3.0,
             "thetas": "10-180 deg by 10", "heights": "2-7 mm by 1"},
    "cantilever": {"model_mN": 7.9, "theory_mN": 7.7, "difference_percent": 2.60,
                   "deflection_difference_max": 8e-3, "links": 140, "load": 0.001,
                   "height": 1.0},
    "table1": {"nonlinear": "3N+2", "lcp": 5},
    "table2": {"fastest_ms": 24.7, "height": 1.0, "links": 140,
               "thetas": [40, 60, 80, 100, 120, 140, 160, 180],
               "nonlinear": [1796.96, 1723.37, 2007.18, 2014.69, 11506.69, 15527.64,
                             19608.82, 22847.96],
               "lcp": [1.0, 1.52, 1.63, 1.60, 2.13, 2.14, 2.07, 3.31],
               "no_contact_below_deg": 40.0},
    "fig26": {"agreement_percent": 0.1, "from_height": 4.0},
    "fig24": {"knee_kpa": {4.5: 68.95, 5.5: 103.42, 6.5: 120.66}, "low_force_gf": 1.0,
              "max_measured_gf": 20.0, "error_low_percent": 45.34,
              "error_high_percent": 20.98},
}


@dataclass(frozen=True)
class Plan:
    """The grids of one run (full: the paper's; quick: a coarse run for the tests)."""

    quick: bool
    links: int
    fig5_thetas: tuple[float, ...]
    fig5_heights: tuple[float, ...]
    fig5_plot_height: float
    fig5_max_links: int
    fig6_thetas: tuple[float, ...]
    fig7_heights: tuple[float, ...]
    fig8a_thetas: tuple[float, ...]
    fig8_heights: tuple[float, ...]
    fig8_EIs: tuple[float, ...]
    fig8c_thetas: tuple[float, ...]
    cantilever_links: tuple[int, ...]
    fig24_pressures: int
    fig26_thetas: tuple[float, ...]
    fig26_heights: tuple[float, ...]
    table2_thetas: tuple[float, ...]
    lcp_repeats: int
    baseline_repeats: int


def _span(start: float, stop: float, step: float) -> tuple[float, ...]:
    """``start, start + step, …, stop`` (inclusive) as floats."""
    return tuple(float(v) for v in np.arange(start, stop + step / 2, step))


FULL = Plan(
    quick=False, links=140,
    fig5_thetas=_span(10, 180, 10), fig5_heights=_span(2, 7, 1), fig5_plot_height=3.0,
    fig5_max_links=200,
    fig6_thetas=(30.0, 60.0, 90.0, 120.0, 150.0, 180.0), fig7_heights=_span(1, 8, 1),
    fig8a_thetas=_span(5, 180, 5), fig8_heights=_span(2, 7, 1), fig8_EIs=_span(10, 100, 5),
    fig8c_thetas=_span(10, 180, 10),
    cantilever_links=(35, 70, 140, 280), fig24_pressures=41,
    fig26_thetas=_span(40, 180, 10), fig26_heights=_span(1, 7, 1),
    table2_thetas=_span(40, 180, 20), lcp_repeats=21, baseline_repeats=3,
)
QUICK = Plan(
    quick=True, links=40,
    fig5_thetas=(60.0, 150.0), fig5_heights=(3.0,), fig5_plot_height=3.0, fig5_max_links=80,
    fig6_thetas=(60.0, 120.0, 180.0), fig7_heights=(2.0, 4.0, 6.0),
    fig8a_thetas=(20.0, 60.0, 100.0, 140.0, 180.0), fig8_heights=(2.0, 4.0, 6.0),
    fig8_EIs=(10.0, 55.0, 100.0), fig8c_thetas=(60.0, 120.0, 180.0),
    cantilever_links=(20, 40, 80), fig24_pressures=6,
    fig26_thetas=(90.0, 150.0, 180.0), fig26_heights=(1.0, 3.0, 4.0, 6.0),
    table2_thetas=(40.0, 110.0, 180.0), lcp_repeats=3, baseline_repeats=1,
)


