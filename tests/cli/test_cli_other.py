"""The ``solvers`` listing and the store commands (``select``) of the command line."""

from __future__ import annotations

import json

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


def test_a_first_use_says_the_kernels_compile_and_later_uses_do_not(tmp_path, monkeypatch,
                                                                    capsys):
    # the notice follows the kernels' cache directory: absent, one line; present, none
    import lcpbench.numba_cache as nc
    from lcpbench.cli import _first_use_notice

    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    monkeypatch.setattr(nc, "kernels_dir", lambda: str(tmp_path / "not-yet"))
    _first_use_notice()
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "compiling the solve kernels" in err
    (tmp_path / "not-yet").mkdir()
    _first_use_notice()
    assert capsys.readouterr().err == ""
