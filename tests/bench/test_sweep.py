"""The sweep harness: rows checked against independent answers, resume, limits, crashes."""

import numpy as np
import pytest
from energy_oracle import energy_minimum

from lcpbench.bench.grid import scene_from_key
from lcpbench.bench.jobs import PROFILE_TOL, REFERENCE_TOL
from lcpbench.bench.metrics import error_of, success_tol
from lcpbench.bench.store import Store
from lcpbench.bench.sweep import plan_sweep, sweep
from lcpbench.errors import ProblemError
from lcpbench.problems.scenes import ActuatorScene

# Two scenes of N = 30: one in contact at h >= 4 mm, where the paper's baseline
# agrees with the LCP (Fig. 26), and one whose arc (height 3.8 mm at 60 deg)
# never reaches a 5 mm wall.
SCENES = [ActuatorScene(theta=150.0, height=5.0, links=30),
          ActuatorScene(theta=60.0, height=5.0, links=30)]


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    path = tmp_path_factory.mktemp("sweep") / "s.sqlite"
    jobs = plan_sweep(SCENES, ["active-set", "lemke"], ["default", "high"])
    with Store(path) as st:
        plan = sweep(st, jobs, workers=2)
        runs, refs = st.runs(), st.refs()
    return path, jobs, plan, runs, refs


def test_every_job_is_stored_once(swept):
    path, jobs, plan, runs, refs = swept
    assert len(plan.todo) == len(jobs) == 2 + 2 * (1 + 2 * 2)
    assert len(refs) == 2 and len(runs) == 2 * (1 + 4)
    assert len({(r["scene"], r["backend"], r["settings"]) for r in runs}) == len(runs)


def test_reference_is_converged_and_confirmed_by_lemke(swept):
    *_, refs = swept
    for key, ref in refs.items():
        assert ref["converged"] and ref["tol"] <= 1e-10 and ref["tol"] >= REFERENCE_TOL
        # its last step re-solved by Lemke, a different algorithm on the dense LCP
        assert ref["check_error"] < 1e-8
        assert ref["forces"].sum() == pytest.approx(ref["total_force"], abs=1e-15)
        # and the scene's energy minimum (tests/energy_oracle.py), so the rows checked
        # against it below are checked against an oracle: 1e-9 of EI/ℓ² (the reference's
        # tol 1e-10 rad; the minimiser's own error ~1e-11)
        scene = scene_from_key(key)
        want = energy_minimum(scene).total_force
        assert abs(ref["total_force"] - want) <= 1e-9 * max(want, scene.EI / scene.length**2)


def test_runs_agree_with_the_reference(swept):
    *_, runs, refs = swept
    for r in runs:
        ref = refs[r["scene"]]
        if r["backend"] == "baseline":
            continue
        assert r["status"] == "solved" and r["converged"]
        assert r["tol"] == PROFILE_TOL[r["settings"]]
        err = error_of(r["total_force"], ref["total_force"], r["EI"] / r["length"] ** 2)
        assert err <= success_tol(r["tol"])
        # complementarity of the stored per-node answer: R >= 0, g >= 0, R.g = 0
        assert r["forces"].min() >= -1e-9 and r["gaps"].min() >= -1e-6
        assert np.max(np.abs(r["forces"] * r["gaps"])) < 1e-8


def test_no_contact_scene_has_no_force(swept):
    *_, runs, refs = swept
    for r in runs:
        if r["theta"] == 60.0 and r["backend"] != "baseline":
            # zero up to round-off, in the chain's force unit EI/l^2
            assert abs(r["total_force"]) <= 1e-8 * r["EI"] / r["length"] ** 2


def test_baseline_rows(swept):
    *_, runs, refs = swept
    base = {r["theta"]: r for r in runs if r["backend"] == "baseline"}
    # h = 5 mm >= 4 mm: the single midspan reaction is right (paper, Fig. 26: within 0.1 %)
    ok = base[150.0]
    assert ok["status"] == "solved"
    ref = refs[ok["scene"]]["total_force"]
    assert abs(ok["total_force"] - ref) <= 1e-3 * ref
    # no contact: a midspan node held at h needs a pulling wall, which is no answer
    assert base[60.0]["status"] == "invalid" and not base[60.0]["converged"]


