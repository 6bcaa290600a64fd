"""Issue 39, target 2: the back-ends of the frictional step agree where each answers.

Random frictional scenes and paths (seed 39: θ 100-170°, h 1-5 mm, N from 12 to 140,
μ 0.05-1, 40 % channels; ends pin–slider, slider–slider, slider–pin, and in channels
pin–free and slider–free; the path {}, θ + 10°, a pull of 0-150 mN where the right end
is not pinned, a release). Two comparisons, each against Lemke (``lemke``, the
reference; relative to the largest force of the state, max(N, |T|, |P|)):

- **on the same step**: the last contact step of every state Lemke's path converges,
  handed to each back-end (:func:`lcpbench.model.friction_solvers.step_runner`); it
  answers when its status is SOLVED (lcpbench's natural residual of the step's LCP
  <= 1e-8, and the back-end's own test);
- **along its own path**: ``lcpbench.solve_path(scene, states, solver=NAME)``; it answers
  a state when the judge calls it converged. Every converged state is also checked
  outside the judge: Coulomb node by node and Σ T + P = 0
  (``friction_paths.breaks_coulomb``).

Forces compared: N per node (both walls); T summed over each run of consecutive nodes
in contact or at a wall (gap <= 1e-3 a, the nodes with a friction pair: "T per run"),
and T per node. In a run of nodes that stick to a flat wall
the chain cannot tell its T apart (the Delassus matrix is singular there), so T per
node is statically indeterminate and only its sum over the run is an answer; T per
node is reported, not judged.

    python benchmarks/friction_agreement.py [--paths 100] [--seed 39] [--tol 1e-8]
        [--out results/friction/agreement.md] [--force]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.model.friction_driver import NEAR
from lcpbench.model.friction_solvers import step_runner
from lcpbench.model.judge import NODE_SHARE as JUDGE_SHARE
from lcpbench.model.judge import force_tol
from lcpbench.solvers.registry import backends

sys.path.insert(0, str(Path(__file__).parent))
import exact_friction as ef  # noqa: E402
from friction_paths import ENDS, breaks_coulomb  # noqa: E402

#: the contenders: Lemke (the reference), the active set, Siconos' fc2d Lemke (the
#: peer) and the Tresca fixed point on two QP back-ends
SOLVERS = ("lemke", "active-set", "siconos-lemke", "proxsuite-dense", "qpsolvers-piqp")
TARGET = 1e-6


def scenes(count: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        channel = bool(rng.random() < 0.4)
        ends = ENDS[rng.integers(5 if channel else 3)]
        theta = float(rng.uniform(100, 170))
        scene = ActuatorScene(theta=theta, height=float(rng.uniform(1.0, 5.0)),
                              links=int(rng.choice([12, 20, 40, 80, 140])), channel=channel,
                              left_end=ends[0], right_end=ends[1],
                              friction=float(rng.uniform(0.05, 1.0)))
        pull = float(rng.uniform(0.0, 0.15)) if ends[1] != "pinned" else 0.0
        yield scene, [{}, {"theta": theta + 10}, {"pull": pull}, {"pull": 0.0}]


def on_wall(res) -> np.ndarray:
    """Free nodes at a wall: gap <= NEAR · a, the nodes the step gives a friction pair
    (a link between two of them is level with the wall to 1e-3 rad: a horizontal force
    moves between them at the cost of a moment arm <= 1e-3 a, which the step's
    residual does not see)."""
    s = res.scene
    a = s.length / res.links
    y = res.y[1:1 + res.forces.size]
    gap = s.height - y
    if s.channel:
        gap = np.minimum(gap, y + s.height)
    return gap <= NEAR * a


def runs(contact: np.ndarray) -> list[np.ndarray]:
    """Maximal runs of consecutive nodes in contact or on a wall."""
    idx = np.flatnonzero(contact)
    return np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []


def differences(N1, T1, N2, T2, contact, scale) -> tuple[float, float, float]:
    """(N per node, T per run, T per node), relative to ``scale``."""
    dn = float(np.max(np.abs(N1 - N2), initial=0.0))
    dr = max((abs(float(T1[r].sum() - T2[r].sum())) for r in runs(contact)), default=0.0)
    dt = float(np.max(np.abs(T1 - T2), initial=0.0))
    return dn / scale, dr / scale, dt / scale


def step_forces(fs, z, n_free, first):
    """N (both walls, per free node), T per free node, and the step's move (δy, τ) in mm
    of a step's answer z."""
    N, T, dy, tau = fs.forces(z)
    Nn, Tn = np.zeros(n_free), np.zeros(n_free)
    np.add.at(Nn, fs.normal_node, N)
    Tn[fs.friction_node - first] = T
    return Nn, Tn, np.append(dy, tau)


