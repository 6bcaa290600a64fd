"""Every installed back-end on every problem of the Siconos LCP collection.

For each problem: size, symmetry, whether a solution exists (enumeration of
complementary bases, n <= 16), and each back-end's status, iterations and
lcpbench's natural residual. Writes ``results/siconos-collection.md`` and
``.json``; ``--expected`` also writes the per-problem, per-back-end outcome
table the tests read (``tests/solvers/data/siconos_expected.json``), which is
then reviewed by hand: every "unsolved" must have a reason in its "why".

    python benchmarks/siconos_collection.py [--settings default] [--expected]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from lcpbench.problems.lcpfile import read_lcp
from lcpbench.solvers import available_backends, solve_lcp
from lcpbench.solvers.enumeration import has_solution

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "siconos-lcp"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--settings", default="default")
    ap.add_argument("--expected", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "results" / "siconos-collection"))
    args = ap.parse_args(argv)
    names = available_backends()
    problems = sorted(DATA.glob("*.dat"))
    table = {}
    info = {}
    for path in problems:
        prob = read_lcp(path)
        M, q = prob.M, prob.q
        sym = bool(np.allclose(M, M.T))
        info[path.name] = {"n": int(q.size), "symmetric": sym,
                           "solution_exists": has_solution(M, q)}
        table[path.name] = {}
        for name in names:
            sol = solve_lcp(M, q, name, args.settings)
            res = sol.extra.get("residuals", {})
            table[path.name][name] = {"status": sol.status.value, "iterations": sol.iterations,
                                      "natural": res.get("natural"), "message": sol.message}
            print(f"{path.name:38s} {name:20s} {sol.status.value:15s} {sol.iterations}",
                  file=sys.stderr)
    out = Path(args.out)
    out.with_suffix(".json").write_text(json.dumps({"problems": info, "runs": table},
                                                   indent=1))
    lines = [
        "# The Siconos LCP collection, every back-end",
        "",
        f"`python benchmarks/siconos_collection.py --settings {args.settings}`. Cell: status "
        "(iterations as the back-end counts them: pivots, sweeps, Newton or QP iterations). "
        "QP back-ends take symmetric problems only (min ½zᵀMz + qᵀz, z >= 0) and return "
        "`failed` on the others by design. 'exists': a solution found by enumerating "
        "complementary bases (n <= 16).",
        "",
        "| problem | n | sym | exists | " + " | ".join(names) + " |",
        "|---|---:|---|---|" + "---|" * len(names),
    ]
    for p, row in table.items():
        i = info[p]
        ex = {True: "yes", False: "no", None: "?"}[i["solution_exists"]]
        cells = [f"{row[n]['status']} ({row[n]['iterations']})" for n in names]
        lines.append(f"| {p.removeprefix('lcp_').removesuffix('.dat')} | {i['n']} | "
                     f"{'yes' if i['symmetric'] else 'no'} | {ex} | " + " | ".join(cells) + " |")
    solved = {n: sum(table[p][n]["status"] == "solved" for p in table) for n in names}
    lines += ["", "Solved, of " + str(len(table)) + ": "
              + ", ".join(f"{n} {k}" for n, k in solved.items())]
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    if args.expected:
        dest = ROOT / "tests" / "solvers" / "data" / "siconos_expected.json"
        old = json.loads(dest.read_text()) if dest.exists() else {}
        kept = old.get("outcomes", {})
        # a reviewed path-dependent outcome ("solved-or-max-iter") is kept as it is
        exp = {"settings": args.settings, "note": old.get("note", ""),
               "outcomes": {p: {n: (kept.get(p, {}).get(n, "")
                                    if "-or-" in kept.get(p, {}).get(n, "") else
                                    "solved" if r["status"] == "solved" else "unsolved")
                                for n, r in row.items()} for p, row in table.items()},
               "why": old.get("why", {})}
        dest.write_text(json.dumps(exp, indent=1) + "\n")
        print(f"wrote {dest} (review it: every 'unsolved' needs a reason)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
