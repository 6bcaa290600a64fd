"""Importing :mod:`lcpbench.paper` must not import matplotlib (it is an optional extra)."""

import subprocess
import sys


def test_importing_the_paper_package_does_not_import_matplotlib():
    code = ("import sys, lcpbench.paper.reproduce, lcpbench.paper.plots; "
            "print('matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"


def test_no_module_over_600_lines():
    from pathlib import Path

    import lcpbench.paper

    for f in Path(lcpbench.paper.__file__).parent.glob("*.py"):
        assert len(f.read_text().splitlines()) <= 600, f.name