class Recorder:
    """Lemke's step solver, keeping every step it is handed (and, as the default path's,
    polishing only the answer that would end a state: the polished one is kept)."""

    takes_step = True
    newton = True  # as the default path's (step_runner("lemke").newton)
    defers_polish = True

    def __init__(self):
        self.run = step_runner("lemke")
        self.steps = []

    def __call__(self, fs, polish=True):
        sol = self.run(fs, polish=polish)
        self.steps.append((fs, sol))
        return sol

    def polish(self, fs, sol, *flips):
        out = self.run.polish(fs, sol, *flips)
        if self.steps and self.steps[-1][1] is sol:
            self.steps[-1] = (fs, out)
        return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=100)
    ap.add_argument("--seed", type=int, default=39)
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--out", default="results/friction/agreement.md")
    ap.add_argument("--force", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    refuse_overwrite([out], args.force)
    cmd = command_line("friction_agreement.py", argv)
    start = timing_start()
    solvers = [s for s in SOLVERS if backends()[s].available()]
    missing = [s for s in SOLVERS if s not in solvers]
    z = {s: {"steps": 0, "answered": 0, "dn": 0.0, "dr": 0.0, "dt": 0.0, "time": 0.0,
             "agree": 0, "dm": 0.0} for s in solvers}
    p = {s: {"states": 0, "converged": 0, "both": 0, "dn": 0.0, "dr": 0.0, "dt": 0.0,
             "broken": 0, "broken_judge": 0, "time": 0.0, "agree": 0, "dm": 0.0,
             "both_clean": 0, "agree_clean": 0}
         for s in solvers}
    worst = {s: (0.0, "") for s in solvers}  # the largest ΔN on the same step, and where
    # the disagreements on the same step by class (exact_friction.classify), and where
    classes = {s: {} for s in solvers}
    lemke_exact = {"steps": 0, "confirmed": 0, "worst": 0.0, "ray": 0, "missed": []}
    t_all = time.perf_counter()
    for index, (scene, states) in enumerate(scenes(args.paths, args.seed)):
        rec = Recorder()
        t0 = time.perf_counter()
        ref = lcpbench.solve_path(scene, states, tol=args.tol, lcp=rec)
        p["lemke"]["time"] += time.perf_counter() - t0
        chain_first = int(scene.chain().free_nodes[0]) if scene.right_end != "free" else 1
        # the last step of each converged state, by the outer steps each state took
        ends = np.cumsum([r.outer_iterations if r.route == "frictional" else 0 for r in ref])
        for si, (r, end) in enumerate(zip(ref, ends)):
            if not r.converged or r.route != "frictional":
                continue
            fs, sol = rec.steps[end - 1]
            n_free = r.forces.size
            N0, T0, m0 = step_forces(fs, sol.z, n_free, chain_first)
            a = scene.length / scene.links
            scale = max(float(N0.max(initial=0.0)), float(np.abs(T0).max(initial=0.0)),
                        abs(r.pull), 1e-300)
            where = f"{index}.{si}"
            primal = ef.chain_step(fs)  # the step in exact arithmetic (exact_friction.py)
            v0 = ef.answer_values(fs, primal, sol.z)
            mine = ef.nearest_exact(primal, v0)
            lemke_exact["steps"] += 1
            if ef.confirmed(mine[0], mine[1]):
                lemke_exact["confirmed"] += 1
                lemke_exact["worst"] = max(lemke_exact["worst"], mine[1][0], mine[1][2])
            else:
                lemke_exact["missed"].append(where)
            lemke_exact["ray"] += mine[0].ray
            for s in solvers:
                z[s]["steps"] += 1
                t0 = time.perf_counter()
                other = sol if s == "lemke" else step_runner(s)(fs)
                z[s]["time"] += time.perf_counter() - t0
                if not other.solved:
                    continue
                z[s]["answered"] += 1
                N1, T1, m1 = step_forces(fs, other.z, n_free, chain_first)
                z[s]["dm"] = max(z[s]["dm"], float(np.max(np.abs(m1 - m0))) / a)
                d = differences(N0, T0, N1, T1, (N0 > 0) | (N1 > 0) | on_wall(r), scale)
                z[s]["agree"] += max(d[0], d[1]) <= TARGET
                if max(d[0], d[1]) > TARGET:
                    kind, info = ef.classify(primal, v0,
                                             ef.answer_values(fs, primal, other.z), a=mine)
                    mark = ("L" if info.get("which") == "a" else "") + (
                        "*" if info.get("exact_there") else "")
                    classes[s].setdefault(kind, []).append(where + mark)
                if d[0] > worst[s][0]:
                    worst[s] = (d[0], f"path {index} state {si} "
                                      f"(N = {scene.links}, μ = {scene.friction:.2f}, "
                                      f"{scene.left_end}–{scene.right_end}"
                                      f"{', channel' if scene.channel else ''})")
                for k, v in zip(("dn", "dr", "dt"), d):
                    z[s][k] = max(z[s][k], v)
        for s in solvers:
            if s == "lemke":
                mine = ref
            else:
                t0 = time.perf_counter()
                mine = lcpbench.solve_path(scene, states, tol=args.tol, solver=s)
                p[s]["time"] += time.perf_counter() - t0
            clean = True  # every previous state of this path converged by both and agreed
            for a, b in zip(ref, mine):
                p[s]["states"] += 1
                if not b.converged:
                    clean = False
                    continue
                p[s]["converged"] += 1
                p[s]["broken"] += breaks_coulomb(b)
                p[s]["broken_judge"] += breaks_coulomb(b, rtol=JUDGE_SHARE * force_tol(args.tol))
                if not a.converged:
                    clean = False
                    continue
                p[s]["both"] += 1
                a_len = scene.length / scene.links
                p[s]["dm"] = max(p[s]["dm"], float(max(np.abs(b.x - a.x).max(),
                                                       np.abs(b.y - a.y).max())) / a_len)
                lo_a = a.forces_lower if a.forces_lower is not None else 0.0
                lo_b = b.forces_lower if b.forces_lower is not None else 0.0
                Na, Nb = a.forces + lo_a, b.forces + lo_b
                scale = max(float(Na.max(initial=0.0)),
                            float(np.abs(a.tangential_forces).max(initial=0.0)), abs(a.pull),
                            1e-300)
                d = differences(Na, a.tangential_forces, Nb, b.tangential_forces,
                                (Na > 0) | (Nb > 0) | on_wall(a) | on_wall(b), scale)
                ok = max(d[0], d[1]) <= TARGET
                p[s]["agree"] += ok
                if clean:
                    p[s]["both_clean"] += 1
                    p[s]["agree_clean"] += ok
                clean &= ok
                for k, v in zip(("dn", "dr", "dt"), d):
                    p[s][k] = max(p[s][k], v)
    total = time.perf_counter() - t_all
    note = timing_note(start)
    lines = [
        "# The frictional step's back-ends agree (issue 39, target 2)", "",
        f"{datetime.now(timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}; `{cmd}`; {note} "
        f"({total:.0f} s in all).", "",
        f"{args.paths} random frictional scenes and paths of 4 states (seed {args.seed}, "
        f"N 12-140, μ 0.05-1, tol {args.tol:g}; `benchmarks/friction_agreement.py` says "
        "how they are drawn). Lemke is the reference. Force differences are relative to "
        "the largest force of the state; target 1e-6 in N per node and in T per run "
        "(consecutive nodes within 1e-3 a of a wall, the nodes with a friction pair). T "
        "per node is reported, not judged: between nodes of a run, and between runs "
        "joined by a straight stretch of chain, a horizontal force moves without moving "
        "the chain (an inextensible straight bar carries it; W is singular there), so "
        "it is statically indeterminate. What the forces do to the chain is: the step's "
        "move (δy, τ), and along a path the shape (x, y), in link lengths a.", "",
        "## On the same step", "",
        "The last contact step of each state Lemke's path converges, handed to each "
        "back-end. Answers: its status SOLVED (lcpbench's natural residual of the "
        "step's LCP <= 1e-8).", "",
        "| back-end | form | steps | answered | agree to 1e-6 | max ΔN | max ΔT per run "
        "| max ΔT per node | max Δ move (a) | time (s) |",
        "|---|---|---|---|---|---|---|---|---|---|"]
    for s in solvers:
        r = z[s]
        lines.append(f"| {s} | {backends()[s].friction_form} | {r['steps']} | "
                     f"{r['answered']} | {r['agree']} | {r['dn']:.1e} | {r['dr']:.1e} | "
                     f"{r['dt']:.1e} | {r['dm']:.1e} | {r['time']:.1f} |")
    lines += ["", "The largest ΔN on the same step, where: " + "; ".join(
        f"{s} {worst[s][0]:.1e}, {worst[s][1]}" for s in solvers if worst[s][1]) + "."]
    kinds = (ef.MULTIPLE, ef.INACCURATE, ef.RAY, ef.SAME)
    lines += ["", "## The disagreements on the same step, solved exactly", "",
              "Each step where a back-end answers and differs from Lemke by more than "
              "1e-6 (N per node or T per run) is solved exactly "
              "(`benchmarks/exact_friction.py`: the step's primal equations from its "
              "doubles, in `fractions.Fraction`) on the index set read from each answer "
              "(per wall row contact or separate, per friction pair stick, slide forward "
              "or backward; nodes that the answer leaves at the edge of two states, to "
              "its round-off, flipped where the first reading breaks a sign condition, "
              "then every state of up to 6 such nodes tried, `edge_search`), "
              "and every complementarity and sign condition is checked exactly. An answer "
              "is confirmed when that exact solution exists and is within 1e-6 of it in "
              "N and in the move (T per node is ill-conditioned along a nearly straight "
              "stretch and is not judged). Classes: (i) both answers confirmed, their "
              "exact solutions 1e-6 apart: the step has two answers and no solver can "
              "be required to agree; (ii) an answer not confirmed; (iii) an index set "
              "whose exact null space moves the chain (a ray of answers: every null "
              "direction is computed exactly); (iv) both confirmed as the same exact "
              "answer in N and the move, each within 1e-6 of it (apart by the sum of "
              "their roundings, or in T along a near-null direction; docs/friction.md, "
              "'State 41.2 taken apart'). Steps are named "
              "path.state; in (ii), L marks a step where Lemke's answer is the one not "
              "confirmed, and * one where that answer's index set has an exact solution, "
              "farther from it than 1e-6 (the others: none found on the sets read from "
              "it).", "",
              "| back-end | disagreements | " + " | ".join(kinds) + " |",
              "|---|---|" + "---|" * len(kinds)]
    for s in solvers:
        if s == "lemke":
            continue
        c = classes[s]
        lines.append(f"| {s} | {sum(len(v) for v in c.values())} | " + " | ".join(
            f"{len(c.get(k, []))}" + (f": {' '.join(c[k])}" if c.get(k) else "")
            for k in kinds) + " |")
    le = lemke_exact
    lines += ["", f"Lemke's own answers (every step, agreeing or not): {le['confirmed']} of "
              f"{le['steps']} confirmed by the exact solution on their index set (largest "
              f"distance in N and the move {le['worst']:.1e}); {le['ray']} with a ray"
              + (f"; not confirmed: {' '.join(le['missed'])}" if le["missed"] else "")
              + "."]
    lines += ["", "## Along its own path", "",
              "Each back-end's own path (each state from its own last). Converged: the "
              "judge's verdict. Broken: converged states that break Coulomb's law node by "
              "node or Σ T + P = 0, checked outside the judge (target 0), to 1e-9 of the "
              "largest force (`friction_paths.breaks_coulomb`) and to the judge's own "
              f"ε_F = {JUDGE_SHARE:g} · force_tol(tol) of it. ΔN, ΔT over the "
              "states both Lemke and the back-end converge. After a state with two "
              "answers the paths may part legitimately (each goes on from its own "
              "answer), so the states are also counted only while every earlier state "
              "of the path was converged by both and agreed ('all before agreed').", "",
              "| back-end | states | converged | broken at 1e-9 | broken at the judge's ε "
              "| both | agree to 1e-6 | both, all before agreed | agree | max ΔN "
              "| max ΔT per run | max ΔT per node | max Δ shape (a) | time (s) |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in solvers:
        r = p[s]
        lines.append(f"| {s} | {r['states']} | {r['converged']} | {r['broken']} | "
                     f"{r['broken_judge']} | "
                     f"{r['both']} | {r['agree']} | {r['both_clean']} | "
                     f"{r['agree_clean']} | {r['dn']:.1e} | {r['dr']:.1e} | "
                     f"{r['dt']:.1e} | {r['dm']:.1e} | {r['time']:.1f} |")
    if missing:
        lines += ["", f"Not installed here: {', '.join(missing)}."]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    broken = sum(p[s]["broken"] for s in solvers)
    return 0 if broken == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
