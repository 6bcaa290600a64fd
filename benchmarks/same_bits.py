"""Did a change move any answer? Answers recorded bit for bit, two trees compared.

A refactoring of the solve (issue 35: each concept once) is meant to keep the
answers. This records a corpus of answers of the tree on ``PYTHONPATH`` (or the
installed one) and compares two such records; it also re-solves the default
back-end's rows of ``results/sweep/runs.csv`` against their stored forces.

    python benchmarks/same_bits.py record before.pkl     # on the old tree
    python benchmarks/same_bits.py record after.pkl      # on the new one
    python benchmarks/same_bits.py compare before.pkl after.pkl
    python benchmarks/same_bits.py sweep                 # the committed sweep's rows

The corpus (about 2,300 answers; ~5 min on one core):
- ``solve_many`` on mixed batches (elastic and profiled walls, sections), the
  paper's grid, random elastic walls (k from 1e-3 to 1e9 N/mm²) and channels;
- ``solve`` and ``start="ramp"`` on rows of two and three sections, and past 180°;
- channels, heavy channels, a stenosis and a profiled channel with the default
  back-end, OSQP and Lemke (the compiled driver around a back-end);
- the wall-free path (arcs clear of flat, elastic, channel and profiled walls, loaded
  arcs on them), with the default back-end and Lemke, and a profiled line solved by
  continuation (``solve_sequence``);
- large N (3000, 6000) with one wall, a channel, a wall profile and elastic walls;
- friction: ``solve_path`` on a flat wall, a channel and a stenosis, pulled and
  released; 40 random paths of 4 states as ``benchmarks/friction_paths.py`` draws
  them (seed 39: every end condition, channels, μ 0.05–0.8);
- the Newton scheme on 30 random flat, channel and elastic scenes (default back-end
  and OSQP), and the sensitivities of five answers (flat, channel, elastic, a
  stenosis, a heavy chain);
- the active set on 200 random box QPs of every face kind (banded, a few more
  sub-diagonals, dense) and on 100 dense LCPs (``solve_lcp``).

Each answer is recorded as (converged, reason, total force, forces, lower
forces, α, outer iterations; with friction the tangential forces, slips and
stick; the judge's bounds, judge force, contractions and rounds) with the
numbers as bytes (a zero's sign counts). ``compare`` counts the answers the same bit
for bit and lists every other: a changed verdict, the judge's numbers moved, or the
forces moved (with the judge's allowance τ F₀ where the answer was judged). ``sweep`` exits 1 if a
row's force moved at all: the sweep's cold rows by ``lcpbench.solve``, its
continuation rows by ``lcpbench sweep --solvers active-set --continuation
adaptive`` into a temporary store.

Nothing is written but the record named.
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import collections
import csv
import json
import pickle
import sqlite3
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.problems.walls import WallProfile
from lcpbench.studies.continuation import solve_sequence

RUNS = HERE.parent / "results" / "sweep" / "runs.csv"


def _bytes(x) -> bytes | None:
    return None if x is None else np.asarray(x, dtype=float).tobytes()


def answer(r) -> dict:
    """What is compared of one answer (a ContactResult or a FrictionResult)."""
    j = getattr(r, "judgement", None)
    allowed = (float(j.force_tol * j.force_unit)
               if j is not None and hasattr(j, "force_tol") else np.nan)
    return dict(converged=bool(r.converged), reason=str(r.reason),
                total_force=float(r.total_force), total_bits=_bytes(r.total_force),
                forces=_bytes(r.forces), lower=_bytes(getattr(r, "forces_lower", None)),
                alpha=_bytes(getattr(r, "alpha", None)),
                outer=getattr(r, "outer_iterations", None),
                # a frictional answer's tangential forces, slips and stick
                **{f: _bytes(getattr(r, f, None)) for f in ("tangential_forces", "slip",
                                                            "stick")},
                allowed=allowed, judge=_judge_numbers(j))


def _judge_numbers(j) -> bytes | None:
    """The judge's own numbers of an answer, bit for bit: its force error bounds, its
    step's total force, the contractions and its rounds (None: not judged so)."""
    fields = ("force_error_bound", "node_error_bound", "judge_total_force", "contraction",
              "judge_contraction", "judge_rounds")
    if j is None or not hasattr(j, "force_error_bound"):
        return None
    return _bytes([np.nan if getattr(j, f, None) is None else getattr(j, f) for f in fields])


