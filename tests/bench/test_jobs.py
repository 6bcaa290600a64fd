"""Typed jobs: every kind returns rows of one schema, in process and through the pool."""

import math

import numpy as np
import pytest

from lcpbench.bench.grid import scene_key
from lcpbench.bench.jobs import (
    BaselineJob,
    LineJob,
    ReferenceJob,
    Rows,
    RunJob,
)
from lcpbench.bench.pool import run_jobs
from lcpbench.bench.rows import CERTIFICATE_FIELDS, ROW_FIELDS, failed_row
from lcpbench.bench.sweep import plan_sweep
from lcpbench.problems.scenes import ActuatorScene

SCENES = [ActuatorScene(theta=t, height=5.0, links=20) for t in (120.0, 150.0)]
KEYS = tuple(scene_key(s) for s in SCENES)
JOBS = [ReferenceJob(KEYS[0]), RunJob(KEYS[0], "active-set", "default", 1e-3),
        RunJob(KEYS[0], "lemke", "mid", 1e-6, driver="undamped"),
        BaselineJob(KEYS[1], "baseline"),
        LineJob(KEYS[0], "active-set", "default", 1e-3, predictor="secant", scenes=KEYS)]
ARRAYS = ("forces", "gaps", "x", "y")


def _check_schema(job, rows: Rows):
    assert isinstance(rows, Rows) and rows.complete
    assert len(rows.rows) == job.size == len(job.keys) == len(job.scene_keys)
    for row in rows.rows:
        assert set(ROW_FIELDS) <= set(row)
        assert set(row["certificate"]) == set(CERTIFICATE_FIELDS)
        assert all(isinstance(v, float) for v in row["certificate"].values())
        for a in ARRAYS:
            assert isinstance(row[a], np.ndarray) and row[a].ndim == 1
        assert row["status"] == "solved" and row["converged"] is True
        assert isinstance(row["outer_iterations"], int)
        assert math.isfinite(row["total_force"]) and row["wall_time"] > 0


@pytest.mark.parametrize("job", JOBS, ids=lambda j: j.kind)
def test_every_kind_of_job_gives_rows_of_one_schema(job):
    _check_schema(job, job.execute(30.0))


def test_the_baseline_certificate_is_the_certificate_of_its_answer():
    row = BaselineJob(KEYS[1], "baseline").execute(30.0).rows[0]
    cert = row["certificate"]
    # an answer on the wall, not through it, with its spring torques balanced
    assert cert["min_gap"] >= -1e-6 and cert["min_force"] >= 0.0
    assert cert["relative_torque_residual"] < 1e-6


def test_the_pool_returns_the_same_schema():
    done = dict(run_jobs(JOBS, workers=2, time_limit=60.0))
    assert set(done) == set(JOBS)
    for job, rows in done.items():
        _check_schema(job, rows)


def test_labels_and_store_keys():
    ref, cold, undamped, base, line = JOBS
    assert [j.label for j in JOBS] == ["globalised", "globalised", "undamped", "hybr",
                                      "globalised+secant"]
    assert BaselineJob(KEYS[0], "baseline-fd").label == "lm"
    assert base.jacobian == "analytic" and base.minpack_method == "hybr"
    assert cold.key == (KEYS[0], "active-set", "default", 1e-3, "globalised")
    assert line.keys == [(k, "active-set", "default", 1e-3, "globalised+secant") for k in KEYS]
    assert line.time_limit(2.0) == 4.0 and cold.time_limit(2.0) == 2.0
    # a reference is not timed against the others: a killed reference costs its scene's runs
    assert ref.time_limit(2.0) >= 10 * cold.time_limit(2.0)
    assert not ref.is_stored(set(), set()) and ref.is_stored(set(), {KEYS[0]})
    assert not line.is_stored({line.keys[0]}, set())
    assert line.is_stored(set(line.keys), set())


def test_plan_gives_typed_jobs():
    jobs = plan_sweep(SCENES, ["active-set"], ["default", "mid"],
                      baselines=("baseline", "baseline-fd"))
    kinds = [type(j) for j in jobs]
    assert kinds.count(ReferenceJob) == 2 and kinds.count(BaselineJob) == 4
    assert kinds.count(RunJob) == 4 and LineJob not in kinds
    lines = plan_sweep(SCENES, ["active-set"], ["default"], baselines=(),
                       continuation="previous")
    assert [type(j) for j in lines] == [ReferenceJob, ReferenceJob, LineJob]
    assert lines[-1].predictor == "previous" and lines[-1].scenes == KEYS


def test_failures_have_the_same_fields_and_one_row_per_key():
    failure = failed_row("timeout", "killed", 3.0)
    for job in JOBS:
        rows = job.failure(dict(failure))
        assert not rows.complete and len(rows.rows) == job.size
        for row in rows.rows:
            assert set(ROW_FIELDS) <= set(row) and row["certificate"] is None
    line = JOBS[-1].failure(dict(failure)).rows
    assert [r["wall_time"] for r in line] == [1.5, 1.5]
    assert all("continuation line of 2 scenes" in r["reason"] for r in line)


def test_a_job_that_raises_costs_failure_rows(monkeypatch):
    import lcpbench.api
    import lcpbench.studies.batch
    import lcpbench.studies.continuation

    def boom(*args, **kwargs):
        raise RuntimeError("this solve always raises")

    monkeypatch.setattr(lcpbench.api, "solve", boom)
    monkeypatch.setattr(lcpbench.studies.continuation, "solve_sequence", boom)
    monkeypatch.setattr(lcpbench.studies.batch, "solve_many", boom)  # a line is one batch
    for job in JOBS[1], JOBS[-1]:
        rows = job.execute(5.0)
        assert not rows.complete and len(rows.rows) == job.size
        for row in rows.rows:
            assert row["status"] == "error" and "always raises" in row["reason"]
            assert set(ROW_FIELDS) <= set(row) and "traceback" in row
