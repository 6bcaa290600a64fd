"""The report's back-end × formulation table, from a tiny store with runs in two forms."""

import pytest

from lcpbench.bench.grid import Grid
from lcpbench.bench.metrics import evaluate, summarise
from lcpbench.bench.report import build_report, formulation_table
from lcpbench.bench.store import Store
from lcpbench.bench.sweep import plan_sweep, sweep

SETTINGS = ["default", "high"]


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """Lemke on 4 scenes (2 with contact at h = 2 mm), each step handed as today's LCP in
    gaps (F1, the plain run) and as the LCP in reactions (F4, method globalised@reactions)."""
    path = tmp_path_factory.mktemp("forms") / "s.sqlite"
    grid = Grid(theta=(60.0, 150.0), height=(2.0, 5.0), links=(30,))
    with Store(path) as st:
        sweep(st, plan_sweep(grid, ["lemke"], SETTINGS, baselines=()), workers=1)
        sweep(st, plan_sweep(grid, ["lemke"], SETTINGS, baselines=(),
                             formulation="reactions"), workers=1)
    return path


def _cells(table: str) -> dict[tuple[str, str], list[str]]:
    rows = [line.strip("|").split("|") for line in table.splitlines() if line.startswith("| `")]
    return {(r[0].strip(), r[1].strip()): [c.strip() for c in r[2:]] for r in rows}


def test_each_form_is_a_row_with_its_own_success_per_settings(store):
    with Store(store) as st:
        ev = evaluate(st.runs(), st.refs())
    cells = _cells(formulation_table(summarise(ev)))
    assert set(cells) == {("`lemke`", "gaps (own)"), ("`lemke`", "reactions")}
    for (_, form), values in cells.items():
        method = "globalised" if form == "gaps (own)" else "globalised@reactions"
        for i, s in enumerate(SETTINGS):  # success recounted from the judged runs
            runs = [e for e in ev if e.settings == s and e.row["method"] == method]
            assert len(runs) == 4
            share = sum(e.success for e in runs) / len(runs)
            assert values[3 * i] == f"{100 * share:.0f} %"
    # both forms are the same LCP (F4 is F1's dual, M SPD: one answer), and Lemke
    # solves it exactly: every scene a success in either form at the paper's tolerance
    assert cells["`lemke`", "gaps (own)"][0] == cells["`lemke`", "reactions"][0] == "100 %"


def test_the_report_has_the_table_only_when_a_form_was_asked_for(store, tmp_path):
    with Store(store) as st:
        build_report(st, tmp_path / "all", plots=False)
        runs = st.runs()
        plain = [r for r in runs if "@" not in r["method"]]
        assert plain and len(plain) < len(runs)
        assert formulation_table(summarise(evaluate(plain, st.refs()))) == ""
    md = (tmp_path / "all" / "report.md").read_text()
    assert "## Back-ends and formulations" in md and "| `lemke` | reactions |" in md


def test_continuation_and_baseline_rows_are_left_out():
    def row(backend, method, settings="high"):
        return {"backend": backend, "settings": settings, "method": method, "success": 1.0,
                "time_sgm_ms": 1.0, "error_median": 1e-9}

    table = formulation_table([row("lemke", "globalised"), row("lemke", "globalised@reactions"),
                               row("active-set", "globalised+adaptive"),
                               row("baseline", "hybr", "-")])
    cells = _cells(table)
    assert set(cells) == {("`lemke`", "gaps (own)"), ("`lemke`", "reactions")}
    assert "high: success" in table and "default: success" not in table
