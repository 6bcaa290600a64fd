"""solve_many's rows of sections started from a neighbouring row: the loading path's state?

A row of sections that the solve kernel refuses cold is solved in ``lcpbench.solve`` along
the loading path (the bend angles grown from zero), which picks the state the
pressurised actuator reaches. ``lcpbench.solve_many`` first starts such a row from the
answer of a row of the batch certified before it, close in bend angles and h (the
escalation ``from_neighbour``: SQP steps in the link angles). This script solves batches
of rows both ways, ``solve_many`` and ``solve`` per row, and counts: the rows that took
``from_neighbour``, how many both certify, how many of those are the same state (each
wall's total force within the judge's τ·F₀, ``escalations.same_state``), the verdict
changes, and the time of each batch. A row certified by ``solve_many`` only is checked
independently: the direct minimisation of its exact energy
(``reference.energy.minimise_energy``, SLSQP and a Newton polish on the KKT system)
started from its answer must stay there, its total force within 1e-6 of F₀. Writes
``results/row-neighbours.md`` (``--out``; not overwritten unless ``--force``).

    python benchmarks/row_neighbours.py --force
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
from mixed_batch import of_kind

import lcpbench
from lcpbench import SectionedScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.escalations import same_state
from lcpbench.reference.energy import minimise_energy

ROOT = Path(__file__).resolve().parents[1]


def random_rows(seed: int, sections: int, channel: bool, count: int, low: float = 100.0,
                high: float = 180.0, h: tuple = (1.0, 5.0), per_section: int = 20) -> list:
    """Rows of ``sections`` sections of 15 mm, each θ of random sign and size in
    [low, high] degrees, h uniform in ``h`` (mm)."""
    rng = np.random.default_rng(seed)
    return [SectionedScene(sections=[(float(rng.choice([-1, 1]) * rng.uniform(low, high)), 15.0)
                                     for _ in range(sections)],
                           height=float(rng.uniform(*h)), links=per_section * sections,
                           channel=channel) for _ in range(count)]


def signed_pairs(seed: int, count: int, channel: bool) -> list:
    """Rows (θ, −θ) as the mixed batch's, θ in 60–200°, h in 1–6 mm, N = 140."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        th = float(rng.uniform(60, 200))
        out.append(SectionedScene(sections=[(th, 15.0), (-th, 15.0)],
                                  height=float(rng.uniform(1.0, 6.0)), links=140,
                                  channel=channel))
    return out


def patterned(seed: int, signs: tuple, count: int, channel: bool = False,
              h: tuple = (1.5, 4.0)) -> list:
    """Rows of 15 mm sections with the bend angles' signs ``signs``, each |θ| uniform in
    100–180°, h uniform in ``h``, N = 20 a section."""
    rng = np.random.default_rng(seed)
    return [SectionedScene(sections=[(float(s * rng.uniform(100, 180)), 15.0) for s in signs],
                           height=float(rng.uniform(*h)), links=20 * len(signs),
                           channel=channel) for _ in range(count)]


def sweeps(signs: tuple, channel: bool, h_mid: float) -> list:
    """A batch of sweeps (a review's, 2026-12-05): rows of 15 mm sections with the signs
    ``signs``, for |θ| 140, 170, 200 and 230° each a sweep in h from 0.8 to 6 mm by 0.45
    then one in |θ| from 100 to 256° by 12° at ``h_mid``, up, then the same down."""
    k = len(signs)
    out = []
    for th in (140, 170, 200, 230):
        for down in (False, True):
            hs, ths = np.arange(0.8, 6.01, 0.45), np.arange(100, 260, 12.0)
            if down:
                hs, ths = hs[::-1], ths[::-1]
            out += [SectionedScene(sections=[(s * th, 15.0) for s in signs], height=float(h),
                                   links=30 * k, channel=channel) for h in hs]
            out += [SectionedScene(sections=[(s * float(t), 15.0) for s in signs],
                                   height=h_mid, links=30 * k, channel=channel) for t in ths]
    return out


