"""Issue 39, target 2: why do Lemke's answers of the frictional step, with a natural
residual far below 1e-8, sit 1e-6 … 1e-4 (in N) from the exact solution on their own
index set? The problem's conditioning, or round-off, and whose?

Each state of benchmarks/friction_agreement.py's 100 paths (seed 39) whose last step the
default (``StepLemke``: the warm start, else Lemke's pivots) answers but the exact oracle
(benchmarks/exact_friction.py) does not confirm, though the answer's index set has an
exact solution; and, over every state, where the answers came from (the warm start or
Lemke's pivots) and whether a fresh Lemke (no support) is confirmed on the unconfirmed
ones. On that index set:

- **gap**: Lemke's answer to the exact solution: N (relative to the largest force) and
  the move (in link lengths a);
- **null directions fitted to N**: the gap with the exact null directions (T per node in
  a stick run) fitted to the answer's N and move alone (T weighted 1e-6): whether N is
  free along them;
- **data ulp**: how far the exact solution moves in N when the step's doubles
  (``FrictionStep.parts``: H's bands, f, tan α, gaps, slips) move by one rounding each
  (relative 2⁻⁵³, random signs; the largest of 3 draws), and **tan α as is**: Lemke's
  distance to the exact solution with the step's own tiny slopes (exact_friction
  levels |tan α| <= 1e-12 links; here LEVEL = 0);
- **the LCP's M_SS** on the same set (S: N on contact rows, β± by T's sign on sticking
  pairs, β∓ and λ on sliding ones): its condition number; M_SS z_S = −q_S solved in
  doubles (LU) with one step of iterative refinement (residual in long double), exactly
  in Fractions from its doubles (up to 20 unknowns; nan where singular), and by
  the warm start's compiled dense factor (``pivoting_kernel.support_pivots``, one
  support, its least-squares fallback), each to the exact solution;
- **the primal equations** on the same set (exact_friction's, in doubles: the heights'
  equilibrium, the x recurrences, the links' horizontal forces and one equation per row
  and pair): their condition number without the exact null directions (T per node
  along a stick run), raw and with rows and columns equilibrated, and their
  equilibrated minimum-norm least-squares solution (SVD, rcond 1e-14) to the exact one;
- **the polish** (``friction_lemke.polish_step``, compiled, banded, O(N): what every
  frictional step's answer now leaves through): its verdict on the answer and the
  polished answer's distance to the exact solution in N.

Every column but the polish's is of the answer before the polish
(``sol.extra["unpolished"]`` where the polish replaced it); the tally counts how many of
the default's answers the exact oracle confirms before and after the polish.

    python benchmarks/friction_polish_probe.py [--out results/friction/polish_probe.md]
        [--force]
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import sys
import time
from dataclasses import replace
from datetime import datetime, timezone
from fractions import Fraction
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.model.friction_lemke import (
    WARM_FEAS_RTOL,
    WARM_PIVOT_RTOL,
    WARM_RCOND,
    StepLemke,
    pivoting_kernels,
)
from lcpbench.model.friction_solvers import judged
from lcpbench.solvers.base import lcp_residuals

sys.path.insert(0, str(Path(__file__).parent))
import exact_friction as ef  # noqa: E402
from friction_agreement import Recorder, scenes  # noqa: E402


def lcp_support(fs, ex, xs, step) -> np.ndarray:
    """The LCP's support S (bool per z) of an exact index set."""
    mn, mt = fs.normal_node.size, fs.friction_node.size
    S = np.zeros(mn + 3 * mt, bool)
    S[:mn] = np.array(ex.rows, bool)
    for c, st in enumerate(ex.pairs):
        if st is ef.OFF:
            continue
        if st == ef.STICK:
            S[mn + c if xs[step.tangential[c]] >= 0 else mn + mt + c] = True
        else:  # forward: T = −μN (β⁻), λ = s; backward: β⁺
            S[(mn + mt + c) if st == ef.FORWARD else (mn + c)] = True
            S[mn + 2 * mt + c] = True
    return S


