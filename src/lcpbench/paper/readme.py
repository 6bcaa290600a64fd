"""``README.md`` of a ``reproduce`` run: each of our numbers beside the paper's."""

from __future__ import annotations

import os
from pathlib import Path

from .markdown import render
from .readme_baseline import baseline_section, differences, errata_section
from .readme_model import (
    cantilever_section,
    fig5_section,
    fig8_section,
    fig24_section,
    shapes_section,
)


def write_readme(path: str | os.PathLike, summary: dict, meta: dict) -> None:
    """Write ``README.md``: each of our numbers beside the paper's, and why they differ.

    Parameters
    ----------
    path : path of the file to write.
    summary : the per-stage results of :func:`reproduce` (every stage).
    meta : run information (quick, elapsed_s, stage_s, solver, tol, links, machine).
    """
    quick = meta["quick"]
    s = summary
    mode = ("**Quick mode** (coarse grids, N = 40): these numbers show the trends "
            "and exercise the code. They are not the paper's values; run without "
            "`--quick` for those.\n\n" if quick else "")
    stage_lines = ", ".join(f"{k} {v:.1f} s" for k, v in meta["stage_s"].items())
    text = render(
        "readme.md",
        quick=' --quick' if quick else '',
        elapsed_s=f"{meta['elapsed_s']:.0f}",
        machine=meta['machine'],
        stage_lines=stage_lines,
        mode=mode,
        links=meta['links'],
        solver=meta['solver'],
        tol=f"{meta['tol']:g}",
        differences=differences(s),
        fig5=fig5_section(s['fig5'], quick),
        fig6_7=shapes_section(s['fig6_7']),
        fig8=fig8_section(s['fig8']),
        cantilever=cantilever_section(s['cantilever']),
        fig24=fig24_section(s['fig24']),
        baseline_section=baseline_section(s),
        errata=errata_section(s['errata']),
    )
    Path(path).write_text(text)

