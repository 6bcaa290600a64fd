"""The registry: listing without native imports, errors that say what to do, plug-ins."""

from __future__ import annotations

import json
import subprocess
import sys
import types

import numpy as np
import pytest

from lcpbench.errors import ProblemError, SolverNotFound
from lcpbench.solvers import registry
from lcpbench.solvers.base import PROFILES, LCPSolution, Settings, Status
from lcpbench.solvers.registry import Backend, backends, get_backend, get_settings
from lcpbench.solvers.runner import solve_lcp

NATIVE = ("osqp", "clarabel", "proxsuite", "cvxpy", "qpsolvers", "daqp", "quadprog",
          "piqp", "highspy", "scs")


def test_listing_imports_no_native_library():
    code = (
        "import sys, lcpbench.solvers.registry as r\n"
        "rows = [b.capabilities() for b in r.backends().values()]\n"
        f"print(sorted(m for m in {NATIVE!r} if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


def test_capabilities_are_data():
    table = backends()
    for must in ("active-set", "lemke", "pgs", "osqp", "clarabel", "proxsuite-dense",
                 "proxsuite-sparse", "cvxpy", "siconos-lemke", "siconos-pgs",
                 "siconos-newton-min", "siconos-newton-fb"):
        assert must in table
    for b in table.values():
        cap = b.capabilities()
        assert cap["form"] in registry.FORMS and cap["storage"] in registry.STORAGES
        assert isinstance(cap["warm_start"], bool) and isinstance(cap["available"], bool)
        if b.extra is not None:
            assert b.extra.removeprefix("apt:") in cap["install"]
    # the built-in ones are always there
    assert {"active-set", "lemke", "pgs"} <= set(registry.available_backends())


def test_auto_is_the_active_set():
    assert get_backend("auto").name == "active-set"


def test_unknown_solver_names_what_is_installed():
    with pytest.raises(SolverNotFound) as err:
        get_backend("no-such-solver")
    msg = str(err.value)
    assert "no-such-solver" in msg and "lemke" in msg and "active-set" in msg


def test_missing_solver_names_the_extra(monkeypatch):
    ghost = Backend("ghost", "qp", "sparse", False, "iterative", "lcpbench.solvers.qp_osqp",
                    requires=("no_such_module_for_lcpbench",), extra="ghost")
    table = dict(registry._all())
    table["ghost"] = ghost
    monkeypatch.setattr(registry, "_all", lambda: table)
    with pytest.raises(SolverNotFound) as err:
        get_backend("ghost")
    assert "pip install 'lcpbench[ghost]'" in str(err.value)
    assert "lemke" in str(err.value)


def test_settings_profiles():
    assert [PROFILES[k].eps for k in ("low", "mid", "high")] == [1e-3, 1e-6, 1e-9]
    assert PROFILES["default"].eps is None
    assert get_settings("mid") is PROFILES["mid"]
    custom = Settings("custom", 1e-4)
    assert get_settings(custom) is custom
    with pytest.raises(ProblemError, match="settings must be one of default, low, mid, high"):
        get_settings("ultra")


# -- plug-ins through the entry-point group -----------------------------------------------
def _plugin_module():
    mod = types.ModuleType("lcpbench_test_plugin")

    def solve_lcp(M, q, settings, warm=None, **options):
        # a "solver" that only knows diagonal problems: z = max(0, -q / diag M)
        z = np.maximum(0.0, -q / np.diag(M))
        return LCPSolution(z, M @ z + q, Status.SOLVED, iterations=1)

    mod.solve_lcp = solve_lcp
    return mod


class _EP:
    def __init__(self, name, obj):
        self.name, self._obj = name, obj

    def load(self):
        if isinstance(self._obj, Exception):
            raise self._obj
        return self._obj


@pytest.fixture
def plugins(monkeypatch):
    monkeypatch.setitem(sys.modules, "lcpbench_test_plugin", _plugin_module())
    good = Backend("diag-plugin", "lcp", "dense", False, "iterative", "lcpbench_test_plugin",
                   "test plug-in")
    eps = [_EP("good", good), _EP("broken", RuntimeError("boom"))]

    def entry_points(group=None):
        return eps if group == registry.ENTRY_POINT_GROUP else []

    monkeypatch.setattr(registry.importlib.metadata, "entry_points", entry_points)
    registry._plugins.cache_clear()
    registry._all.cache_clear()
    yield
    registry._plugins.cache_clear()
    registry._all.cache_clear()


def test_entry_point_backend_plugs_in(plugins):
    assert "diag-plugin" in backends()
    assert any("broken" in e and "boom" in e for e in registry.plugin_errors())
    M, q = np.diag([2.0, 4.0]), np.array([-2.0, 1.0])
    sol = solve_lcp(M, q, "diag-plugin")
    assert sol.solved
    np.testing.assert_allclose(sol.z, [1.0, 0.0])
    # judged by lcpbench's residuals like every back-end
    assert sol.extra["residuals"]["natural"] == 0.0


def test_plugin_that_lies_is_not_called_solved(plugins):
    # the diagonal-only plug-in on a coupled problem: its z is wrong, lcpbench says so
    M, q = np.array([[2.0, 1.5], [1.5, 2.0]]), np.array([-2.0, -2.0])
    sol = solve_lcp(M, q, "diag-plugin")
    assert sol.status is Status.INACCURATE
    assert "natural residual" in sol.message


def test_cli_solvers_json_lists_everything():
    from lcpbench.cli import main

    out = subprocess.run([sys.executable, "-m", "lcpbench.cli", "solvers", "--json"],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    rows = json.loads(out.stdout)
    assert {r["name"] for r in rows} == set(backends())
    assert main(["solvers"]) == 0


def test_a_qpsolvers_hint_names_the_package_the_extra_does_not_install():
    """Issue 40, item 7: 'pip install lcpbench[qpsolvers]' only where that extra installs
    the solver (pyproject.toml); else the solver's package, and a commercial licence."""
    import re
    from pathlib import Path

    from lcpbench.solvers import qp_qpsolvers as qq

    text = (Path(__file__).parents[2] / "pyproject.toml").read_text()  # (no tomllib in 3.10)
    line = re.search(r"^qpsolvers = \[(.*)\]$", text, flags=re.M).group(1)
    extra = {re.split(r"[<>=\[ ]", r.strip(' "'))[0].lower() for r in line.split(",")}
    assert "qpsolvers" in extra and "daqp" in extra
    table = backends()
    for solver, module in qq.KNOWN_SOLVERS.items():
        b = table.get(f"qpsolvers-{solver}")
        if b is None:  # the native back-ends (osqp, clarabel, proxqp)
            continue
        hint = b.install_hint()
        if module.lower() in extra:
            assert hint == "pip install 'lcpbench[qpsolvers]'", solver
        else:
            assert hint.startswith("pip install ") and "does not include it" in hint, hint
            assert hint.removeprefix("pip install ").startswith(qq.PIP_NAMES.get(solver, module))
    for solver, owner in (("gurobi", "Gurobi"), ("mosek", "MOSEK"), ("copt", "COPT")):
        assert f"{owner} licence" in table[f"qpsolvers-{solver}"].install_hint()