def _kept(out: dict, key, solve) -> None:
    try:
        out[key] = answer(solve())
    except Exception as e:  # noqa: BLE001 (an error is an outcome to compare too)
        out[key] = dict(error=repr(e))


def corpus() -> dict:
    """Every answer of the corpus, by key."""
    import mixed_batch as mb
    from cold_sqp_states import rows_of

    out: dict = {}
    for seed in (7, 8, 9, 11, 12, 13):
        for i, r in enumerate(lcpbench.solve_many(mb.mixed(seed), tol=1e-3)):
            out[("many-mixed", seed, i)] = answer(r)
    for i, r in enumerate(lcpbench.solve_many(mb.paper_grid(), tol=1e-3)):
        out[("many-grid", i)] = answer(r)
    rng = np.random.default_rng(2027)
    for b in range(2):
        el = [ActuatorScene(theta=float(rng.uniform(60, 200)), height=float(rng.uniform(1.5, 5)),
                            links=140, wall_stiffness=float(10 ** rng.uniform(-3, 9)))
              for _ in range(100)]
        ch = [ActuatorScene(theta=float(rng.uniform(60, 300)), height=float(rng.uniform(0.6, 5)),
                            links=140, channel=True) for _ in range(100)]
        for name, batch in (("many-el", el), ("many-ch", ch)):
            for i, r in enumerate(lcpbench.solve_many(batch, tol=1e-3)):
                out[(name, b, i)] = answer(r)
    for seed in (7, 8, 11):
        for i, s in enumerate(mb.of_kind(seed, "two sections")):
            _kept(out, ("solve-row", seed, i), lambda s=s: lcpbench.solve(s))
            _kept(out, ("ramp-row", seed, i), lambda s=s: lcpbench.solve(s, start="ramp"))
    for k, (sections, channel) in enumerate(((2, False), (2, True), (3, False), (3, True))):
        for i, s in enumerate(rows_of(100 + k, sections, channel, count=40)):
            _kept(out, ("solve-rows", k, i), lambda s=s: lcpbench.solve(s))
    for i in range(30):
        s = ActuatorScene(theta=float(rng.uniform(190, 300)), height=float(rng.uniform(0.8, 4)),
                          links=140, channel=bool(i % 2))
        _kept(out, ("ramp-past180", i), lambda s=s: lcpbench.solve(s, start="ramp"))
        _kept(out, ("solve-past180", i), lambda s=s: lcpbench.solve(s))
    up = WallProfile.from_table([-5, 10, 14, 18, 35], [3.0, 3.0, 2.4, 3.0, 3.0])
    rng = np.random.default_rng(5)
    kinds = []
    for _ in range(12):
        th, h = float(rng.uniform(60, 170)), float(rng.uniform(1.0, 4))
        kinds += [("channel", ActuatorScene(theta=th, height=h, links=140, channel=True)),
                  ("heavy channel", ActuatorScene(theta=th, height=h, links=140, channel=True,
                                                  weight=0.01)),
                  ("stenosis", ActuatorScene(theta=th, height=3.0, links=140, wall_profile=up)),
                  ("profiled channel", ActuatorScene(theta=th, height=3.0, links=140,
                                                     channel=True, wall_profile=up,
                                                     lower_profile=up.mirrored()))]
    for tag, s in kinds:
        for solver in ("auto", "osqp", "lemke"):
            _kept(out, (tag, s.theta, solver), lambda s=s, v=solver: lcpbench.solve(
                s, solver=v, tol=1e-6))
    for i, r in enumerate(lcpbench.solve_many([s for _, s in kinds], tol=1e-3)):
        out[("many-kinds", i)] = answer(r)
    # the wall-free path: arcs that clear their walls and loaded arcs on a wall (the
    # first step without walls decides), flat, elastic, channel and profiled walls, with
    # the default back-end and Lemke; a profiled line by continuation (Solved)
    for theta in (30.0, 60.0, 150.0):
        for h in (3.0, 8.0):
            for tag, kw in (("flat", {}), ("channel", {"channel": True}),
                            ("elastic", {"wall_stiffness": 5.0}), ("profile", {
                                "wall_profile": WallProfile.from_table(
                                    [-5, 10, 14, 18, 35], [h, h, 0.8 * h, h, h])})):
                s = ActuatorScene(theta=theta, height=h, links=140, **kw)
                for solver in ("auto", "lemke"):
                    _kept(out, ("wall-free", tag, theta, h, solver),
                          lambda s=s, v=solver: lcpbench.solve(s, solver=v, tol=1e-8))
    line = [ActuatorScene(theta=t, height=3.0, links=140, wall_profile=up)
            for t in (20.0, 40.0, 60.0, 100.0, 130.0, 150.0, 160.0, 170.0)]
    for i, r in enumerate(solve_sequence(line, predictor="adaptive", tol=1e-6)):
        out[("wall-free line", i)] = answer(r)
    for theta in (150.0, 200.0):
        for n in (3000, 6000):
            for channel in (False, True):
                for tag, prof in (("large", None), ("large profiled", up)):
                    s = ActuatorScene(theta=theta, height=2.0, links=n, channel=channel,
                                      wall_profile=prof)
                    _kept(out, (tag, theta, n, channel), lambda s=s: lcpbench.solve(s, tol=1e-6))
    for k in (0.1, 1e4):  # elastic walls at large N (the judge in increments from 4000)
        for n in (3000, 6000):
            s = ActuatorScene(theta=150.0, height=3.0, links=n, wall_stiffness=k)
            _kept(out, ("large elastic", k, n), lambda s=s: lcpbench.solve(s, tol=1e-6))
    states = [{}, {"pull": 0.05}, {"pull": 0.0}]
    for tag, kw in (("friction flat", {}), ("friction channel", {"channel": True}),
                    ("friction stenosis", {"wall_profile": up})):
        for theta in (120.0, 150.0):
            s = ActuatorScene(theta=theta, height=3.0, friction=0.3, left_end="slider",
                              right_end="slider", **kw)
            try:
                for i, r in enumerate(lcpbench.solve_path(s, states)):
                    out[(tag, theta, i)] = answer(r)
            except Exception as e:  # noqa: BLE001
                out[(tag, theta)] = dict(error=repr(e))
    rng = np.random.default_rng(11)
    for i in range(30):  # the Newton scheme (its test of H + T), flat, channel, elastic
        kw = dict(theta=float(rng.uniform(40, 178)), height=float(rng.uniform(1, 5)),
                  links=140)
        if i % 3 == 1:
            kw["channel"] = True
        if i % 3 == 2:
            kw["wall_stiffness"] = float(10 ** rng.uniform(-2, 6))
        for solver in ("auto", "osqp"):
            _kept(out, ("newton", i, solver), lambda kw=kw, v=solver: lcpbench.solve(
                ActuatorScene(**kw), method="newton", tol=1e-8, solver=v))
    for i, (theta, kw) in enumerate([(150.0, {}), (120.0, {"channel": True}),
                                     (160.0, {"wall_stiffness": 10.0}),
                                     (150.0, {"wall_profile": up}), (165.0, {"weight": 0.01})]):
        try:  # the sensitivities of the answer (implicit differentiation)
            sens = lcpbench.sensitivities(lcpbench.solve(ActuatorScene(
                theta=theta, height=3.0, links=140, **kw), tol=1e-9))
            out[("sensitivities", i)] = {k: _bytes(v) for k, v in sorted(
                sens.total_force.items())}
        except Exception as e:  # noqa: BLE001
            out[("sensitivities", i)] = dict(error=repr(e))
    from friction_paths import ENDS  # the issue-39 audit's ends

    rng = np.random.default_rng(39)
    for index in range(40):  # random frictional paths, as benchmarks/friction_paths.py
        channel = bool(rng.random() < 0.4)
        ends = ENDS[rng.integers(7 if channel else 3)]
        theta = float(rng.uniform(100, 170))
        s = ActuatorScene(theta=theta, height=float(rng.uniform(1.0, 5.0)),
                          links=int(rng.choice([20, 40])), channel=channel, left_end=ends[0],
                          right_end=ends[1], friction=float(rng.uniform(0.05, 0.8)))
        pull = float(rng.uniform(0.0, 0.15)) if ends[1] != "pinned" else 0.0
        states = [{}, {"theta": theta + 10}, {"pull": pull}, {"pull": 0.0}]
        try:
            for i, r in enumerate(lcpbench.solve_path(s, states, tol=1e-8)):
                out[("friction random", index, i)] = answer(r)
        except Exception as e:  # noqa: BLE001
            out[("friction random", index)] = dict(error=repr(e))
    active_set_qps(out)
    return out