def primal_system(step, rows, pairs):
    """The index set's primal equations (exact_friction.solve's) in doubles: (A, b)."""
    eqs = list(step.mechanics)
    for r, contact in enumerate(rows):
        eqs.append((step.gap[r][1], -step.gap[r][0]) if contact else ({step.normal[r]: 1}, 0))
    for c, st in enumerate(pairs):
        Tc = step.tangential[c]
        if st is ef.OFF:
            eqs.append(({Tc: 1}, 0))
        elif st == ef.STICK:
            eqs.append((step.slip[c][1], -step.slip[c][0]))
        else:
            d = {Tc: 1}
            for r in range(len(rows)):
                if step.pair[r] == c:
                    d[step.normal[r]] = d.get(step.normal[r], 0) + st * step.mu[r]
            eqs.append((d, 0))
    A = np.zeros((len(eqs), step.n))
    b = np.array([float(r) for _, r in eqs])
    for i, (d, _) in enumerate(eqs):
        for k, v in d.items():
            A[i, k] = float(v)
    return A, b


#: the largest M_SS solved exactly from its rounded entries (dense Fraction elimination)
EXACT_MSS_MAX = 20


def exact_dense(A, b) -> np.ndarray | None:
    """x with A x = b in :class:`fractions.Fraction` from A's and b's doubles (None when
    A is singular exactly)."""
    n = b.size
    R = [[Fraction(float(v)) for v in A[i]] + [Fraction(float(b[i]))] for i in range(n)]
    for c in range(n):
        p = next((i for i in range(c, n) if R[i][c] != 0), None)
        if p is None:
            return None
        R[c], R[p] = R[p], R[c]
        for i in range(c + 1, n):
            if R[i][c] != 0:
                f = R[i][c] / R[c][c]
                R[i] = [a - f * bb for a, bb in zip(R[i], R[c])]
    x = [Fraction(0)] * n
    for i in range(n - 1, -1, -1):
        x[i] = (R[i][n] - sum(R[i][j] * x[j] for j in range(i + 1, n))) / R[i][i]
    return np.array([float(v) for v in x])


def dN(step, x, xs, scale):
    return float(np.max(np.abs(x[step.normal] - xs[step.normal]))) / scale


def origin(fs, sol, step, ex, dist, tally: dict) -> None:
    """Count where an answer came from (the warm start, or Lemke's pivots) and, for an
    unconfirmed warm answer, whether Lemke from scratch (no support) is confirmed."""
    warm = "start" in sol.extra
    ok = ef.confirmed(ex, dist)
    key = ("warm start" if warm else "Lemke's pivots") + (", confirmed" if ok else
                                                           ", not confirmed")
    tally[key] = tally.get(key, 0) + 1
    if ok:
        return
    cold = judged(fs, StepLemke()(fs))
    if not cold.solved:
        key = "from scratch: not SOLVED"
    else:
        vc = ef.answer_values(fs, step, cold.extra.get("unpolished", cold.z))
        exc, dc, _ = ef.nearest_exact(step, vc)
        key = "from scratch: " + ("confirmed" if ef.confirmed(exc, dc) else "not confirmed")
    tally[key] = tally.get(key, 0) + 1


