"""Elastic walls from soft to rigid: every stiffness converges, the rigid limit is continuous.

Issue 35, target 2 (and issue 36's elastic walls at tight tolerance): the paper
scene (θ = 150°, h = 3 mm) with one wall and in a channel, N = 40 and 140, the
Winkler stiffness k from 1e-3 to 1e10 N/mm² in half decades, at tol 1e-9 and
1e-10 rad, each solved cold by ``lcpbench.solve`` (the default back-end). For each
(tol, wall, N) the table gives how many stiffnesses converged and |F(k) − F(∞)| /
F(∞) at k = 1e9 and 1e10 against the rigid wall's answer (theory: O(1/k)).
Writes ``results/elastic/stiffness-sweep.md`` (``--out``; not overwritten without
``--force``).

    python benchmarks/stiffness_sweep.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite

ROOT = Path(__file__).resolve().parents[1]
STIFFNESS = 10.0 ** np.arange(-3.0, 10.25, 0.5)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=ROOT / "results" / "elastic" /
                   "stiffness-sweep.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("stiffness_sweep.py", argv)
    rows, refused = [], []
    for tol in (1e-9, 1e-10):
        for channel in (False, True):
            for links in (40, 140):
                kw = dict(theta=150.0, height=3.0, links=links, channel=channel)
                rigid = lcpbench.solve(ActuatorScene(**kw), tol=tol)
                ok, near = 0, {}
                for k in STIFFNESS:
                    r = lcpbench.solve(ActuatorScene(wall_stiffness=float(k), **kw), tol=tol)
                    ok += bool(r.converged)
                    if not r.converged:
                        refused.append(f"- tol {tol:g}, {'channel' if channel else 'one wall'}, "
                                       f"N = {links}, k = {k:.3g}: {r.reason}")
                    if k in (1e9, 1e10):
                        near[k] = abs(r.total_force / rigid.total_force - 1.0)
                rows.append(f"| {tol:g} | {'channel' if channel else 'one wall'} | {links} | "
                            f"{ok} / {STIFFNESS.size} | {rigid.total_force:.10g} | "
                            f"{near[1e9]:.2e} | {near[1e10]:.2e} |")
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# Elastic walls from soft to rigid (issue 35, target 2)", "",
        f"Computed {when} by `{cmd}`: θ = 150°, "
        f"h = 3 mm, k = 1e-3 … 1e10 N/mm² in half decades ({STIFFNESS.size} values), each "
        "a cold `lcpbench.solve` with the default back-end (the compiled kernel's "
        "compliance form, docs/elastic-walls.md). Target: every k converges, and at "
        "k = 1e9 the force is the rigid wall's within 1e-6 relative.", "",
        "| tol (rad) | walls | N | converged | F rigid (N) | rel. diff. k = 1e9 | "
        "rel. diff. k = 1e10 |", "|---|---|---:|---:|---:|---:|---:|", *rows, "",
        "Refused: " + ("none." if not refused else ""), *refused, ""])
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