def active_set_qps(out: dict) -> None:
    """The active set on QPs of every face kind (the solves above reach only the contact
    step's banded faces): the back-end on 200 random box QPs of bandwidth 1, 2 (the
    banded LDLᵀ), 3–6 (the banded Cholesky of a face) and dense (LAPACK's Cholesky of
    the free block), and ``solve_lcp(M, q, solver="active-set")`` on 100 dense LCPs."""
    import scipy.sparse as sp

    from lcpbench.solvers import banded, solve_lcp
    from lcpbench.solvers.base import BoxQP, Settings

    rng = np.random.default_rng(3)
    for case in range(200):  # H symmetric, banded, diagonally dominant: positive definite
        n = int(rng.integers(2, 80))
        b = max(1, min(int(rng.choice([1, 2, 3, 4, 6, n - 1])), n - 1))
        A = rng.standard_normal((n, n))
        H = np.triu(np.tril(A + A.T, b), -b)
        np.fill_diagonal(H, np.abs(H).sum(axis=1) + 0.1)
        bands = np.zeros((b + 1, n))
        for k in range(b + 1):
            bands[k, :n - k] = np.diagonal(H, -k)
        lo = np.where(rng.random(n) < 0.3, -np.inf, -rng.random(n))
        hi = np.where(rng.random(n) < 0.3, np.inf, rng.random(n))
        qp = BoxQP(sp.csc_matrix(H), 3 * rng.standard_normal(n), lo, hi, bands)
        r = banded.solve_qp(qp, Settings("default", None))
        out[("active-set box QP", b if b <= 6 else "dense", case)] = dict(
            converged=str(r.status), reason=str(r.message), x=_bytes(r.x), y=_bytes(r.y),
            iterations=r.iterations)
    for case in range(100):
        n = int(rng.integers(2, 60))
        A = rng.standard_normal((n, n))
        sol = solve_lcp(A @ A.T + 0.1 * np.eye(n), rng.standard_normal(n),
                        solver="active-set")
        out[("active-set LCP", case)] = dict(converged=str(sol.status), z=_bytes(sol.z),
                                             iterations=getattr(sol, "iterations", None))


