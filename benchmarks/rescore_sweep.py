"""Rescore the committed standard report from its committed runs, without solving anything.

    python benchmarks/rescore_sweep.py [results/sweep]

The standard run's store (`std.sqlite`, about 55 minutes of solves) is not
committed, but `results/sweep/runs.csv` holds every run with its scene's
reference force: everything the scores need. This script judges those runs
again (`bench.metrics.evaluate`, the same success rule), checks that every
row's success rate is the committed one, and rewrites what the scoring rule
decides: `summary.json`, `profiles.csv`, the six profile figures,
`work-precision.png`, and in `report.md` the scoring paragraph, the table
"Back-ends compared", the sections "Back-ends without runs here" (with today's
install hints), "Back-ends and formulations" and "Unsuccessful runs" (counted against today's `bench.expected`)
and the section "Performance and data profiles". The rest
of report.md (the reference check, Table II, continuation, the machine) and
the force and shape figures need the store's arrays and stay as they are.
`lcpbench report --out results/sweep` on the store rebuilds everything at once.
"""

from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path

from lcpbench.bench.jobs import DEFAULT_TIME_LIMIT
from lcpbench.bench.metrics import continuation_pairs, evaluate, summarise
from lcpbench.bench.plot import plot_work_precision
from lcpbench.bench.profiles import profiles_section
from lcpbench.bench.report import (
    _attach_continuation,
    _write_profiles,
    comparison_table,
    failures,
    formulation_table,
    scoring_text,
    skipped_backends,
)
from lcpbench.jsonsafe import sanitise

NOTE = ("\n\n*The scores, the table below, the profiles, the work-precision figure and the "
        "unsuccessful runs' expected and unexpected counts were recomputed from "
        "[runs.csv](runs.csv) by `benchmarks/rescore_sweep.py` (issue 37: scores over every "
        "scene, failures charged; issue 40: the documented refusals of `bench.expected`), "
        "with the same successes; the rest of this report is as the standard run built it.*")
FLOATS = ("tol", "theta", "height", "length", "EI", "weight", "total_force", "wall_time",
          "solver_time", "setup_time", "wall_time_min", "wall_time_max")
INTS = ("links", "outer_iterations", "inner_iterations", "repeats")


def _value(key: str, text: str):
    if text == "":
        return None
    if key in FLOATS:
        return float(text)
    if key in INTS:
        return int(float(text))
    if key in ("converged", "channel"):
        return bool(int(float(text)))
    return text


def read_runs(path: Path) -> tuple[list[dict], dict[str, dict]]:
    """The runs of a report's runs.csv and the references they carry."""
    runs, refs = [], {}
    with open(path, newline="") as fh:
        for r in csv.DictReader(fh):
            ref = r.pop("reference_force")
            runs.append({k: _value(k, v) for k, v in r.items()})
            if ref != "":
                refs[r["scene"]] = {"converged": True, "total_force": float(ref)}
    return runs, refs


def _replace_section(text: str, start: str, end: str, new: str) -> str:
    a = text.index(start)
    b = text.index(end, a + len(start))
    return text[:a] + new + text[b:]


def main(folder: Path) -> None:
    runs, refs = read_runs(folder / "runs.csv")
    evaluated = evaluate(runs, refs)
    summary = summarise(evaluated, time_limit=DEFAULT_TIME_LIMIT)
    _attach_continuation(summary, continuation_pairs(runs))
    old = {(r["backend"], r["settings"], r["method"]): r
           for r in json.loads((folder / "summary.json").read_text())}
    for r in summary:  # the same runs judged by the same rule: the same successes
        was = old[r["backend"], r["settings"], r["method"]]
        if not (math.isclose(was["success"], r["success"]) and was["runs"] == r["runs"]):
            raise SystemExit(f"{r['backend']} {r['settings']}: success {r['success']} "
                             f"here, {was['success']} committed")
    (folder / "summary.json").write_text(json.dumps(sanitise(summary), indent=1) + "\n")
    figures = _write_profiles(evaluated, folder, True)
    plot_work_precision(summary, evaluated, folder / "work-precision.png",
                        time_limit=DEFAULT_TIME_LIMIT)
    text = (folder / "report.md").read_text()
    text = _replace_section(text, "**Error** of a run", "\n\n## Back-ends compared",
                            scoring_text(DEFAULT_TIME_LIMIT) + NOTE)
    forms = formulation_table(summary)
    text = _replace_section(text, "## Back-ends compared", "\n## Back-ends without runs here",
                            "## Back-ends compared\n\n" + comparison_table(summary) + "\n"
                            + (f"\n## Back-ends and formulations\n\n{forms}\n" if forms
                               else ""))
    text = _replace_section(text, "## Back-ends without runs here", "\n## Unsuccessful runs",
                            "## Back-ends without runs here\n\n"
                            + skipped_backends({r["backend"] for r in runs}) + "\n")
    text = _replace_section(text, "## Unsuccessful runs", "\n## Computation time per bend",
                            "## Unsuccessful runs\n\n" + failures(evaluated) + "\n")
    text = _replace_section(text, "\n## Performance and data profiles", "\n## Machine and timing",
                            profiles_section(figures))
    (folder / "report.md").write_text(text)
    print(f"rescored {len(runs)} runs in {len(summary)} rows into {folder}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "results/sweep"))
