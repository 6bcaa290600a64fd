"""Fixtures of the benchmark tests: a fake plug-in package with misbehaving back-ends.

The sweep runs every job in a worker subprocess, so a back-end that hangs or
kills its process has to be a real installed plug-in: a module and a
``*.dist-info`` with an ``lcpbench.solvers`` entry point, put on PYTHONPATH
(the workers inherit it) and on sys.path (the parent's registry).
"""

import os
import textwrap

import pytest

from lcpbench.solvers import registry

PLUGIN = textwrap.dedent('''
    import os
    import signal
    import time

    import numpy as np

    from lcpbench.solvers.base import LCPSolution, Status
    from lcpbench.solvers.registry import Backend


    def solve_lcp(M, q, settings, warm=None, mode="ok", **options):
        if mode == "hang":
            time.sleep(600)
        if mode == "crash":
            os.kill(os.getpid(), signal.SIGKILL)
        if mode == "raise":
            raise RuntimeError("this back-end always raises")
        raise AssertionError("unknown mode")


    def _backend(name, mode):
        return Backend(name, "lcp", "dense", False, "pivoting", "lcpbench_misbehave",
                       options={"mode": mode})


    BACKENDS = [_backend("test-hang", "hang"), _backend("test-crash", "crash"),
                _backend("test-raise", "raise")]
''')


@pytest.fixture
def misbehaving_backends(tmp_path_factory, monkeypatch):
    site = tmp_path_factory.mktemp("site")
    (site / "lcpbench_misbehave.py").write_text(PLUGIN)
    info = site / "lcpbench_misbehave-0.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: lcpbench-misbehave\n"
                                   "Version: 0.0\n")
    (info / "entry_points.txt").write_text("[lcpbench.solvers]\nmisbehave = "
                                           "lcpbench_misbehave:BACKENDS\n")
    monkeypatch.syspath_prepend(str(site))
    before = os.environ.get("PYTHONPATH")
    monkeypatch.setenv("PYTHONPATH", str(site) + (os.pathsep + before if before else ""))
    registry._plugins.cache_clear()
    registry._all.cache_clear()
    yield ["test-hang", "test-crash", "test-raise"]
    registry._plugins.cache_clear()
    registry._all.cache_clear()
