"""Issue 39, item 6: the friction figures and the friction grid, into results/friction/.

* ``forces-along-chain.png``: the normal and tangential forces along the chain, stick
  and slip marked (``lcpbench solve --friction ... --plot``'s figure): the paper's scene
  (θ = 150°, h = 3 mm, one wall, N = 140), μ = 0.3, sliders at both ends, pulled to
  90 % of its pull-out force in four steps.
* ``pull-out.csv``, ``pull-out-pressure.png``: ``lcpbench sweep --grid friction`` (the
  default grid: μ 0, 0.1, 0.3, 0.5 × 10, 15, 20, 25 psi × h 4.5, 5.5, 6.5 mm, N = 140)
  run into a temporary store.
* ``load-cycle.csv``, ``load-cycle.png``: actuator 1 inflated from 0 to 25 psi in
  2.5-psi steps and deflated again at h = 5.5 mm in the channel, the model's support,
  μ = 0.1 and 0.3, N = 40 (at N = 140 the frictional outer loop does not converge at
  25 psi, μ = 0.3), beside the frictionless model.
* ``README.md``: the date, the command, the machine load and what each file holds.

Not overwritten without ``--force``.

    python benchmarks/friction_figures.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import csv
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

import lcpbench
from lcpbench.bench.friction_plot import plot_friction_forces, plot_load_cycle
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.cli import main as cli
from lcpbench.studies.load_cycle import load_cycle

ROOT = Path(__file__).resolve().parents[1]
PSI = 6.894757293168361  # kPa
FILES = ("forces-along-chain.png", "pull-out.csv", "pull-out-pressure.png", "load-cycle.csv",
         "load-cycle.png", "README.md")


def forces_figure(out: Path) -> str:
    scene = lcpbench.ActuatorScene(theta=150, height=3.0, links=140, friction=0.3,
                                   left_end="slider", right_end="slider")
    po = lcpbench.pull_out(scene, tol=1e-10)
    path = lcpbench.solve_path(scene, [{"pull": f * po.force} for f in (0.25, 0.5, 0.75, 0.9)],
                               tol=1e-10)
    res = path[-1]
    plot_friction_forces(res, out / "forces-along-chain.png")
    contact = res.forces > 0
    at_cone = contact & (np.abs(res.tangential_forces) >= 0.3 * res.forces * (1 - 1e-6))
    return (f"pull-out force {1e3 * po.force:.4g} mN in {po.solves} frictional solves; at "
            f"90 % of it ({1e3 * res.pull:.4g} mN) ΣN = {1e3 * res.total_force:.4g} mN, "
            f"{int((contact & res.stick).sum())} of {int(contact.sum())} contact nodes stick "
            f"({int(at_cone.sum())} of them at the cone |T| = μN), "
            f"{int((contact & ~res.stick).sum())} slide (converged: {res.converged})")


def cycle_figure(out: Path) -> str:
    psi = np.arange(0.0, 25.0 + 1.25, 2.5)
    cycles = [load_cycle(lcpbench.ActuatorScene(theta=90, height=5.5, channel=True,
                                                links=40, friction=mu), psi * PSI, tol=1e-9)
              for mu in (0.1, 0.3)]
    plot_load_cycle(cycles, out / "load-cycle.png")
    with open(out / "load-cycle.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["friction", "pressure_kpa", "theta_deg", "loading", "force_n",
                    "frictionless_force_n", "converged"])
        for c, mu in zip(cycles, (0.1, 0.3), strict=True):
            for k in range(c.pressure.size):
                w.writerow([mu, round(float(c.pressure[k]), 4), round(float(c.theta[k]), 6),
                            bool(c.loading[k]), float(c.force[k]), float(c.frictionless[k]),
                            bool(c.converged[k])])
    c = cycles[1]
    (p, up), (_, down) = c.branch(True), c.branch(False)
    i = int(np.argmin(np.abs(p - 20 * PSI)))
    return (f"at 20 psi, μ = 0.3: loading {1e3 * up[i]:.4g} mN, unloading "
            f"{1e3 * down[i]:.4g} mN, frictionless {1e3 * c.frictionless[c.loading][i]:.4g} "
            f"mN; every state converged: {all(bool(x.converged.all()) for x in cycles)}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "friction")
    ap.add_argument("--force", action="store_true", help="overwrite committed results")
    a = ap.parse_args(argv)
    refuse_overwrite([a.out / f for f in FILES], a.force)
    cmd = command_line("friction_figures.py", argv)
    a.out.mkdir(parents=True, exist_ok=True)
    start, t0 = timing_start(), time.perf_counter()
    notes = [forces_figure(a.out)]
    with tempfile.TemporaryDirectory() as tmp:
        code = cli(["sweep", "--grid", "friction", "--store", str(Path(tmp) / "f.sqlite"),
                    "--out", str(a.out), "--quiet", "--rerun"])
    notes.append(f"`lcpbench sweep --grid friction` exit status {code}")
    notes.append(cycle_figure(a.out))
    text = [
        "# Friction figures (issue 39)", "",
        f"Written {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC by `{cmd}` in "
        f"{time.perf_counter() - t0:.0f} s; "
        f"{timing_note(start)}", "",
        "| file | what |", "|---|---|",
        "| `forces-along-chain.png` | normal and tangential forces along the chain, stick "
        "and slip marked: θ = 150°, h = 3 mm, one wall, N = 140, μ = 0.3, sliders, "
        "pulled to 90 % of its pull-out force |",
        "| `pull-out.csv`, `pull-out-pressure.png` | `lcpbench sweep --grid friction`: the "
        "pull-out force over μ 0, 0.1, 0.3, 0.5 × 68.95-172.37 kPa × h 4.5, 5.5, 6.5 mm "
        "(actuator 1, channel, N = 140) |",
        "| `load-cycle.csv`, `load-cycle.png` | actuator 1 inflated 0-25 psi and deflated, "
        "h = 5.5 mm, channel, pin and roller, N = 40, μ 0.1 and 0.3, and the frictionless "
        "model |",
        "| `study.md`, `study.json` | `python benchmarks/friction_study.py --force`: the "
        "paper's force error beside wall friction's effect |", "",
        *[f"- {n}" for n in notes], "",
    ]
    (a.out / "README.md").write_text("\n".join(text))
    print("\n".join(text))
    return 0 if code == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
