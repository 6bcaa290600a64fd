"""How a :class:`~lcpbench.model.result.ContactResult` shows itself: text, HTML, a node table.

Presentation only: nothing here computes or judges an answer. Three views
of one result:

- :func:`summary_text` — a few lines for a terminal (``ContactResult.summary()``);
- :func:`summary_html` — the same as an HTML table (``_repr_html_``, notebooks);
- :func:`node_table` — one row per free node (the paper's node number i, its
  coordinates x_i, y_i, the gap g_i = h − y_i and the reaction R_i of eq. (30),
  and whether it is in contact), as a pandas DataFrame when pandas is
  installed, else a dict of numpy columns (pandas is not a dependency).
"""

from __future__ import annotations

import html
from dataclasses import is_dataclass
from typing import Any

import numpy as np

#: a :class:`~lcpbench.model.result.ContactResult`; not imported, not even for type
#: checking: result.py imports this module (its ``summary``, ``_repr_html_``, ``nodes``),
#: and no import cycle is allowed (tests/test_layers.py)
ContactResult = Any

#: the node table's columns, in order, with their units
NODE_COLUMNS = {
    "node": "paper's node number i (1 = left pin)",
    "x": "mm",
    "y": "mm",
    "gap": "h - y, distance below the upper wall (mm)",
    "force": "R, the upper wall's reaction (N)",
    "contact": "R above the judge's contact threshold",
}
#: extra columns of a channel (two walls)
LOWER_COLUMNS = {
    "gap_lower": "y + h, distance above the lower wall (mm)",
    "force_lower": "the lower wall's reaction (N)",
}


#: extra columns of a scene with elastic walls
ELASTIC_COLUMNS = {
    "indentation": "depth the node indents an elastic wall (mm)",
    "pressure": "contact pressure per length, R / share (N/mm)",
}


def free_node_indices(res: ContactResult) -> np.ndarray:
    """0-based indices (into ``res.x``, ``res.y``) of the nodes of ``res.forces``."""
    if res.free_nodes is not None:
        return np.asarray(res.free_nodes, dtype=int)
    # the chains of lcpbench: free nodes follow the left pin (node 1) in order
    return np.arange(1, 1 + np.asarray(res.forces).size)


def node_columns(res: ContactResult) -> dict[str, np.ndarray]:
    """The node table as a dict of equal-length numpy columns (see :data:`NODE_COLUMNS`)."""
    idx = free_node_indices(res)
    cols: dict[str, np.ndarray] = {
        "node": idx + 1,
        "x": np.asarray(res.x, dtype=float)[idx],
        "y": np.asarray(res.y, dtype=float)[idx],
        "gap": np.asarray(res.gaps, dtype=float).copy(),
        "force": np.asarray(res.forces, dtype=float).copy(),
    }
    contact = np.zeros(idx.size, dtype=bool)
    contact[res.contact_nodes] = True
    cols["contact"] = contact
    if res.forces_lower is not None and res.gaps_lower is not None:
        cols["gap_lower"] = np.asarray(res.gaps_lower, dtype=float).copy()
        cols["force_lower"] = np.asarray(res.forces_lower, dtype=float).copy()
    if getattr(res.scene, "wall_stiffness", np.inf) < np.inf and res.pressure is not None:
        cols.update({k: np.asarray(getattr(res, k), dtype=float).copy()
                     for k in ELASTIC_COLUMNS})
    return cols


def node_table(res: ContactResult, *, frame: bool | None = None) -> Any:
    """One row per free node: a pandas DataFrame, or a dict of numpy columns.

    ``frame``: True needs pandas (ImportError without it), False always gives
    the dict, None (default) a DataFrame when pandas is installed.
    """
    cols = node_columns(res)
    if frame is False:
        return cols
    try:
        import pandas as pd
    except ImportError:
        if frame:
            raise ImportError("ContactResult.nodes(frame=True) needs pandas: "
                              "pip install pandas") from None
        return cols
    return pd.DataFrame(cols).set_index("node")


def _runs(nodes: np.ndarray) -> str:
    """Node numbers as ranges: [3, 4, 5, 9] -> "3-5, 9"."""
    if nodes.size == 0:
        return "none"
    parts, start, prev = [], int(nodes[0]), int(nodes[0])
    for n in map(int, nodes[1:]):
        if n != prev + 1:
            parts.append(f"{start}" if start == prev else f"{start}-{prev}")
            start = n
        prev = n
    parts.append(f"{start}" if start == prev else f"{start}-{prev}")
    return ", ".join(parts)


