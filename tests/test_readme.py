"""The README works on copy-paste: its Python snippets run, its command lines run as
pasted in the shell its two commands leave (bash, the virtual environment's bin first on
PATH, as `. .venv/bin/activate` puts it), and CI runs its test command."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
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


def test_activation_comes_right_under_the_two_commands():
    """`lcpbench` is not on PATH after the commands alone: the README says how, at once."""
    commands = _indented_commands()
    last = max(i for i, c in enumerate(commands) if "'.[bench]'" in c or "'.[test]'" in c)
    assert commands[last + 1] == ". .venv/bin/activate", commands


def _use_lines() -> list[str]:
    """The `lcpbench ...` lines of the Use section, as written (comments included)."""
    part = README.split("## Use", 1)[1].split("\n## ", 1)[0]
    return [ln.strip() for ln in part.splitlines() if ln.startswith("    lcpbench ")]


def _use_commands() -> list[list[str]]:
    """The `lcpbench ...` lines of the Use section, as argument lists (comments dropped)."""
    return [shlex.split(ln, comments=True) for ln in _use_lines()]


#: commands of the Use section that take more than a few seconds, or touch the
#: machine beyond the working directory (`compile` writes the user's kernel cache;
#: tests/model/test_aot.py covers it)
_SLOW = ("select", "sweep", "report", "reproduce")
_ELSEWHERE = ("compile",)


def _lines_of(commands: tuple[str, ...], *, but: tuple[str, ...] = ()) -> list[str]:
    """The Use lines whose command (``lcpbench COMMAND``) is in ``commands`` (or, with
    ``commands`` empty, every one not in ``but``), as written."""
    return [ln for ln, argv in zip(_use_lines(), _use_commands(), strict=True)
            if (argv[1] in commands if commands else argv[1] not in but)]


def _in_the_readme_shell(tmp_path, lines: list[str]) -> None:
    """Each line as pasted, run by bash in the shell `. .venv/bin/activate` leaves (the
    environment's bin first on PATH, ``VIRTUAL_ENV`` set), from a directory that holds
    the clone's ``examples/``, as the README's "run from the clone's root"."""
    bin_dir = Path(sys.executable).parent
    if not (bin_dir / "lcpbench").exists():
        pytest.skip(f"no lcpbench script beside {sys.executable} (not an installed venv)")
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    env = {**os.environ, "VIRTUAL_ENV": str(bin_dir.parent),
           "PATH": f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}"}
    env.pop("LCPBENCH_STORE", None)
    for line in lines:
        out = subprocess.run(["bash", "-c", line], cwd=tmp_path, env=env, text=True,
                             capture_output=True, timeout=1200)
        assert out.returncode == 0, f"{line}\nexit {out.returncode}: {out.stderr[-2000:]}"


def test_readme_cli_examples_run_as_written(tmp_path):
    fast = _lines_of((), but=_SLOW + _ELSEWHERE + ("vision",))
    assert any(ln.startswith("lcpbench solve ") for ln in fast)
    _in_the_readme_shell(tmp_path, fast)
    assert (tmp_path / "shape.png").exists() and (tmp_path / "fit.png").exists()
    assert (tmp_path / "cycle.png").exists()


@pytest.mark.slow
def test_readme_slow_cli_examples_run_as_written(tmp_path):
    slow = _lines_of(_SLOW)
    assert {shlex.split(ln, comments=True)[1] for ln in slow} == set(_SLOW)
    _in_the_readme_shell(tmp_path, slow)
    assert (tmp_path / "scratch-report" / "report.md").exists()


def test_readme_vision_examples_run_as_written(tmp_path):
    pytest.importorskip("cv2")
    vision = _lines_of(("vision",))
    assert [shlex.split(ln, comments=True)[2] for ln in vision] == ["render", "measure"]
    _in_the_readme_shell(tmp_path, vision)
    assert (tmp_path / "overlay.png").exists()


def test_every_use_command_is_run_by_a_test():
    names = {a[1] for a in _use_commands()}
    assert names <= {"solve", "anchor", "cycle", "solvers", "design", "fit", "vision", *_SLOW,
                     *_ELSEWHERE}, names
