"""The exported qpbenchmark test set: read back by qpsolvers' loader, checked independently."""

import math

import numpy as np
import pytest
from energy_oracle import energy_minimum

from lcpbench.bench.testset import (
    RESULT_COLUMNS,
    load_problem,
    read_results,
    write_results,
)
from lcpbench.bench.testset_files import export_testset
from lcpbench.cli import main
from lcpbench.problems.scenes import ActuatorScene

qpsolvers = pytest.importorskip("qpsolvers")

SCENES = [ActuatorScene(theta=150.0, height=3.0, links=20),
          ActuatorScene(theta=120.0, height=4.0, links=24, channel=True)]
SOLVERS = ["active-set", "lemke", "osqp"]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    out = tmp_path_factory.mktemp("ts")
    info = export_testset(SCENES, out, solvers=SOLVERS, settings=["default", "high"],
                          grid="test")
    return out, info


def _meta(out):
    import csv

    with open(out / "problems.csv") as fh:
        return {r["name"]: r for r in csv.DictReader(fh)}


def test_every_problem_loads_with_qpsolvers_loader(exported):
    out, info = exported
    files = sorted((out / "data").glob("*.npz"))
    assert info["problems"] == len(files) == 4  # first and converged step per scene
    meta = _meta(out)
    for f in files:
        prob = qpsolvers.Problem.load(str(f))  # what qpbenchmark.Problem.load calls
        prob.check_constraints()
        assert prob.G is None and prob.A is None and prob.h is None and prob.b is None
        m = meta[f.stem]
        n = int(m["n"])
        assert prob.P.shape == (n, n) and prob.q.shape == prob.lb.shape == (n,)
        np.testing.assert_array_equal(prob.P, prob.P.T)
        # the condition number, recomputed by dense numpy
        assert float(m["cond_P"]) == pytest.approx(np.linalg.cond(prob.P), rel=1e-6)
        # the optimal cost, by a solver that shares nothing with lcpbench's active set
        x = qpsolvers.solve_problem(prob, solver="quadprog").x
        cost = 0.5 * x @ prob.P @ x + prob.q @ x
        assert float(m["optimal_cost"]) == pytest.approx(cost, rel=1e-7, abs=1e-10)
        assert load_problem(f)["G"] is None


def test_converged_step_reproduces_the_reference_force(exported):
    out, _ = exported
    for scene in SCENES:
        name = (f"LCPB-N{scene.links}-T{scene.theta:g}-H{scene.height:g}"
                f"{'-C' if scene.channel else ''}-converged")
        prob = qpsolvers.Problem.load(str(out / "data" / f"{name}.npz"))
        sol = qpsolvers.solve_problem(prob, solver="quadprog")
        assert sol.found
        ref = energy_minimum(scene)  # the direct minimisation (tests/energy_oracle.py)
        unit = scene.EI / scene.length**2  # the multipliers are reactions in EI/l^2
        upper = np.maximum(sol.z_box, 0.0) * unit
        assert upper.sum() == pytest.approx(ref.total_force, rel=1e-6)
        # the wall is the upper bound, h / l, at the nodes that can touch it (+inf at
        # the others), and the second wall of a channel the lower one
        wall = np.isfinite(prob.ub)
        assert wall.any()
        assert np.allclose(prob.ub[wall], scene.height / scene.length)
        if scene.channel:
            assert np.allclose(prob.lb[wall], -scene.height / scene.length)
        else:
            assert np.all(np.isneginf(prob.lb))


def test_results_in_qpbenchmark_schema_round_trip(exported, tmp_path):
    out, info = exported
    rows = read_results(out / "results" / "lcpbench_contact.csv")
    assert info["results"] == len(rows) == 4 * len(SOLVERS) * 2
    assert {r["settings"] for r in rows} == {"default", "high_accuracy"}
    for r in rows:
        if r["found"]:  # judged SOLVED: qpbenchmark's residuals are small
            assert r["primal_residual"] <= 1e-9 and r["dual_residual"] <= 1e-5
            assert r["duality_gap"] <= 1e-5
        else:  # written as qpbenchmark writes a failure
            assert math.isinf(r["primal_residual"]) and math.isinf(r["duality_gap"])
    exact = [r for r in rows if r["solver"] in ("active-set", "lemke")]
    assert all(r["found"] for r in exact)
    write_results(rows, tmp_path / "again.csv")
    assert read_results(tmp_path / "again.csv") == sorted(
        rows, key=lambda r: (r["problem"], r["solver"], r["settings"]))
    header = (out / "results" / "lcpbench_contact.csv").read_text().splitlines()[0]
    assert tuple(header.split(",")) == RESULT_COLUMNS


def test_test_set_module_and_readme(exported):
    out, _ = exported
    source = (out / "lcpbench_contact.py").read_text()
    compile(source, "lcpbench_contact.py", "exec")
    text = (out / "README.md").read_text()
    assert "python lcpbench_contact.py run" in text and "N⁴" in text


def test_test_set_module_loads_in_qpbenchmark(exported):
    qpbenchmark = pytest.importorskip("qpbenchmark")
    import importlib.util

    out, _ = exported
    spec = importlib.util.spec_from_file_location("lcpbench_contact",
                                                  out / "lcpbench_contact.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    ts = mod.LcpbenchContact()
    assert isinstance(ts, qpbenchmark.TestSet) and ts.count_problems() == 4


def test_cli_refuses_to_replace_a_test_set(exported, capsys):
    out, _ = exported
    code = main(["export-testset", "--theta", "150", "--height", "3", "--links", "20",
                 "--out", str(out), "--no-results", "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--overwrite" in err[0]