def _scene_line(res: ContactResult) -> str:
    s = res.scene
    if not is_dataclass(s):
        return f"{s!r}, N = {res.links}"
    names = {"theta": ("θ", "°"), "height": ("h", " mm"), "length": ("ℓ", " mm"),
             "EI": ("EI", " N·mm²"), "weight": ("w", " N/mm"), "load": ("q", " N/mm"),
             "wall_stiffness": ("k", " N/mm per mm")}
    profile = getattr(s, "wall_profile", None)
    if hasattr(s, "sections"):  # a row of sections: θ:ℓ[:EI:w] each, not one θ
        from ..problems.sections import sections_text

        parts = [f"sections {sections_text(s)} (θ:ℓ[:EI:w])", f"N = {res.links}",
                 f"h = {s.height:g} mm", f"ℓ = {s.length:g} mm"]
        if s.gravity == "+y":
            parts.append("weight toward the upper wall")
    else:
        parts = [f"{sym} = {getattr(s, k):g}{unit}" for k, (sym, unit) in names.items()
                 if hasattr(s, k)
                 and not (k == "wall_stiffness" and getattr(s, k) == np.inf)]
        parts.insert(2 if hasattr(s, "theta") else 1, f"N = {res.links}")
        if profile is not None:  # h is not used: the wall is y = h(x)
            parts = [p for p in parts if not p.startswith("h = ")]
            parts.append(f"wall profile {profile.name}")
    if getattr(s, "channel", False):
        parts.append("channel (walls at ±h)" if profile is None else "channel")
    return f"{type(s).__name__}: " + ", ".join(parts)


def pressure_rows(res: ContactResult) -> list[tuple[str, str]]:
    """The summary lines of an elastic wall and of a pressure limit (also the CLI's)."""
    rows: list[tuple[str, str]] = []
    if getattr(res.scene, "wall_stiffness", np.inf) < np.inf or res.pressure_limit is not None:
        rows.append(("contact pressure", f"max {res.max_pressure:.4g} N/mm, max indentation "
                                         f"{res.max_indentation:.4g} mm"))
    if res.pressure_limit is not None:
        flag = "EXCEEDED" if res.pressure_exceeded else "below"
        rows.append(("pressure limit", f"{flag}: max pressure {res.max_pressure:.4g} N/mm, "
                                       f"limit {res.pressure_limit:g} N/mm"))
    return rows


def summary_rows(res: ContactResult) -> list[tuple[str, str]]:
    """(label, value) pairs shared by the text and HTML summaries."""
    idx = free_node_indices(res)
    contact = idx[res.contact_nodes] + 1
    verdict = "yes" if res.converged else "NO"
    rows = [
        ("scene", _scene_line(res)),
        ("converged", f"{verdict} ({res.reason})" if res.reason not in ("", "converged")
                      else verdict),
        ("total force F = ΣR" if res.forces_lower is None else "upper wall F = ΣR",
         f"{1e3 * res.total_force:.6g} mN on {contact.size} contact node(s): "
         f"{_runs(contact)}" + ("" if res.forces_lower is None
                                else " (total_force: the paper's load cell)")),
    ]
    if res.total_force_lower is not None:
        rows.append(("lower wall ΣR", f"{1e3 * res.total_force_lower:.6g} mN "
                                      "(total_force_lower)"))
    rows += pressure_rows(res)
    if res.states:
        rows.append(("stable states", states_line(res)))
    rows.append(("force error bound", f"{res.force_error_bound:.2g} (relative to "
                                      "max(|F|, EI/ℓ²), lcpbench's judge)"))
    c = res.certificate
    rows.append(("certificate", f"min gap {c.min_gap:.3g} mm, min force {c.min_force:.3g} N, "
                                f"complementarity {c.complementarity:.2g} N·mm, closure "
                                f"{c.closure:.2g} mm, torque residual "
                                f"{c.relative_torque_residual:.2g} (relative)"))
    rows.append(("solved by", f"{res.solver}, driver {res.method}, tol {res.tol:g} rad: "
                              f"{res.outer_iterations} outer / {res.inner_iterations} inner "
                              f"iterations, {1e3 * res.time_s:.3g} ms"))
    return rows


def states_line(res: ContactResult) -> str:
    """One line on the distinct stable states the solve's starts reached
    (``res.states``), lowest energy first, the answer's marked."""
    return (f"{len(res.states)} reached, lowest energy first: " + "; ".join(
        f"E = {s.energy:.6g} N·mm, F = {s.total_force:.6g} N ({s.start}"
        + (", this answer)" if s.answer else ")") for s in res.states))


def summary_text(res: ContactResult) -> str:
    """A few lines: scene, verdict, force and contact nodes, bound, certificate, cost."""
    rows = summary_rows(res)
    width = max(len(k) for k, _ in rows)
    return "\n".join(["ContactResult"] + [f"  {k:<{width}}  {v}" for k, v in rows])


def summary_html(res: ContactResult) -> str:
    """The summary as a small HTML table (for notebooks)."""
    body = "".join(f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
                   f"<td style='text-align:left'>{html.escape(v)}</td></tr>"
                   for k, v in summary_rows(res))
    return (f"<table><caption style='text-align:left'><b>ContactResult</b></caption>"
            f"{body}</table>")


__all__ = ["ELASTIC_COLUMNS", "LOWER_COLUMNS", "NODE_COLUMNS", "free_node_indices", "node_columns",
           "node_table", "states_line", "summary_html", "summary_rows", "summary_text"]
