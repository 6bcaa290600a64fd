"""Formatting helpers of the regenerated README, and its templates.

The README's prose lives in ``lcpbench/paper/templates/*.md`` (package data),
one :class:`string.Template` per section (``$name`` placeholders, ``$$`` for a
dollar sign); :func:`render` fills one in. The section functions of
:mod:`lcpbench.paper.readme_model` and :mod:`lcpbench.paper.readme_baseline`
compute the values.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from importlib import resources
from string import Template

#: The test module whose tests the README names as evidence ("Shown by").
TESTS = "tests/paper/test_reproduce.py"


def num(v: float | int | None, spec: str = ".3g", missing: str = "—") -> str:
    """Format a number, or ``missing`` for None/NaN."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return missing
    return format(v, spec)


def millinewtons(v: float, spec: str = ".4g") -> str:
    """A force in N, written in mN."""
    return f"{num(1e3 * v, spec)} mN"


def md_table(head: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def scene_list(pairs: Iterable) -> str:
    """(θ, h, …) pairs as readable text."""
    return ", ".join(f"(θ = {t:g}°, h = {h:g} mm)" for t, h, *_ in pairs) or "none"




def render(name: str, **values: object) -> str:
    """Fill in the template ``templates/<name>``; every placeholder must be given.

    Values are turned into text with ``str`` (the callers pass strings already
    formatted where a format matters).
    """
    text = resources.files(__package__).joinpath("templates", name).read_text(encoding="utf-8")
    return Template(text).substitute(values)
