"""Issue 39, target 5: how many signs fail in the polishes the polish keeps, and in those
it refuses (docs/friction.md, "Speed")? Every polish of a state's answer on
benchmarks/friction_agreement.py's Lemke paths (100 paths, seed 39, tol 1e-8) and on the
three pull-outs of benchmarks/friction_speed.py; with ``--solver NAME`` (a back-end by
name, which polishes every step) its own paths and Lemke's steps handed to it instead:
the number of rows and pairs whose sign fails (:func:`lcpbench.model.friction_polish.
signs`) at the answer's own set and after each flip (``extra["polish_failing"]``), the
edge search's nodes, and the verdict. The flips stop at POLISH_MOST_FAILING; the
numbers in its docstring were measured with it out of reach.

    python benchmarks/friction_polish_failing.py [--paths 100] [--solver NAME]
        [--out FILE.json]
"""

# ruff: noqa: E402
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import json
import sys
from pathlib import Path

import lcpbench
from lcpbench.model import friction_lemke as fl
from lcpbench.model import friction_solvers as fsolv
from lcpbench.model.friction_solvers import step_runner

sys.path.insert(0, str(Path(__file__).resolve().parent))
from friction_agreement import Recorder, scenes  # noqa: E402
from friction_speed import SCENES  # noqa: E402

LOG: list[dict] = []


class Watched:
    """The polish kernels, recording each ``polish_on`` with flips and each edge search."""

    def __init__(self, k):
        self.k = k

    def __getattr__(self, name):
        return getattr(self.k, name)

    def polish_on(self, *args):  # (the own set, the first flip, then the other flips)
        out = self.k.polish_on(*args)
        LOG[-1]["failing"] += [int(f) for f in out[8]]
        LOG[-1]["flips_code"] = int(out[0])
        return out

    def polish_sets(self, *args):
        out = self.k.polish_sets(*args)
        LOG[-1]["edge"] = {"nodes": int(args[-5].size), "code": int(out[0])}
        return out


def watch():
    kernels, step = fl.polish_kernels, fl.polish_step

    def polish_kernels():
        return Watched(kernels())

    def polish_step(fs, sol, *flips):
        LOG.append({"where": WHERE[0], "failing": [], "edge": None})
        out = step(fs, sol, *flips)
        LOG[-1]["verdict"] = out.extra.get("polish")
        LOG[-1]["nodes"] = int(fs.friction_node.size)
        return out

    fl.polish_kernels, fl.polish_step = polish_kernels, polish_step
    fsolv.polish_step = polish_step


WHERE = [""]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=100)
    ap.add_argument("--solver", default="")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    watch()
    for index, (scene, states) in enumerate(scenes(args.paths, 39)):
        WHERE[0] = f"agreement {index}"
        rec = Recorder()
        n = len(LOG)
        lcpbench.solve_path(scene, states, tol=1e-8, lcp=rec)
        if not args.solver:
            continue
        del LOG[n:]
        WHERE[0] = f"{args.solver} path {index}"
        lcpbench.solve_path(scene, states, tol=1e-8, solver=args.solver)
        WHERE[0] = f"{args.solver} step {index}"
        for fs, _ in rec.steps:
            step_runner(args.solver)(fs)
    for name, scene in SCENES.items() if not args.solver else ():
        WHERE[0] = f"pull-out {name}"
        r = lcpbench.pull_out(scene)
        print(name, "P* (mN)", repr(1e3 * r.force))
    if args.out:
        Path(args.out).write_text(json.dumps(LOG))
    polished = [e for e in LOG if e["failing"]]
    kept = [e for e in polished if e["verdict"] == "kept"]
    refused = [e for e in polished if e["verdict"] != "kept"]
    print(f"{len(LOG)} polishes, {len(polished)} solved a set, {len(kept)} kept")
    print("kept: largest failing at the answer's set",
          max(e["failing"][0] for e in kept), "at any set",
          max(max(e["failing"]) for e in kept), "kept by its flips, at any set",
          max((max(e["failing"]) for e in kept if not e["edge"]), default=None))
    past = [e for e in polished if max(e["failing"]) > 20]
    print("passed 20:", len(past), "kept by their flips:",
          sum(e["verdict"] == "kept" and not e["edge"] for e in past))
    many = [e for e in refused if e["failing"][0] >= 40]
    print("refused with 40+ failing at the start:", len(many), "smallest",
          min((e["failing"][0] for e in many), default=None))
    hist: dict = {}
    for e in polished:
        f0 = e["failing"][0]
        key = "kept" if e["verdict"] == "kept" else "refused"
        hist.setdefault(f0, {"kept": 0, "refused": 0})[key] += 1
    print("failing at the start: kept / refused")
    for f0 in sorted(hist):
        print(f"  {f0:4d}: {hist[f0]['kept']:4d} / {hist[f0]['refused']:4d}")
    for e in polished:
        if e["failing"][0] > 3 or e["verdict"] != "kept":
            print(e["where"], e["verdict"], e["failing"], e["edge"])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