def _same(x: dict, y: dict) -> bool:
    """The same answer, bit for bit (NaN equal to NaN). The judge's numbers are compared
    where both records have them (records older than the field lack it)."""
    keys = x.keys() | y.keys()
    if "judge" not in x.keys() & y.keys():
        keys -= {"judge"}
    return all(f in x and f in y and (
        x[f] == y[f] or (isinstance(x[f], float) and isinstance(y[f], float)
                         and np.isnan(x[f]) and np.isnan(y[f]))) for f in keys)


def compare(a: dict, b: dict) -> int:
    """Print how the answers of ``b`` differ from ``a``'s; 0 where none moved."""
    counts: collections.Counter = collections.Counter()
    for key in sorted(set(a) | set(b), key=repr):
        x, y = a.get(key), b.get(key)
        group = key[0]
        if x is None or y is None:
            counts[(group, "only in one")] += 1
            print("only in one:", key)
        elif _same(x, y):
            counts[(group, "same bits")] += 1
        elif "error" in x or "error" in y or x.get("converged") != y.get("converged"):
            counts[(group, "VERDICT")] += 1
            print("verdict:", key, x.get("error", x.get("reason")), "->",
                  y.get("error", y.get("reason")))
        elif _same({**x, "judge": None}, {**y, "judge": None}):
            counts[(group, "judge's numbers moved")] += 1
            print("judge's numbers moved:", key)
        else:
            moved = abs(x.get("total_force", np.nan) - y.get("total_force", np.nan))
            # (NaN where neither was judged, or no force: a sensitivity; "moved")
            allowed = np.fmax(x.get("allowed", np.nan), y.get("allowed", np.nan))
            state = "within tau F0" if moved <= allowed else "moved"
            counts[(group, state)] += 1
            print(f"{state}:", key, x.get("total_force"), "->", y.get("total_force"))
    for k in sorted(counts):
        print(*k, counts[k], sep="\t")
    same = sum(v for (_, s), v in counts.items() if s == "same bits")
    print(f"{same} of {sum(counts.values())} answers the same bit for bit")
    return 0 if same == sum(counts.values()) else 1


