"""The README works on copy-paste: its Python snippets run, and CI runs its test command."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README, flags=re.S)


def _indented_commands() -> list[str]:
    """The README's shell commands: the indented lines under "Two commands"."""
    part = README.split("## Two commands", 1)[1].split("\n## ", 1)[0]
    return [ln.strip() for ln in part.splitlines() if ln.startswith("    ") and ln.strip()]


def test_readme_python_blocks_run_as_written(tmp_path, monkeypatch):
    blocks = _blocks("python")
    assert blocks, "the README has no python block"
    monkeypatch.chdir(tmp_path)  # select_backend caches its probes in the store
    monkeypatch.setenv("LCPBENCH_STORE", str(tmp_path / "probes.sqlite"))
    for code in blocks:
        namespace: dict = {}
        exec(compile(code, "README.md", "exec"), namespace)
        if "sol" in namespace:  # the LCP example: z solves 2 z1 + z2 = 5, z1 + 2 z2 = 6
            np.testing.assert_allclose(namespace["sol"].z, [4 / 3, 7 / 3], rtol=1e-12)
        if "res" in namespace:
            assert namespace["res"].converged
    # the store is where the snippet's comment says, and not under the project
    assert (tmp_path / "probes.sqlite").exists()


def test_ci_runs_exactly_the_readme_test_command():
    commands = _indented_commands()
    tests = [c for c in commands if "pytest" in c]
    assert len(tests) == 1, commands
    ci = [ln.strip() for ln in (ROOT / ".ci" / "run").read_text().splitlines()
          if ln.strip() and not ln.lstrip().startswith("#")]
    assert ci[-1] == tests[0]


@pytest.mark.parametrize("which", ["bench", "test"])
def test_readme_commands_need_only_python3(which):
    """PEP 668 and no `python`: each command makes a venv with python3 and uses only it."""
    (cmd,) = [c for c in _indented_commands() if f"'.[{which}]'" in c]
    steps = [shlex.split(s) for s in cmd.split("&&")]
    assert steps[0][:3] == ["python3", "-m", "venv"]
    venv = steps[0][3]
    for step in steps[1:]:
        assert step[0].startswith(f"{venv}/bin/"), step
