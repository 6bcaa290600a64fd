"""PGS and PSOR on the formulations that allow them: predicted against measured rate (issue 37, item 5).

Near the answer, once the contact set is fixed, projected Gauss–Seidel is Gauss–Seidel
(or SOR with ω) on the block M_FF of the rows whose unknown is positive, so its
asymptotic rate is the spectral radius ρ of that iteration matrix,
(D + ωL)⁻¹((1 − ω)D − ωU) on M_FF (D, L, U its diagonal and triangles). For F1 (the
LCP in gaps) and F4 (the reactions' LCP), plain and Ruiz-equilibrated, at θ = 150°,
h = 3 mm: ρ from the exact answer's positive set, the rate PGS measures over its last
sweeps (``extra["rate"]`` of :func:`lcpbench.solvers.pgs.pgs`, 2000 sweeps), and the
sweeps ρ predicts for a 1e-9 reduction, log(1e-9)/log ρ. Then the accelerated projected
method, PGS with subspace minimisation (``pgs-sm``, Morales, Nocedal & Smelyanskiy 2008),
on the same LCPs at eps 1e-9: its cycles, PGS sweeps and subspace steps.

    python benchmarks/pgs_rate.py [--links 40,140] [--out results/formulations/pgs-rate]
        [--force]
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

for _k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_k] = "1"

import numpy as np  # noqa: E402

SWEEPS = 2000


def rho(M: np.ndarray, free: np.ndarray, omega: float) -> float:
    """Spectral radius of SOR(ω) on M[free, free]."""
    A = M[np.ix_(free, free)]
    D = np.diag(np.diag(A))
    L, U = np.tril(A, -1), np.triu(A, 1)
    B = np.linalg.solve(D + omega * L, (1 - omega) * D - omega * U)
    return float(np.max(np.abs(np.linalg.eigvals(B))))


def forms(step):
    """(name, M, q, positive set of the exact answer, the exact answer) of F1, F1r, F4,
    F4r (the active set's, mapped to each form's unknowns)."""
    from lcpbench.model.formulations import reaction_lcp
    from lcpbench.model.step_solver import solve_step, step_lcp
    from lcpbench.solvers.equilibrate import equilibrate_lcp

    exact = solve_step(step, "active-set", "high")
    form, M1, q1, dz, _ = step_lcp(step)
    g = (form.heights - exact.u[form.rows]) / dz[: form.n_gap]
    f4 = reaction_lcp(step)
    lam = exact.forces_upper[f4.nodes] / step.force_scale
    out = []
    for name, M, q, z in (("gaps", M1, q1, g), ("reactions", f4.M, f4.q, lam)):
        free = np.flatnonzero(z > 1e-12 * max(np.max(np.abs(z)), 1e-300))
        out.append((name, M, q, free, z))
        Ms, qs, D = equilibrate_lcp(M, q)
        out.append((name + "+ruiz", Ms, qs, free, z / D))  # D > 0: the same positive set
    return out


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--links", default="40,140")
    p.add_argument("--out", default="results/formulations/pgs-rate")
    p.add_argument("--force", action="store_true")
    a = p.parse_args(argv)

    import lcpbench
    from lcpbench import ActuatorScene
    from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
    from lcpbench.model.compiled_driver import assemble_step
    from lcpbench.solvers.base import PROFILES
    from lcpbench.solvers.pgs import pgs
    from lcpbench.solvers.pgs_sm import pgs_sm
    from lcpbench.solvers.runner import judge_lcp

    md = Path(a.out).with_suffix(".md")
    refuse_overwrite([md], a.force)
    start = timing_start()
    sm = ["| N | formulation | status | cycles | PGS sweeps | subspace steps | "
          "natural residual (lcpbench's) | max rel. error of z against the active set's |",
          "| ---: | --- | --- | ---: | ---: | ---: | ---: | ---: |"]
    rows = ["| N | formulation | ω | positive rows | ρ (predicted) | sweeps for 1e-9 by ρ | "
            "measured rate | status after 2000 sweeps |",
            "| ---: | --- | ---: | ---: | ---: | ---: | ---: | --- |"]
    for n in (int(x) for x in a.links.split(",")):
        scene = ActuatorScene(theta=150, height=3, links=n)
        res = lcpbench.solve(scene, settings="high", tol=1e-10)
        step = assemble_step(scene.chain(), np.asarray(res.alpha))
        for name, M, q, free, exact in forms(step):
            sol = judge_lcp(M, q, pgs_sm(M, q, eps=1e-9), PROFILES["high"])
            err = float(np.max(np.abs(sol.z - exact)) / max(np.max(np.abs(exact)), 1e-300))
            sm.append(f"| {n} | {name} | {sol.status.value} | {sol.iterations} | "
                      f"{sol.extra['sweeps']} | {sol.extra['subspace_steps']} | "
                      f"{sol.extra['residuals']['natural']:.1e} | {err:.1e} |")
            for omega in (1.0, 1.5):
                r = rho(M, free, omega)
                sol = pgs(M, q, omega=omega, eps=1e-14, max_sweeps=SWEEPS)
                need = np.log(1e-9) / np.log(r) if 0 < r < 1 else float("inf")
                rows.append(f"| {n} | {name} | {omega:g} | {free.size} | {r:.8f} | "
                            f"{need:.3g} | {sol.extra.get('rate', float('nan')):.8f} | "
                            f"{sol.status.value} |")
    text = ("# PGS and PSOR: the predicted rate against the measured one\n\n"
            f"Command: `{command_line('pgs_rate.py', argv)}`. θ = 150°, "
            "h = 3 mm, the step at its answer. ρ: spectral radius of SOR(ω) on the block "
            "of the rows positive at the exact answer (Gauss–Seidel at ω = 1); measured: "
            "the residual's mean contraction per sweep over PGS's last sweeps.\n\n"
            + "\n".join(rows) + "\n\n"
            "Reading: Ruiz's symmetric scaling leaves Gauss–Seidel's spectral radius "
            "unchanged (DMD's iteration is similar to M's). At N = 40 the measured rate of "
            "PSOR on F1 matches ρ to 4 digits; at N = 140 the 2000 sweeps are not yet in "
            "the asymptotic phase (the positive set still changes). In F4 few rows are positive "
            "(the contact nodes) but their compliances are nearly equal, so even a 3 x 3 "
            "block has ρ within 3e-4 of 1. PGS needs 10^5-10^6 sweeps for 1e-9 at N = 140 "
            "in every form: no formulation makes plain projected iteration viable.\n\n"
            "## PGS with subspace minimisation (pgs-sm) on the same LCPs\n\n"
            "Two PGS sweeps per cycle pick the active set, a reduced Newton step on the "
            "free rows with a projected search finishes it (docs/formulations.md); eps "
            "1e-9 on lcpbench's natural residual. Error: max |z − z*| / max |z*| against "
            "the active set's answer (gaps in F1, reactions in F4: cond K · ε ≈ 1e-8 is "
            "the agreement of two exact methods here).\n\n"
            + "\n".join(sm) + f"\n\nMachine: {timing_note(start)}\n")
    md.parent.mkdir(parents=True, exist_ok=True)
    md.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