def _same_tree_env() -> dict:
    """The environment of a child process that imports this process's lcpbench (an
    absolute ``PYTHONPATH``: a relative one, run from another directory, would reach
    the installed tree instead)."""
    here = str(Path(lcpbench.__file__).resolve().parent.parent)
    return {**os.environ, "PYTHONPATH": os.pathsep.join(
        [here, *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))])}


def sweep_rows(runs: Path) -> int:
    """Re-solve the default back-end's rows of the committed sweep; 0 where every
    total force is the stored one, bit for bit."""
    rows = [r for r in csv.DictReader(runs.open()) if r["backend"] == "active-set"]
    moved = same = 0
    for r in rows:
        if r["method"] != "globalised":
            continue
        d = json.loads(r["scene"])
        s = ActuatorScene(theta=d["theta"], height=d["height"], links=d["links"],
                          length=d["length"], EI=d["EI"], weight=d["weight"],
                          channel=d["channel"])
        F = float(lcpbench.solve(s, tol=float(r["tol"]), method="globalised",
                                 settings=r["settings"]).total_force)
        if F == float(r["total_force"]):
            same += 1
        else:
            moved += 1
            print("moved:", r["method"], r["settings"], d["theta"], d["height"], r["total_force"],
                  "->", F)
    line = sorted({r["method"] for r in rows} - {"globalised"})
    for method in line:  # the continuation rows: the sweep itself, into a temporary store
        predictor = method.split("+")[1]
        settings = sorted({r["settings"] for r in rows if r["method"] == method})
        with tempfile.TemporaryDirectory() as tmp:
            store = Path(tmp) / "store.sqlite"
            subprocess.run([sys.executable, "-m", "lcpbench.cli", "sweep", "--solvers", "active-set",
                            "--settings", ",".join(settings), "--continuation", predictor,
                            "--baseline", "none", "--store", str(store), "--no-report",
                            "--quiet", "--out", tmp], check=True, cwd=tmp,
                           capture_output=True, env=_same_tree_env())
            with sqlite3.connect(store) as con:
                got = {(sc, st, m): F for sc, st, m, F in con.execute(
                    "select scene, settings, method, total_force from runs "
                    "where backend = 'active-set'")}
        for r in rows:
            if r["method"] != method:
                continue
            F = got.get((r["scene"], r["settings"], method))
            if F is not None and float(F) == float(r["total_force"]):
                same += 1
            else:
                moved += 1
                print("moved:", method, r["settings"], r["theta"], r["height"],
                      r["total_force"], "->", F)
    print(f"{same} of {same + moved} default-back-end rows of {runs} the same bit for bit")
    return 0 if moved == 0 else 1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="what", required=True)
    sub.add_parser("record", help="record the corpus's answers").add_argument("out", type=Path)
    cmp_ = sub.add_parser("compare", help="compare two records")
    cmp_.add_argument("before", type=Path)
    cmp_.add_argument("after", type=Path)
    sw = sub.add_parser("sweep", help="the committed sweep's default-back-end rows")
    sw.add_argument("--runs", type=Path, default=RUNS)
    args = ap.parse_args(argv)
    if args.what == "record":
        out = corpus()
        with args.out.open("wb") as f:
            pickle.dump(out, f)
        print(f"{len(out)} answers ({sum(v.get('converged', False) for v in out.values())} "
              f"converged) -> {args.out}")
        return 0
    if args.what == "compare":
        return compare(*(pickle.loads(p.read_bytes()) for p in (args.before, args.after)))
    return sweep_rows(args.runs)


if __name__ == "__main__":
    raise SystemExit(main())
