"""The ``solvers`` listing and the store commands (``select``) of the command line."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from lcpbench.cli import main


def test_solvers_lists_every_backend(capsys):
    from lcpbench.solvers import backends

    assert main(["solvers"]) == 0
    out = capsys.readouterr().out
    for name in backends():
        assert name in out
    assert main(["solvers", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert {r["name"] for r in rows} == set(backends())
    for r in rows:
        assert {"available", "version", "form", "storage", "warm_start", "method",
                "install"} <= set(r)


def test_select_cli(tmp_path, capsys):
    args = ["select", "--force-tol", "1e-3", "--links", "20", "--solvers", "active-set,lemke",
            "--store", str(tmp_path / "s.sqlite"), "--quiet", "--jobs", "2", "--oversubscribe"]
    code = main([*args, "--json"])
    d = json.loads(capsys.readouterr().out)  # exactly one JSON document on stdout
    assert code == 0 and d["backend"] in ("active-set", "lemke") and d["error"] <= 1e-3
    assert d["force_tol"] == 1e-3 and d["driver_tol"] == 1e-3  # relative force error; rad
    assert main(args) == 0  # cached the second time; one line with the reason
    out = capsys.readouterr().out.strip()
    assert len(out.splitlines()) == 1
    # the options that run the selection with `lcpbench solve`: back-end, profile, the
    # probes' driver tol (the accuracy's, which the profile alone would not give)
    assert out.startswith(f"--solver {d['backend']} --settings {d['settings']} --tol 0.001:")


def test_a_second_sweep_on_a_locked_store_exits_2_naming_the_holder(tmp_path, capsys):
    from lcpbench.bench.store import Store
    from lcpbench.cli import main

    path = tmp_path / "s.sqlite"
    with Store(path) as store, store.lock("lcpbench sweep"):
        code = main(["sweep", "--theta", "150", "--height", "3", "--links", "20",
                     "--solvers", "active-set", "--settings", "default", "--baseline", "none",
                     "--store", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "locked by pid" in err[0]


def test_jobs_above_the_core_count_need_oversubscribe(capsys):
    """More workers than cores would store the times of processes sharing a
    core: refused with one line unless --oversubscribe."""
    import os

    from lcpbench.cli import main
    from lcpbench.cli._common import worker_count

    cores = os.cpu_count() or 1
    assert main(["sweep", "--jobs", str(cores + 1), "--solvers", "active-set",
                 "--baseline", "none"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--oversubscribe" in err[0] and f"{cores} cores" in err[0]
    assert worker_count(cores + 1, oversubscribe=True) == cores + 1
    assert worker_count(cores) == cores


def test_progress_has_one_bar_per_phase_and_counts_expected_failures(tmp_path):
    """Issue 15: references and runs get their own bars (their own ETA); failures the
    docs expect (PGS not converging) are counted apart from the others."""
    from lcpbench.bench.jobs import ReferenceJob, RunJob
    from lcpbench.cli._common import ProgressBar

    bar = ProgressBar({"references": 2, "runs": 3})
    ref, pgs, act = ReferenceJob("s1"), RunJob("s1", "pgs", "high", 1e-9), \
        RunJob("s1", "active-set", "high", 1e-9)
    bar.update(1, 5, ref, {"converged": 1})
    bar.update(2, 5, pgs, {"status": "not_converged"})
    bar.update(3, 5, act, {"status": "not_converged"})
    bar.update(4, 5, act, {"status": "solved"})
    assert bar.bars["references"].total == 2 and bar.bars["references"].n == 1
    assert bar.bars["runs"].total == 3 and bar.bars["runs"].n == 3
    assert (bar.failed, bar.expected) == (2, 1)
    bar.close()


def test_one_bar_follows_each_sweep_it_is_handed(tmp_path):
    # select runs two sweeps on one bar (the first probe, then the rest): each sweep's
    # count starts again at 1 of its own total, and the bar must show that count, not
    # run past its first total
    from lcpbench.bench.jobs import RunJob
    from lcpbench.cli._common import ProgressBar

    bar = ProgressBar()
    job = RunJob("s1", "active-set", "high", 1e-9)
    for done in (1, 2, 3, 4):
        bar.update(done, 4, job, {"status": "solved"})
    assert (bar.bar.n, bar.bar.total) == (4, 4)
    for done in (1, 2):
        bar.update(done, 12, job, {"status": "solved"})
    assert (bar.bar.n, bar.bar.total) == (2, 12)
    bar.update(7, 9, job, {"status": "solved"})  # a resumed sweep: 6 of 9 already in
    assert (bar.bar.n, bar.bar.total) == (7, 9)
    assert bar.bar.initial == 6  # stored rows count as done, not in the rate (its ETA)
    bar.close()


TINY_KERNEL = """
from numba import njit


@njit(cache=True)
def twice(x):
    return 2.0 * x
"""

CALL_TINY_KERNEL = """
import sys

from numba.core import config

config.CACHE_DIR = sys.argv[1]
sys.path.insert(0, sys.argv[2])
import tiny_kernel
from lcpbench import numba_cache
from lcpbench.cli import _first_use_notice

numba_cache.light_cache_load(tiny_kernel.twice)  # as jit_module hooks every kernel
_first_use_notice()
assert tiny_kernel.twice(2.0) == 4.0 and tiny_kernel.twice(3.0) == 6.0
assert tiny_kernel.twice(2) == 4.0  # a second signature: compiled too, no second line
"""


def test_a_first_compile_says_so_once_and_a_cached_kernel_says_nothing(tmp_path):
    # a real numba kernel in a cache of its own: the first process compiles it (one
    # line, whatever it calls after), the second loads it from the cache (no line)
    (tmp_path / "tiny_kernel.py").write_text(TINY_KERNEL)
    cmd = [sys.executable, "-c", CALL_TINY_KERNEL, str(tmp_path / "cache"), str(tmp_path)]
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_DISABLE_JIT",
                                                            "LCPBENCH_NUMBA_FULL_LOAD")}
    first = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    assert first.returncode == 0, first.stderr
    assert first.stderr.count("compiling kernels") == 1, first.stderr
    again = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    assert again.returncode == 0, again.stderr
    assert "compiling" not in again.stderr, again.stderr
