"""The paper's numbers as data (:mod:`lcpbench.paper.data`), checked against the paper's text."""

import math

from lcpbench.paper.data import FULL, GF, PAPER, QUICK, RULE_THRESHOLD


def test_table2_rows_are_complete_and_normalised_by_the_fastest_lcp_solve():
    t2 = PAPER["table2"]
    assert len(t2["thetas"]) == len(t2["nonlinear"]) == len(t2["lcp"]) == 8
    assert t2["thetas"] == list(range(40, 181, 20))  # Table II: 40°-180° by 20°
    assert min(t2["lcp"]) == 1.0 and t2["lcp"][0] == 1.0  # each column over its fastest
    assert all(n > 1000 * lc for n, lc in zip(t2["nonlinear"], t2["lcp"]))  # 3-4 decades


def test_cantilever_difference_is_the_rounded_forces_ratio():
    c = PAPER["cantilever"]  # Sec. III-G: 7.9 mN against 7.7 mN, "2.60 %"
    diff = 100 * (c["model_mN"] - c["theory_mN"]) / c["theory_mN"]
    assert round(diff, 2) == c["difference_percent"]


def test_table1_counts():
    assert PAPER["table1"] == {"nonlinear": "3N+2", "lcp": 5}  # eqs. 3, 8, 11, 17, 18


def test_gram_force_is_standard_gravity():
    assert math.isclose(GF, 9.80665 * 1e-3, rel_tol=1e-15)  # 1 gf = 1 g x g0, in N


def test_full_plan_is_the_papers_grid():
    assert RULE_THRESHOLD == PAPER["fig5"]["threshold_percent"] == 0.01
    assert FULL.links == PAPER["fig5"]["links"] == 140
    assert FULL.fig5_thetas == tuple(float(t) for t in range(10, 181, 10))
    assert FULL.fig5_heights == (2.0, 3.0, 4.0, 5.0, 6.0, 7.0)
    assert FULL.table2_thetas == tuple(float(t) for t in PAPER["table2"]["thetas"])
    assert FULL.fig26_heights[0] == 1.0 and PAPER["fig26"]["from_height"] in FULL.fig26_heights
    assert not FULL.quick and QUICK.quick and QUICK.links < FULL.links