def probe(fs, sol, rng, tally) -> dict | None:
    step = ef.chain_step(fs)
    polished = sol.z
    v1 = ef.answer_values(fs, step, polished)
    ex1, dist1, _ = ef.nearest_exact(step, v1)
    key = "after the polish: " + ("confirmed" if ef.confirmed(ex1, dist1) else "not confirmed")
    tally[key] = tally.get(key, 0) + 1
    verdict = sol.extra.get("polish", "")
    tally["polish " + verdict] = tally.get("polish " + verdict, 0) + 1
    sol = replace(sol, z=sol.extra.get("unpolished", sol.z))
    v0 = ef.answer_values(fs, step, sol.z)
    ex, dist, _ = ef.nearest_exact(step, v0)
    origin(fs, sol, step, ex, dist, tally)
    if ef.confirmed(ex, dist) or not ex.solution:
        return None
    xs = np.array([float(v) for v in ex.x])
    scale = max(float(np.max(np.abs(v0[step.normal + step.tangential]))), 1e-300)
    out = {"gap": dist[0], "move": dist[2], "free": ex.free, "size": step.n,
           "residual": (sol.extra.get("unpolished_residuals") or sol.extra.get("residuals")
                        or {}).get("natural", np.nan)}
    # the null directions fitted to N and the move alone (T weighted 1e-6): is N free?
    en = ef.solve(step, ex.rows, ex.pairs, v0, fit_t=1e-6)
    out["fit_n"] = ef.distance(step, en, v0, scale)[0]
    ulp = 0.0
    for _ in range(3):  # one rounding of the step's doubles
        P = dict(fs.parts)
        for key in ("bands", "f", "tan", "gap", "slip"):
            a = np.asarray(P[key], float)
            P[key] = a * (1 + 2.0 ** -53 * rng.choice([-1.0, 1.0], a.shape))
        e2 = ef.solve(ef.chain_step(replace(fs, parts=P)), ex.rows, ex.pairs, xs)
        ulp = max(ulp, dN(step, np.array([float(v) for v in e2.x]), xs, scale))
    out["ulp"] = ulp
    level, ef.LEVEL = ef.LEVEL, 0.0  # the step's own tiny slopes
    try:
        st0 = ef.chain_step(fs)
        va = ef.answer_values(fs, st0, sol.z)
        e0 = ef.solve(st0, ex.rows, ex.pairs, va)
        out["as_is"] = ef.distance(st0, e0, va, scale)[0] if e0.solution else np.nan
    finally:
        ef.LEVEL = level
    S = lcp_support(fs, ex, xs, step)
    MS, qS = fs.M[np.ix_(S, S)], -fs.q[S]
    out["cond_mss"] = float(np.linalg.cond(MS))
    z = np.zeros(fs.q.size)
    try:
        x = np.linalg.solve(MS, qS)
        r = qS.astype(np.longdouble) - MS.astype(np.longdouble) @ x.astype(np.longdouble)
        z[S] = x + np.linalg.solve(MS, r.astype(float))
    except np.linalg.LinAlgError:
        z[S] = np.nan
    out["mss_refined"] = dN(step, ef.answer_values(fs, step, z), xs, scale)
    zx = exact_dense(MS, qS) if S.sum() <= EXACT_MSS_MAX else None
    z[:] = 0.0
    if zx is not None:
        z[S] = zx
    out["mss_exact"] = (dN(step, ef.answer_values(fs, step, z), xs, scale) if zx is not None
                        else np.nan)
    k = pivoting_kernels()
    zz, _, _, end, _ = k.support_pivots(np.ascontiguousarray(fs.M), fs.q, S, 1, WARM_FEAS_RTOL,
                                        WARM_PIVOT_RTOL, WARM_RCOND)
    out["mss_compiled"] = dN(step, ef.answer_values(fs, step, zz), xs, scale)
    # the polish as an LCP back-end would do it: kept only where the candidate is feasible
    # (DONE) and its natural residual is below Lemke's
    res = lcp_residuals(fs.M, fs.q, zz)["natural"]
    out["kept"] = bool(end == k.DONE and res < out["residual"])
    A, b = primal_system(step, ex.rows, ex.pairs)
    sv = np.linalg.svd(A, compute_uv=False)
    out["cond_primal"] = sv[0] / sv[-1 - ex.free]
    rs = 1 / np.maximum(np.abs(A).max(axis=1), 1e-300)
    As = A * rs[:, None]
    cs = 1 / np.maximum(np.abs(As).max(axis=0), 1e-300)
    As = As * cs[None, :]
    sv = np.linalg.svd(As, compute_uv=False)
    out["cond_equil"] = sv[0] / sv[-1 - ex.free]
    xp = np.linalg.lstsq(As, b * rs, rcond=1e-14)[0] * cs
    out["primal"] = dN(step, xp, xs, scale)
    out["polished"] = dN(step, v1, xs, scale)
    out["verdict"] = verdict
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/friction/polish_probe.md")
    ap.add_argument("--force", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    refuse_overwrite([out], args.force)
    cmd = command_line("friction_polish_probe.py", argv)
    start = timing_start()
    t0 = time.perf_counter()
    rng = np.random.default_rng(1)
    cols = ("gap", "move", "fit_n", "ulp", "as_is", "cond_mss", "mss_refined", "mss_exact",
            "mss_compiled",
            "cond_primal", "cond_equil", "primal", "residual", "polished", "kept")
    rows, tally = [], {}
    for index, (scene, states) in enumerate(scenes(100, 39)):
        rec = Recorder()
        ref = lcpbench.solve_path(scene, states, tol=1e-8, lcp=rec)
        ends = np.cumsum([r.outer_iterations if r.route == "frictional" else 0 for r in ref])
        for si, (r, end) in enumerate(zip(ref, ends)):
            if not r.converged or r.route != "frictional":
                continue
            got = probe(*rec.steps[end - 1], rng, tally)
            if got is not None:
                rows.append((f"{index}.{si}", scene.links, got))
                print(rows[-1][0], scene.links, " ".join(f"{got[c]:.1e}" for c in cols[:-1]),
                      got["kept"], got["verdict"], flush=True)
    lines = [
        "# Lemke's unconfirmed answers: conditioning or round-off? (issue 39, target 2)", "",
        f"{datetime.now(timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}; "
        f"`{cmd}`; {timing_note(start)} "
        f"({time.perf_counter() - t0:.0f} s).", "",
        "The states of `benchmarks/friction_agreement.py`'s 100 paths whose last step Lemke "
        "(the default, `StepLemke`) answers but the exact oracle does not confirm, where its index set has an exact "
        "solution (the module's docstring says what each column is). N columns: the "
        "largest difference in N to the exact solution on Lemke's index set, relative to "
        "the largest force; move in link lengths.", "",
        "| step | links | gap N | gap move | gap N, null directions fitted to N "
        "| data ulp: exact N moves | tan α as is: gap N "
        "| cond M_SS | M_SS, LU + refinement | M_SS exactly from its doubles "
        "| M_SS, compiled factor | cond primal "
        "| cond primal, equilibrated | primal, equilibrated lstsq | Lemke's residual "
        "| the polish: gap N | compiled M_SS kept (feasible, residual below Lemke's) "
        "| the polish's verdict |",
        "|---|---|" + "---|" * (len(cols) + 1)]
    for name, links, g in rows:
        lines.append(f"| {name} | {links} | " + " | ".join(f"{g[c]:.1e}" for c in cols[:-1])
                     + f" | {'yes' if g['kept'] else 'no'} | {g['verdict']} |")
    arr = {c: np.array([g[c] for _, _, g in rows]) for c in cols}
    if rows:
        lines += ["", f"{len(rows)} steps. Median gap N {np.median(arr['gap']):.1e} (max "
                  f"{arr['gap'].max():.1e}); exact N under one rounding of the data: max "
                  f"{arr['ulp'].max():.1e}; M_SS solved in doubles with refinement within 1e-8 "
                  f"on "
                  f"{int(np.sum(arr['mss_refined'] <= 1e-8))} (nan: M_SS singular in doubles "
                  f"on {int(np.sum(np.isnan(arr['mss_refined'])))}); solved exactly from its "
                  f"rounded entries (up to {EXACT_MSS_MAX} unknowns) within 1e-8 on "
                  f"{int(np.sum(arr['mss_exact'] <= 1e-8))} of "
                  f"{int(np.sum(np.isfinite(arr['mss_exact'])))}; by the compiled factor within "
                  f"1e-8 on {int(np.sum(arr['mss_compiled'] <= 1e-8))}, kept by the polish's "
                  f"rule on {int(np.sum(arr['kept']))}; the equilibrated primal "
                  f"least squares: median {np.median(arr['primal']):.1e} (max "
                  f"{arr['primal'].max():.1e}), within 1e-8 on "
                  f"{int(np.sum(arr['primal'] <= 1e-8))}; the polish (banded, in the library): "
                  f"median {np.median(arr['polished']):.1e} (max {arr['polished'].max():.1e}), "
                  f"within 1e-8 on {int(np.sum(arr['polished'] <= 1e-8))}."]
    lines += ["", "Where the default's answers come from (the last step of each state its path "
              "converges, the 100 paths): " + "; ".join(f"{k} {v}" for k, v in tally.items())
              + " (the unconfirmed answers' steps solved again by a fresh StepLemke, no "
              "support: Lemke's pivots alone)."]
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
