"""`lcpbench sweep` killed with SIGKILL and restarted gives the uninterrupted run's table."""

import json
import subprocess
import sys

import pytest
from sweep_kill import killed_after_first_run

from lcpbench.bench.metrics import evaluate, summarise
from lcpbench.bench.store import Store

# 4 scenes x (3 back-ends + baseline) + 4 references = 20 jobs of N = 20: PGS takes
# ~0.3 s a scene, so a sweep lasts a few seconds and is killed after its first run.
ARGS = ["sweep", "--theta", "120,150", "--height", "3,5", "--links", "20",
        "--solvers", "active-set,lemke,pgs", "--settings", "default", "--baseline",
        "analytic", "--jobs", "2", "--oversubscribe", "--quiet", "--no-report"]
RUNS = 4 * 4
TIMES = ("time_sgm_ms", "time_median_successes_ms", "time_sgm_rel", "speedup_vs_baseline",
         "speedup_vs_baseline_fd")


def _cmd(store):
    return [sys.executable, "-m", "lcpbench.cli", *ARGS, "--store", str(store)]


def _table(store_path, out):
    from lcpbench.cli import main

    assert main(["report", "--no-plots", "--store", str(store_path), "--out", str(out)]) == 0
    with Store(store_path) as st:
        runs = st.runs()
        summary = summarise(evaluate(runs, st.refs()))
    stored = {(r["scene"], r["backend"], r["settings"]): (r["status"], r["total_force"],
              r["outer_iterations"], r["inner_iterations"], tuple(r["forces"]))
              for r in runs}
    report = json.loads((out / "summary.json").read_text())
    for row in [*summary, *report]:
        for k in TIMES:
            row.pop(k, None)
    return len(runs), stored, summary, report


def test_sigkill_then_restart_gives_the_same_table(tmp_path):
    """Route against route: the rows must not depend on the executor or on a
    restart (determinism); the serial rows are checked against the sweep's
    reference, itself against the energy minimum, in tests/bench/test_sweep.py."""
    clean = tmp_path / "clean.sqlite"
    killed, _ = killed_after_first_run(_cmd, tmp_path, RUNS, group=True)
    # the uninterrupted sweep, in its own store (started after the kill: the poll above
    # shares the cores with fewer processes)
    whole = subprocess.Popen(_cmd(clean), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True)

    again = subprocess.run(_cmd(killed), capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert "already in" in again.stdout
    _, err = whole.communicate(timeout=120)
    assert whole.returncode == 0, err

    n_killed, rows_killed, sum_killed, rep_killed = _table(killed, tmp_path / "rk")
    n_clean, rows_clean, sum_clean, rep_clean = _table(clean, tmp_path / "rc")
    assert n_killed == n_clean == RUNS  # nothing lost, nothing twice
    assert rows_killed == rows_clean  # every run: same status, forces and iterations
    same = json.dumps  # NaN-aware: NaN != NaN, but its text is the same
    assert same(sum_killed, sort_keys=True) == same(sum_clean, sort_keys=True)  # the table
    assert same(rep_killed, sort_keys=True) == same(rep_clean, sort_keys=True)
    assert (tmp_path / "rk" / "report.md").exists()


@pytest.mark.parametrize(("args", "message"), [
    (["--theta", "10:5:1"], "theta must be"),
    (["--height", "a:b"], "height must be"),
    (["--links", "3"], "links"),
    (["--solvers", "nope"], "nope"),
    (["--settings", "fast"], "settings must be one of"),
    (["--jobs", "0"], "jobs must be"),
    (["--time-limit", "-1"], "time-limit must be"),
    (["--tol", "2"], "tol must be"),
])
def test_bad_sweep_input_is_one_line_and_exit_2(tmp_path, args, message, capsys):
    from lcpbench.cli import main

    code = main(["sweep", "--store", str(tmp_path / "s.sqlite"), "--quiet", *args])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and message in err
    assert not (tmp_path / "s.sqlite").exists()  # nothing ran, nothing was created


def test_corrupt_store_is_exit_2_and_untouched(tmp_path, capsys):
    from lcpbench.cli import main

    store = tmp_path / "s.sqlite"
    store.write_bytes(b"garbage" * 100)
    for argv in (["sweep", "--theta", "150", "--height", "3", "--solvers", "active-set",
                  "--quiet"], ["report"]):
        code = main([*argv, "--store", str(store), "--out", str(tmp_path / "o")])
        err = capsys.readouterr().err
        assert code == 2 and len(err.strip().splitlines()) == 1
        assert "left as it is" in err
        assert store.read_bytes() == b"garbage" * 100


def test_report_needs_an_existing_store(tmp_path, capsys):
    from lcpbench.cli import main

    assert main(["report", "--store", str(tmp_path / "none.sqlite")]) == 2
    assert "no such file" in capsys.readouterr().err
