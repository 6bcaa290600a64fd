"""README helpers and templates (:mod:`lcpbench.paper.markdown`)."""

import math
import re
from importlib import resources

import pytest

from lcpbench.paper.markdown import md_table, millinewtons, num, render, scene_list


def test_numbers_and_missing_values():
    assert num(0.012345) == "0.0123"
    assert num(None) == num(math.nan) == "—"
    assert millinewtons(0.007875) == "7.875 mN"  # N to mN


def test_table_and_scene_list():
    assert md_table(["a", "b"], [["1", "2"]]) == "| a | b |\n|---|---|\n| 1 | 2 |"
    assert scene_list([(150.0, 1.0, "x")]) == "(θ = 150°, h = 1 mm)"
    assert scene_list([]) == "none"


def test_render_needs_every_placeholder():
    with pytest.raises(KeyError):
        render("errata.md")


def test_every_template_is_shipped_and_has_placeholders():
    names = [p.name for p in resources.files("lcpbench.paper").joinpath("templates").iterdir()]
    assert {"readme.md", "fig5.md", "baseline.md", "differences.md"} <= set(names)
    for name in names:
        text = resources.files("lcpbench.paper").joinpath("templates", name).read_text()
        assert re.search(r"\$\{\w+\}", text), name
