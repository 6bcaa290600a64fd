"""How the driver tolerance relates to the relative force error, on the paper grid.

Issue 40, item 4 (one accuracy knob): ``lcpbench.solve(scene, accuracy=a)`` asks for
a relative error a of the total force F = ΣR and is translated into the driver's
``tol`` (rad) and the back-end's ε (:mod:`lcpbench.accuracy`). This script measures
what a driver tolerance gives: on the paper's 108 scenes (θ 10–180° by 10, h 2–7 mm,
N = 140) each ``tol`` from 1e-2 to 1e-10 rad, solved cold by the default back-end,
against the scene's reference (the built-in active set at 1e-11 rad,
:func:`lcpbench.bench.jobs.reference_row`). Per tol: how many converged, the
largest and median force error |F − F_ref| / max(|F_ref|, EI/ℓ²), the largest
error / tol, the largest judge's bound (``force_error_bound``) and what the judge
allows, min(1e-3, 100 tol), and the mean number of outer steps (counts, not times).
Then the same for ``accuracy=a`` as translated. Writes
``results/accuracy-translation.md`` (``--out``; not overwritten without ``--force``).

    python benchmarks/accuracy_translation.py --force
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
from lcpbench.accuracy import LOWEST, driver_tol_for, held_to
from lcpbench.bench.grid import PAPER_GRID
from lcpbench.bench.jobs import reference_row
from lcpbench.bench.machine import command_line, refuse_overwrite
from lcpbench.bench.metrics import error_of
from lcpbench.model.judge import force_tol

ROOT = Path(__file__).resolve().parents[1]
TOLS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
ACCURACIES = (1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-9, 1e-10)


def _row(label: str, scenes, refs, kw) -> tuple[str, float]:
    errs, bounds, outer, ok, more = [], [], [], 0, 0
    for s, ref in zip(scenes, refs, strict=True):
        if "below" in kw:  # what solve(accuracy=a) would do, had it not refused a
            a = kw["below"]
            r = held_to(lcpbench.solve(s, tol=driver_tol_for(a)), a,
                        lambda t, got, sc=s: lcpbench.solve(sc, tol=t, start=got))
        else:
            r = lcpbench.solve(s, **kw)
        if not r.converged:
            continue
        ok += 1
        more += r.retried("accuracy") is not None
        errs.append(error_of(r.total_force, ref, s.EI / s.length**2))
        bounds.append(r.force_error_bound)
        outer.append(r.outer_iterations)
    e, b = np.array(errs), np.array(bounds)
    tol = kw.get("tol") or driver_tol_for(kw.get("accuracy", kw.get("below")))
    return (f"| {label} | {tol:.0e} | {ok} / {len(scenes)} | "
            f"{'—' if 'tol' in kw else more} | {e.max():.1e} | "
            f"{np.median(e):.1e} | {e.max() / tol:.2g} | {b.max():.1e} | "
            f"{force_tol(tol):.0e} | {np.mean(outer):.2f} |"), float(e.max())


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, default=ROOT / "results" / "accuracy-translation.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("accuracy_translation.py", argv)
    scenes = PAPER_GRID.scenes()
    refs = [reference_row(s)["total_force"] for s in scenes]
    head = ["| asked | tol (rad) | converged | continued at tol/100 | max error | "
            "median error | max error / tol | max judge's bound | judge allows | "
            "mean outer steps |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    by_tol = [_row(f"tol {t:.0e}", scenes, refs, {"tol": t})[0] for t in TOLS]
    by_acc = []
    for acc in ACCURACIES:  # 1e-10 is below lcpbench.accuracy.LOWEST: as solve would run it
        kw = {"accuracy": acc} if acc >= LOWEST else {"below": acc}
        row, worst = _row(f"accuracy {acc:.0e}" + ("" if acc >= LOWEST else " (refused)"),
                          scenes, refs, kw)
        by_acc.append(row + (" **over**" if worst > acc else ""))
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# Driver tolerance against force error, the paper grid (issue 40, item 4)", "",
        f"Computed {when} by `{cmd}` "
        f"(lcpbench {lcpbench.__version__}): the paper's {len(scenes)} scenes (θ 10–180° by "
        "10, h 2–7 mm by 1, N = 140), each solved cold by `lcpbench.solve` with the "
        "default back-end. Error: |F − F_ref| / max(|F_ref|, EI/ℓ²) against the "
        "reference at 1e-11 rad, over the converged runs. The judge accepts an answer "
        "whose bound is at most min(1e-3, 100 tol); `accuracy=a` runs at tol min(a, 1e-3) "
        "and continues an answer whose bound exceeds a at tol a/100 (column 4). Outer "
        "steps are counts; nothing here is timed. Below 1e-9 `accuracy` is refused "
        "(the last row: what it would do, run by hand): the error is at the "
        "reference's round-off. docs/accuracy.md reads this table.",
        "", "## By driver tolerance", "", *head, *by_tol, "",
        "## By `accuracy=` (translated by `lcpbench.accuracy`)", "", *head, *by_acc, ""])
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