def saddle_rows(seed: int, count: int) -> list:
    """Rows as benchmarks/saddle_audit.py draws them: 2–4 sections of 30 mm, θ 10–170° of
    random sign, h 1–8 mm, one wall or a channel."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        k = int(rng.integers(2, 5))
        angles = rng.uniform(10, 170, k) * rng.choice([-1, 1], k)
        out.append(SectionedScene(sections=[(float(a), 30.0) for a in angles],
                                  height=float(rng.uniform(1, 8)),
                                  channel=bool(rng.random() < 0.5)))
    return out


def batches() -> list[tuple[str, object]]:
    """(name, a maker of fresh scenes) for every batch of the audit."""
    out: list[tuple[str, object]] = [
        (f"the mixed batch's rows (θ, −θ), seed {s}", lambda s=s: of_kind(s, "two sections"))
        for s in (7, 8, 9, 11, 12, 13, 14, 15)]
    for k, (n, ch) in enumerate(((2, False), (2, True), (3, False), (3, True))):
        out.append((f"{n} sections, θ ±100–180°, {'channel' if ch else 'one wall'}",
                    lambda k=k, n=n, ch=ch: random_rows(300 + k, n, ch, 120)))
    for k, (n, ch) in enumerate(((2, False), (2, True), (4, False))):
        out.append((f"{n} sections, θ ±130–180°, h 1.5–3.5 mm (dense), "
                    f"{'channel' if ch else 'one wall'}",
                    lambda k=k, n=n, ch=ch: random_rows(400 + k, n, ch, 100, 130, 180,
                                                        (1.5, 3.5), 30)))
    for k, ch in enumerate((False, False, True)):
        out.append((f"(θ, −θ), θ 60–200°, h 1–6 mm, {'channel' if ch else 'one wall'}, "
                    f"seed {500 + k}",
                    lambda k=k, ch=ch: signed_pairs(500 + k, 60, ch)))
    for k, (signs, ch) in enumerate((((1, -1, 1, -1), False), ((1, -1, 1, -1), True),
                                     ((1, 1, -1, -1), False), ((1, -1, 1), False),
                                     ((-1, 1, -1), True))):
        out.append((f"signs {''.join('+' if x > 0 else '−' for x in signs)}, "
                    f"θ 100–180°, h 1.5–4 mm, {'channel' if ch else 'one wall'}",
                    lambda k=k, signs=signs, ch=ch: patterned(700 + k, signs, 200, ch)))
    for k, signs in enumerate(((1, -1), (1, -1, 1), (1, 1, -1), (1, -1, 1, -1), (-1, 1, 1))):
        for ch in (False, True):
            out.append((f"sweeps in h and |θ| up to 256°, signs "
                        f"{''.join('+' if x > 0 else '−' for x in signs)}, "
                        f"{'channel' if ch else 'one wall'}",
                        lambda signs=signs, ch=ch, k=k: sweeps(signs, ch, 2.0 + 0.3 * k)))
    out.append(("2–4 sections of 30 mm as saddle_audit.py's", lambda: saddle_rows(600, 60)))
    return out


def audit(make) -> dict:
    """One batch both ways: counts, the largest relative force difference of the rows
    that took ``from_neighbour`` and are one state, and the times."""
    t0 = time.perf_counter()
    many = lcpbench.solve_many(make(), tol=1e-3)
    t_many = time.perf_counter() - t0
    t0 = time.perf_counter()
    alone = [lcpbench.solve(s, tol=1e-3) for s in make()]
    t_alone = time.perf_counter() - t0
    row = dict(rows=len(many), took=0, both=0, same=0, only_many=0, checked=0,
               only_solve=0, worst=0.0, t_many=t_many, t_alone=t_alone, other=[])
    for a, b in zip(many, alone, strict=True):
        if not (a.retries and a.retries[-1].name == "from_neighbour"):
            continue
        row["took"] += 1
        if a.converged and b.converged:
            row["both"] += 1
            if same_state(a, b):
                row["same"] += 1
                row["worst"] = max(row["worst"], abs(a.total_force - b.total_force)
                                   / max(abs(b.total_force), a.scene.chain().force_scale))
            else:
                row["other"].append((a.scene, a.total_force, b.total_force))
        elif a.converged:
            row["only_many"] += 1
            ref = minimise_energy(a.scene, start=np.asarray(a.alpha, float))
            unit = max(abs(a.total_force), a.scene.chain().force_scale)
            if ref.success and abs(ref.total_force - a.total_force) <= 1e-6 * unit:
                row["checked"] += 1
        elif b.converged:
            row["only_solve"] += 1
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "row-neighbours.md")
    ap.add_argument("--force", action="store_true", help="overwrite --out")
    args = ap.parse_args(argv)
    refuse_overwrite([args.out], args.force)
    cmd = command_line("row_neighbours.py", argv)
    lcpbench.solve_many(of_kind(7, "two sections"), tol=1e-3)  # (compiled before the clocks)
    start = timing_start()
    lines = ["| batch | rows | took from_neighbour | both certified | same state | "
             "certified by solve_many only (of them at an energy minimum) | by solve only | "
             "largest force difference (of F₀) | solve_many (s) | solve per row (s) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    total = dict(rows=0, took=0, both=0, same=0, only_many=0, checked=0, only_solve=0)
    others = []
    for name, make in batches():
        r = audit(make)
        print(name, {k: v for k, v in r.items() if k != "other"}, flush=True)
        for k in total:
            total[k] += r[k]
        others += r["other"]
        lines.append(f"| {name} | {r['rows']} | {r['took']} | {r['both']} | {r['same']} | "
                     f"{r['only_many']} ({r['checked']}) | {r['only_solve']} | {r['worst']:.1e} | "
                     f"{r['t_many']:.3f} | {r['t_alone']:.3f} |")
    lines.append(f"| all | {total['rows']} | {total['took']} | {total['both']} | "
                 f"{total['same']} | {total['only_many']} ({total['checked']}) | "
                 f"{total['only_solve']} | | | |")
    text = ["# solve_many's rows started from a neighbouring row (issue 35, target 3)", "",
            f"Measured {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
            f"{timing_note(start)} Command: `{cmd}`; "
            "tol 1e-3.",
            "", __doc__.split("\n\n")[1].replace("\n", " "), "", *lines, ""]
    if others:
        text += ["Rows that took `from_neighbour` and reached another state than "
                 "`solve`'s loading path:", ""]
        text += [f"- {s}: {fa:.6g} N against {fb:.6g} N" for s, fa, fb in others]
    else:
        text.append("Every row that took `from_neighbour` and that both certify is the "
                    "loading path's state.")
    args.out.write_text("\n".join(text) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
