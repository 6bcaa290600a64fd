"""The command line's frame: every sub-command's help, the one error path, the hooks."""

from __future__ import annotations

import argparse
import subprocess
import sys
import types

import pytest

from lcpbench.cli import build_parser, main


def _commands(parser, prefix=()):
    """Every sub-command path of *parser*, e.g. ('validate', 'cantilever')."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield (*prefix, name)
                yield from _commands(sub, (*prefix, name))


COMMANDS = list(_commands(build_parser()))


def test_every_group_is_registered():
    assert {c[0] for c in COMMANDS} >= {"solve", "solvers", "export", "lcp", "validate",
                                        "sweep", "report", "select", "reproduce"}
    assert ("validate", "cantilever") in COMMANDS


def _one_error_line(err: str) -> str:
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("lcpbench: error: ")
    assert "Traceback" not in err and "usage:" not in err
    return lines[0]


@pytest.mark.parametrize("argv", [[], *map(list, COMMANDS)], ids=lambda a: " ".join(a) or "-")
def test_help_exits_0(capsys, argv):
    assert main([*argv, "--help"]) == 0
    out = capsys.readouterr()
    assert out.out.startswith("usage: lcpbench") and out.err == ""


@pytest.mark.parametrize("argv", [list(c) for c in COMMANDS], ids=" ".join)
def test_unknown_option_exit_2_one_line(capsys, argv):
    assert main([*argv, "--no-such-option"]) == 2
    out = capsys.readouterr()
    line = _one_error_line(out.err)  # a missing required argument may be named first
    assert "--no-such-option" in line or "required" in line
    assert out.out == ""


@pytest.mark.parametrize("argv, names", [
    ([], "COMMAND (solve, export, lcp, validate, solvers, sweep"),
    (["validate"], "CASE (cantilever)"),
    (["nope"], "nope"),
    (["sweep", "--jobs", "two"], "two"),
    (["sweep", "--jobs", "0", "--solvers", "active-set", "--baseline", "none"], "jobs"),
    (["sweep", "--settings", ","], "settings"),
    (["sweep", "--tol", "0", "--solvers", "active-set"], "tol"),
    (["sweep", "--grid", "hard", "--theta", "10"], "--theta"),
    (["sweep", "--continuation", "--method", "undamped"], "continuation"),
    (["select", "--links", "auto"], "links"),
    (["select", "--jobs", "0", "--links", "20"], "jobs"),
    (["report", "--store", "/no/such/dir/s.sqlite"], None),
])
def test_bad_input_exit_2_one_line(capsys, argv, names):
    assert main(argv) == 2
    out = capsys.readouterr()
    line = _one_error_line(out.err)
    if names is not None:
        assert names in line
    assert out.out == ""


def test_keyboard_interrupt_exit_130(capsys, monkeypatch):
    import lcpbench.cli.solvers as group

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(group, "cmd_solvers", interrupted)  # register() reads it again
    assert main(["solvers"]) == 130
    assert "interrupted" in _one_error_line(capsys.readouterr().err)


def test_vision_hook(capsys, monkeypatch):
    """A ``lcpbench.vision.commands`` module with ``register(subparsers)`` joins in."""
    def register(subparsers):
        v = subparsers.add_parser("vision", help="vision tools")
        cases = v.add_subparsers(dest="vision_command", metavar="VCOMMAND")
        cases.add_parser("ping").set_defaults(func=lambda args: 7)

    pkg = types.ModuleType("lcpbench.vision")
    pkg.__path__ = []
    commands = types.ModuleType("lcpbench.vision.commands")
    commands.register = register
    pkg.commands = commands
    monkeypatch.setitem(sys.modules, "lcpbench.vision", pkg)
    monkeypatch.setitem(sys.modules, "lcpbench.vision.commands", commands)
    assert main(["vision", "ping"]) == 7
    assert main(["vision", "ping", "--help"]) == 0
    capsys.readouterr()
    assert main(["vision"]) == 2
    assert "VCOMMAND (ping)" in _one_error_line(capsys.readouterr().err)
    assert main(["vision", "ping", "--bad"]) == 2
    _one_error_line(capsys.readouterr().err)


def test_import_is_light():
    """``import lcpbench.cli`` loads no command module, matplotlib or tqdm."""
    code = ("import sys, lcpbench.cli; "
            "print(sorted(m for m in sys.modules if m.startswith('lcpbench.cli.') "
            "or m.split('.')[0] in ('matplotlib', 'tqdm')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=True).stdout.strip()
    assert out == "['lcpbench.cli._common']"


def test_module_entry_point_help():
    proc = subprocess.run([sys.executable, "-m", "lcpbench.cli", "--help"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and proc.stdout.startswith("usage: lcpbench")