def test_restart_skips_what_is_stored_and_rerun_recomputes(swept):
    """Route against route: the rows must not depend on the executor or on a
    restart (determinism); the serial rows are checked against the sweep's
    reference, itself against the energy minimum, above."""
    path, jobs, *_ = swept
    with Store(path) as st:
        n = st.count()
        plan = sweep(st, jobs)
        assert plan.todo == [] and st.count() == n
        some = [j for j in jobs if j.backend == "lemke"]
        plan = sweep(st, some, rerun=True)
        assert len(plan.todo) == len(some) and st.count() == n


def test_parallel_sweep_gives_the_serial_numbers(tmp_path):
    """Route against route: the rows must not depend on the executor or on a
    restart (determinism); the serial rows are checked against the sweep's
    reference, itself against the energy minimum, above."""
    jobs = plan_sweep(SCENES[:1], ["active-set", "qpsolvers-piqp"
                                   if _installed("qpsolvers-piqp") else "lemke"],
                      ["default"], baselines=())
    out = []
    for workers in (1, 2):
        with Store(tmp_path / f"w{workers}.sqlite") as st:
            sweep(st, jobs, workers=workers)
            out.append({(r["backend"], r["settings"]): r for r in st.runs()})
    assert out[0].keys() == out[1].keys()
    for k in out[0]:
        np.testing.assert_array_equal(out[0][k]["forces"], out[1][k]["forces"])
        assert out[0][k]["outer_iterations"] == out[1][k]["outer_iterations"]


def _installed(name):
    from lcpbench.solvers.registry import available_backends

    return name in available_backends()


def test_hang_crash_and_raise_cost_one_row_each(tmp_path, misbehaving_backends):
    jobs = plan_sweep(SCENES[:1], ["active-set", *misbehaving_backends], ["default"],
                      baselines=())
    with Store(tmp_path / "s.sqlite") as st:
        sweep(st, jobs, workers=2, time_limit=8.0)  # room for worker start-up under load
        rows = {r["backend"]: r for r in st.runs(arrays=False)}
    assert set(rows) == {"active-set", *misbehaving_backends}
    assert rows["active-set"]["status"] == "solved"
    assert rows["test-hang"]["status"] == "timeout" and "time limit" in rows["test-hang"]["reason"]
    assert rows["test-crash"]["status"] == "crashed"
    # an exception in a back-end is its step's FAILED status: the driver stops, says why
    assert rows["test-raise"]["status"] == "not_converged"
    assert "always raises" in rows["test-raise"]["reason"]
    assert not any(rows[b]["converged"] for b in misbehaving_backends)


def test_a_formulation_is_a_run_of_its_own(tmp_path):
    """--formulation: each back-end's runs stored as method driver@form, beside and
    equal (to the tolerance) to the reference; a back-end's own form is the plain run."""
    with pytest.raises(ProblemError, match="active-set does not take reactions"):
        plan_sweep(SCENES[:1], ["active-set"], ["high"], formulation="reactions")
    jobs = plan_sweep(SCENES[:1], ["lemke"], ["high"], baselines=(), formulation="reactions")
    assert [j.label for j in jobs if hasattr(j, "driver")] == ["globalised@reactions"]
    assert [j.label for j in plan_sweep(SCENES[:1], ["lemke"], ["high"], baselines=(),
                                        formulation="gaps") if hasattr(j, "driver")] \
        == ["globalised"]  # Lemke's own form: the plain run
    with Store(tmp_path / "f.sqlite") as st:
        sweep(st, jobs, workers=1)
        runs, refs = st.runs(), st.refs()
    (row,) = runs
    assert row["method"] == "globalised@reactions" and row["converged"]
    ref = refs[row["scene"]]
    assert error_of(row["total_force"], ref["total_force"], 32.01 / 30 ** 2) <= success_tol(
        PROFILE_TOL["high"])
