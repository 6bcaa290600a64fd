"""``lcpbench reproduce``: regenerate the paper's figures and tables, side by side.

Each figure of the paper that the model can regenerate is written to
``out_dir`` as a PNG (:mod:`lcpbench.paper.plots`) with the numbers
behind it as CSV and JSON; ``summary.json`` gathers the headline numbers and
``README.md`` puts each of them beside the paper's, with the reason for every
difference that is not round-off.

======================  ========================================================
paper                   files
======================  ========================================================
Fig. 5, Sec. III-D      ``fig5-discretisation.{png,csv,json}``
Figs. 6, 7              ``fig6-shapes-theta.{png,csv}``, ``fig7-shapes-height.{png,csv}``
Fig. 8 (a)-(c)          ``fig8-forces.png``, ``fig8{a,b,c}-*.csv``, ``fig8.json``
Sec. III-G, Fig. 10     ``fig10-cantilever.{png,csv,json}``
Fig. 24 (model side)    ``fig24-force-pressure.{png,csv,json}``
Fig. 26                 ``fig26-disagreement.{png,csv}``
Fig. 27                 ``fig27-shapes-baseline.{png,csv}``
Tables I, II            ``table1-equations.json``, ``table2-times.{png,csv,json}``
errata, driver          ``errata-gravity.json`` (the effect of the eq. (13) misprint)
======================  ========================================================

The model's numbers are computed with the built-in active set (an exact
method, so the figures do not depend on a cached back-end selection) and the
globalised driver at 1e-8 rad, so that they show the model rather than the
driver's truncation at the paper's 1e-3 rad. Table II is the exception: it
times ``lcpbench.solve(scene)`` as a user calls it (the default back-end,
the paper's 1e-3 rad).
"""

from __future__ import annotations

import json
import os
import platform
import time
from collections.abc import Callable, Iterable
from pathlib import Path

from ..errors import ProblemError
from .baseline_figures import (
    errata_gravity,
    fig26_disagreement,
    fig27_shapes,
    table1,
    table2_times,
)
from .data import DEFAULT_OUT, FULL, QUICK, SOLVER, TOL, Plan
from .figures import cantilever, fig5_discretisation, fig6_7_shapes, fig8_forces, fig24_pressure
from .output import Output
from .readme import write_readme

# -- the run ----------------------------------------------------------------------------------
STAGES: tuple[tuple[str, Callable[[Plan, Output], dict]], ...] = (
    ("fig5", fig5_discretisation),
    ("fig6_7", fig6_7_shapes),
    ("fig8", fig8_forces),
    ("cantilever", cantilever),
    ("fig24", fig24_pressure),
    ("fig26", fig26_disagreement),
    ("fig27", fig27_shapes),
    ("table1", table1),
    ("table2", table2_times),
    ("errata", errata_gravity),
)


def reproduce(
    out_dir: str | os.PathLike = DEFAULT_OUT,
    *,
    quick: bool = False,
    progress: Callable[[int, int, str], None] | None = None,
    stages: Iterable[str] | None = None,
) -> dict:
    """Regenerate the paper's figures and tables into ``out_dir``, with a README beside them.

    Parameters
    ----------
    out_dir : str or path
        Directory to write to (created if needed; files of the same names are
        replaced, nothing else is touched).
    quick : bool
        Coarse grids and N = 40 (Table II and the cantilever included), one
        repeat per timing: well under a minute, for the tests. The numbers
        then show the trends, not the paper's values.
    progress : callable(done, total, stage), optional
        Called after each stage ("fig5", "fig6_7", …, "readme").
    stages : iterable of str, optional
        Run only these stages (names as above; the README needs them all and
        is only written when every stage ran).

    Returns
    -------
    dict
        ``out_dir``, ``quick``, ``files`` (names written), ``elapsed_s``,
        ``stage_s`` (seconds per stage) and ``summary`` (per stage, the
        numbers the README quotes; also written as ``summary.json``).
    """
    plan = QUICK if quick else FULL
    root = Path(out_dir)
    root.mkdir(parents=True, exist_ok=True)
    chosen = [name for name, _ in STAGES] if stages is None else list(stages)
    unknown = sorted(set(chosen) - {name for name, _ in STAGES})
    if unknown:
        raise ProblemError(f"unknown stage(s) {', '.join(unknown)}; the stages are "
                           + ", ".join(name for name, _ in STAGES))
    out = Output(root)
    everything = len(set(chosen)) == len(STAGES)
    total = len(chosen) + int(everything)
    summary: dict = {}
    stage_s: dict[str, float] = {}
    t_start = time.perf_counter()
    done = 0
    try:
        for name, fn in STAGES:
            if name not in chosen:
                continue
            t0 = time.perf_counter()
            summary[name] = fn(plan, out)
            stage_s[name] = time.perf_counter() - t0
            done += 1
            if progress is not None:
                progress(done, total, name)
    except BaseException:
        out.finish()  # keep what the finished stages computed
        raise
    elapsed = time.perf_counter() - t_start
    meta = {"quick": quick, "elapsed_s": elapsed, "stage_s": stage_s, "solver": SOLVER,
            "tol": TOL, "links": plan.links,
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, "
                       f"python {platform.python_version()}"}
    previous = {}
    if not everything and (root / "summary.json").is_file():  # keep the other stages
        try:
            previous = json.loads((root / "summary.json").read_text())
        except (OSError, ValueError):
            previous = {}
    out.json("summary.json", {**previous, "meta": meta, **summary})
    if everything:
        write_readme(out.path("README.md"), summary, meta)
        done += 1
        if progress is not None:
            progress(done, total, "readme")
    out.finish()
    return {"out_dir": str(root), "quick": quick, "files": list(out.files),
            "written": list(out.written), "unchanged": list(out.unchanged),
            "elapsed_s": elapsed, "stage_s": stage_s, "summary": summary}


