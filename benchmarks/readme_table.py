"""The README's standard-run table, from the committed results/sweep/summary.json.

    python benchmarks/readme_table.py [results/sweep/summary.json] [--min-success 0.9]

prints the markdown table (back-end, settings, driver, success, converged off
the reference, the time and outer-iteration scores over every scene with
failures charged, median force error, speed-ups), ordered by the time score,
so the README's numbers come from committed results. The scores are the
report's (docs/bench.md, "Scores"): shifted geometric means over all scenes,
time with shift 1 ms and a failure at the 60 s limit, outer iterations with
shift 1 and a failure at the driver's 200. With ``--min-success S`` only the
rows that succeed on at least that share of the scenes, and the baselines (the
README's table).
"""

from __future__ import annotations

import argparse
import json
import math


def _fmt(v, spec):
    return "—" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def table(rows: list[dict]) -> str:
    head = ("| back-end | settings | driver | success | converged, off the reference | "
            "time sgm, all scenes (ms) | × best | outer it. sgm | median force error | "
            "× faster than baseline (analytic / fd) |\n"
            "|---|---|---|---:|---:|---:|---:|---:|---:|---:|")
    order = sorted(rows, key=lambda r: (r["backend"].startswith("baseline"),
                                        r["time_sgm_ms"], -r["success"]))
    lines = [head]
    for r in order:
        driver, at, form = r["method"].partition("@")  # DRIVER@FORM: --formulation
        driver = driver.replace("globalised+", "continuation (") + (
            ")" if "+" in driver else "") + at + form
        speed = (f"{_fmt(r['speedup_vs_baseline'], '.0f')} / "
                 f"{_fmt(r['speedup_vs_baseline_fd'], '.0f')}")
        if r["backend"].startswith("baseline"):
            speed = "—"
        lines.append(f"| `{r['backend']}` | {r['settings']} | {driver} | "
                     f"{100 * r['success']:.0f} % | {r['converged_but_off']} | "
                     f"{_fmt(r['time_sgm_ms'], '.3g')} | {_fmt(r['time_sgm_rel'], '.1f')} | "
                     f"{_fmt(r['outer_sgm'], '.3g')} | {_fmt(r['error_median'], '.1e')} | "
                     f"{speed} |")
    return "\n".join(lines)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("summary", nargs="?", default="results/sweep/summary.json")
    ap.add_argument("--min-success", type=float, default=0.0,
                    help="keep the rows with at least this success share, and the baselines")
    ap.add_argument("--fastest-form", action="store_true",
                    help="of a back-end's rows at one settings profile and driver (continuation "
                         "or not) that pass --min-success, keep the fastest form only")
    args = ap.parse_args()
    rows = [r for r in json.load(open(args.summary)) if r["success"] >= args.min_success
            or r["backend"].startswith("baseline")]
    if args.fastest_form:
        best: dict = {}
        for r in rows:  # the summary's method: DRIVER or DRIVER@FORM
            key = (r["backend"], r["settings"], r["method"].split("@")[0])
            if key not in best or r["time_sgm_ms"] < best[key]["time_sgm_ms"]:
                best[key] = r
        rows = [r for r in rows if best[(r["backend"], r["settings"],
                                         r["method"].split("@")[0])] is r]
    print(table(rows))
