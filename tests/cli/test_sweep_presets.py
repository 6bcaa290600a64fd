"""What `lcpbench sweep` runs by default (the main job) and with --standard (issue 15).

The main job is the paper's grid over every installed back-end but those the
documentation says never converge on a contact step, at settings default,
with the analytic baseline, each run timed once; --standard is the committed
standard run. Explicit options override either. Nothing is faked: a back-end
left out has no rows, and the sweep says so.
"""

from __future__ import annotations

from lcpbench.bench.expected import EXPECTED, never_converges
from lcpbench.bench.store import Store
from lcpbench.cli import build_parser, main
from lcpbench.cli.sweep import _apply_preset, sweep_backends
from lcpbench.solvers.registry import available_backends


def _args(*argv):
    args = build_parser().parse_args(["sweep", *argv])
    _apply_preset(args)
    return args


def test_never_converging_are_the_documented_pgs_and_newton_min():
    # README, Results: PGS/SOR (ours and Siconos's) and Siconos Newton-min
    assert {b for b in ("pgs", "psor", "siconos-pgs", "siconos-newton-min", "lemke",
                        "osqp", "active-set", "baseline") if never_converges(b)} == {
        "pgs", "psor", "siconos-pgs", "siconos-newton-min"}
    # each is one of the documented expected failures, at any settings
    for b in ("pgs", "siconos-newton-min"):
        assert never_converges(b) in EXPECTED and never_converges(b).settings is None


def test_main_job_defaults():
    args = _args()
    assert (args.settings, args.baseline, args.repeat) == ("default", "analytic", 1)
    solvers, settings = sweep_backends(args)
    assert settings == ["default"]
    assert solvers == [b for b in available_backends() if not never_converges(b)]
    assert "active-set" in solvers and "pgs" not in solvers


def test_standard_run_defaults_and_explicit_options_win():
    args = _args("--standard")
    assert (args.settings, args.baseline, args.repeat) == ("default,high", "both", 3)
    solvers, settings = sweep_backends(args)
    assert solvers == available_backends() and settings == ["default", "high"]
    args = _args("--standard", "--settings", "high", "--baseline", "none", "--repeat", "2")
    assert (args.settings, args.baseline, args.repeat) == ("high", "none", 2)
    args = _args("--solvers", "all")  # every installed back-end in the main job's settings
    assert sweep_backends(args)[0] == available_backends()
    assert args.settings == "default"


def test_main_job_runs_what_it_says_and_announces_what_it_leaves_out(tmp_path, capsys):
    store = tmp_path / "s.sqlite"
    assert main(["sweep", "--theta", "150", "--height", "3", "--links", "20", "--solvers",
                 "active-set,pgs", "--store", str(store), "--jobs", "1", "--quiet",
                 "--no-report"]) == 0
    with Store(store) as st:
        runs = st.runs(arrays=False)
    # an explicit --solvers runs PGS too; the main job's settings, baseline and repeat
    assert sorted((r["backend"], r["settings"]) for r in runs) == [
        ("active-set", "default"), ("baseline", "-"), ("pgs", "default")]
    assert {r["repeats"] for r in runs} == {1}
    err = capsys.readouterr().err
    assert "the main job" in err and "lcpbench sweep --standard" in err


def test_default_sweep_says_which_documented_failures_it_leaves_out(capsys):
    from lcpbench.cli.sweep import _print_backends

    args = _args()
    solvers, _ = sweep_backends(args)
    _print_backends(solvers, explicit=False, main_job=True)
    err = capsys.readouterr().err
    line = next(ln for ln in err.splitlines() if "never to converge" in ln)
    assert line.startswith("skipping") and "pgs" in line and "--standard" in line
