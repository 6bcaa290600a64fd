"""Issue 38, target 3: fitting EI to synthetic force-pressure data with 5 % noise.

Each of ``--trials`` trials draws m in [8, 15] pressures uniformly over the
calibration of actuator 1 between θ = 90° and its largest pressure, computes the
total force of the paper's actuator (N = 140, h = 4 mm, ℓ = 30 mm, w = 0.245 N/m)
with the true EI = 40 N mm² by a forward solve (tol 1e-10), multiplies each by
1 + 0.05 z (z standard normal, numpy's default_rng(seed)), and fits EI from the
paper's 32.01 N mm² by ``lcpbench.studies.fit.fit`` (the calibration fixed). Reports
the share of fits within 2 % of the true EI, the median error, and how often the 95 %
interval covers the truth. For each trial it also computes the Cramér–Rao bound: the
smallest standard deviation s of any unbiased estimate of EI from that trial's
pressures, s⁻² = Σᵢ gᵢ² (1/0.05² + 2), gᵢ = ∂ln Fᵢ/∂ln EI from
``lcpbench.sensitivities`` at the true EI (the 2 is the information the noise's
scale, 0.05 Fᵢ, carries); an efficient estimator is within 2 % with probability
erf(0.02 / (s√2)), and the report gives its mean over the trials. Writes ``results/fit-ei.md`` (``--out``; not overwritten
without ``--force``).

    python benchmarks/fit_ei.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.special import erf

import lcpbench
from lcpbench import ActuatorScene
from lcpbench.bench.machine import command_line, refuse_overwrite
from lcpbench.problems.calibrations import get_calibration
from lcpbench.studies.fit import fit

ROOT = Path(__file__).resolve().parents[1]
EI_TRUE, NOISE, H, N = 40.0, 0.05, 4.0, 140


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--trials", type=int, default=100)
    p.add_argument("--seed", type=int, default=2026)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "fit-ei.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("fit_ei.py", argv)
    cal = get_calibration(1)
    lo, hi = float(cal.pressure(90.0)), cal.p_max
    rng = np.random.default_rng(a.seed)
    errors, covered, widths, solves, bound = [], 0, [], [], []
    t0 = time.perf_counter()
    for _ in range(a.trials):
        m = int(rng.integers(8, 16))
        P = np.sort(rng.uniform(lo, hi, m))
        true = [lcpbench.solve(ActuatorScene(theta=float(cal.theta(q)), height=H, links=N,
                                             EI=EI_TRUE), tol=1e-10) for q in P]
        F = np.array([r.total_force for r in true])
        y = F * (1 + NOISE * rng.standard_normal(m))
        g = np.array([EI_TRUE * lcpbench.sensitivities(r, wrt=("EI",)).total_force["EI"] / f
                      if f > 0 else 0.0 for r, f in zip(true, F)])
        bound.append(1.0 / np.sqrt(np.sum(g**2) * (1 / NOISE**2 + 2)))
        got = fit(ActuatorScene(theta=150.0, height=H, links=N), P, y, cal)
        errors.append(got.EI / EI_TRUE - 1)
        covered += got.EI_low <= EI_TRUE <= got.EI_high
        widths.append((got.EI_high - got.EI_low) / (2 * EI_TRUE))
        solves.append(got.solves)
    err = np.abs(np.array(errors))
    bound = np.array(bound)
    efficient = float(np.mean(erf(0.02 / (bound * np.sqrt(2)))))
    best = 1.0 / np.sqrt(15 * (1 / NOISE**2 + 2))  # 15 points, all pressing, g = 1
    best_share = float(erf(0.02 / (best * np.sqrt(2))))
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# Fitting EI to noisy force-pressure data (issue 38, target 3)", "",
        f"Computed {when} by `{cmd}` in {time.perf_counter() - t0:.0f} s. Data: m ∈ [8, 15] pressures uniform "
        f"in [{lo:.1f}, {hi:.1f}] kPa (actuator 1's calibration, θ from 90°), the model's "
        f"total force at EI = {EI_TRUE:g} N mm² (N = {N}, h = {H:g} mm, forward solves at "
        f"tol 1e-10) times 1 + {NOISE:g} z, z ~ N(0, 1). The fit starts from 32.01 N mm² "
        "with the calibration fixed. The data come from the model being fitted (no model "
        "error): this measures the estimator and its interval, not the model.", "",
        "| trials | within 2 % of EI | median error | 90th percentile error | 95 % interval "
        "covers EI | median half-width | median solves | within 2 % at the Cramér–Rao "
        "bound | median bound s |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        f"| {a.trials} | {np.mean(err <= 0.02):.0%} | {np.median(err):.2%} | "
        f"{np.percentile(err, 90):.2%} | {covered / a.trials:.0%} | {np.median(widths):.2%} | "
        f"{int(np.median(solves))} | {efficient:.0%} | {np.median(bound):.2%} |", "",
        "F is nearly proportional to EI (EI ∂F/∂EI = F − w ∂F/∂w, the weight term about 1 %), "
        "so with 5 % noise the standard error of EI is about 5 %/√m_c, m_c the points that "
        "press the wall (the lowest pressures touch it little or not at all): 1.3–1.8 % for "
        "15 to 8 such points. The share of fits within 2 % follows from that, whatever the "
        "estimator; the interval's coverage is the check on the reported uncertainty.", "",
        "The Cramér–Rao column makes that exact: it is the share of trials an efficient "
        "unbiased estimator would bring within 2 %, from each trial's own pressures. Even the "
        f"best design the target admits, 15 points that all press the wall (g = 1), has "
        f"s = {best:.2%} and brings {best_share:.0%} of trials within 2 %: 90 % within 2 % "
        "at 5 % noise needs at least 17 pressing points.", ""])
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
