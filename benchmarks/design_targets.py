"""Issue 38, targets 1, 2 and 4: sensitivities against finite differences, and the cost
of sensitivities and inverse queries.

1. Random actuator scenes (θ ∈ [100°, 175°], h ∈ [1.5, 6] mm, N ∈ {40, 140}, a channel
   in a third, elastic walls in a third with k = 10^U(−1, 4) N/mm², weight 1× or 5× the
   paper's; numpy default_rng(seed)), each solved at the tightest tolerance the judge
   certifies (1e-13, 1e-12 or 1e-11); those touching a wall with a stable contact set
   (no node at a change of it) are kept, up to ``--scenes``; then rows of sections and
   profiled walls (``--more`` each). For each parameter, the total force's derivative
   against Richardson's extrapolation of central differences of solves at δ and 2δ
   (:func:`richardson`, O(δ⁴); relative δ 1e-3, the weights and the wall stiffness
   1e-2, smaller where a moved solve leaves the centre's contact set), by the relative
   difference; a derivative that is ~0 (|p ∂F/∂p| < TINY F) apart, by its difference in
   F per relative change of p.
2. At N = 140 (θ = 150°, h = 3 mm, tol 1e-10; a row of two sections in a channel; a
   stenosis, a wall profile), interleaved: ``lcpbench.solve``, ``sensitivities`` (all
   parameters, and the first alone); and ``lcpbench.design`` queries (forward solves
   and wall time).
4. The design answers' force error and the force 0.01° beyond.

Writes ``results/design-targets.md`` (``--out``; not overwritten without ``--force``).

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 python benchmarks/design_targets.py --force
"""

# ruff: noqa: E402  (BLAS is pinned to one thread before numpy is imported)
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from perf import interleaved, wall  # (benchmarks/ is the script's directory)

import lcpbench
from lcpbench import ActuatorScene, SectionedScene
from lcpbench.bench.machine import command_line, refuse_overwrite, timing_note, timing_start
from lcpbench.model.sensitivity import sensitivities
from lcpbench.problems.walls import WallProfile
from lcpbench.studies.design import design

ROOT = Path(__file__).resolve().parents[1]
ATTR = {"theta_deg": "theta", "height_mm": "height", "EI": "EI", "weight": "weight",
        "length_mm": "length", "wall_stiffness": "wall_stiffness"}
#: the finite differences' relative steps, largest first (the next is tried where a
#: moved solve leaves the centre's contact set); the force is nearly linear in the
#: weights and the wall stiffness, whose steps start larger
STEPS, STEPS_LINEAR = (1e-3, 1e-4), (1e-2, 1e-3, 1e-4)
#: the solves' tolerances, tightest first: each scene at the tightest the judge certifies
TOLS = (1e-13, 1e-12, 1e-11)
#: a derivative is ~0 where a relative change of p moves F by less than TINY of that
#: change (|p ∂F/∂p| < TINY F): the oracle's noise (solves to ~1e-12 of F over a relative
#: step of 1e-3: ~1e-9 F) is then more than 1e-6 of it
TINY = 1e-3


def _contact_set(r) -> tuple:
    return (tuple(np.flatnonzero(r.forces > 0)),
            () if r.forces_lower is None else tuple(np.flatnonzero(r.forces_lower > 0)))


def _solve(scene, tols=TOLS, start=None):
    """The first of ``tols`` at which the judge certifies the solve: (result, tol), or
    (the last result, None)."""
    for t in tols:
        r = lcpbench.solve(scene, tol=t, start=start)
        if r.converged:
            return r, t
    return r, None


def richardson(scene, res, tol, p, size, moved, linear):
    """The total force's derivative in ``p`` by Richardson extrapolation of central
    differences at δ and 2δ, (4 D(δ) − D(2δ)) / 3 = ∂F/∂p + O(δ⁴): (it, D(δ) alone, the
    relative step, the loosest tolerance used, its error bound from the judge's force
    error bounds of the solves, O(δ⁴) aside), or (None, why). Every moved solve at the
    tightest tolerance certified from the centre's on, kept only where it keeps the
    centre's contact set (else the next smaller step)."""
    tols = TOLS[TOLS.index(tol):]
    centre, why = _contact_set(res), "a moved solve changes the contact set at every step"
    for rel in (STEPS_LINEAR if linear else STEPS):
        d, D, loosest = rel * abs(size), [], tol
        eps = res.force_error_bound * res.judgement.force_unit
        for m in (1, 2):
            start = None if p == "length_mm" else res
            (up, tu), (dn, td) = (_solve(moved(scene, p, s * m * d), tols, start)
                                  for s in (1, -1))
            if tu is None or td is None:
                why = "a moved solve is not certified at tol 1e-11"
                break
            if _contact_set(up) != centre or _contact_set(dn) != centre:
                break
            loosest = max(loosest, tu, td)
            D.append((up.total_force - dn.total_force) / (2 * m * d))
            eps = max(eps, *(r.force_error_bound * r.judgement.force_unit for r in (up, dn)))
        if len(D) == 2:  # |error| <= (4/3) ε/δ + (1/3) ε/(2δ) from the solves' bounds ε
            return ((4 * D[0] - D[1]) / 3, D[0], rel, loosest, 1.5 * eps / d), ""
    return None, why


def _pair(scene, res, tol, sens, p, size, moved, linear):
    """One derivative against the oracle: a dict of its numbers, or the reason it has none."""
    got, why = richardson(scene, res, tol, p, size, moved, linear)
    if got is None:
        return why
    rich, central, rel, loosest, bound = got
    imp, F = sens.total_force[p], res.total_force
    return {"p": p, "rel": abs(imp - rich) / abs(rich) if rich else np.inf,
            "bound": bound * abs(size) / F,  # (in F per relative change of p)
            "central": abs(imp - central) / abs(central) if central else np.inf,
            # in F per relative change of p: the difference and the derivative's size
            "scaled": abs(imp - rich) * abs(size) / F, "size": abs(rich * size) / F,
            "step": rel, "tol": loosest}


def target1(n_scenes: int, seed: int) -> tuple[list[str], dict]:
    rng = np.random.default_rng(seed)
    pairs: list[dict] = []
    dropped: dict[str, int] = {}
    kept = tried = 0
    tols: dict[float, int] = {}
    while kept < n_scenes and tried < 20 * n_scenes:
        tried += 1
        kw = dict(theta=float(rng.uniform(100, 175)), height=float(rng.uniform(1.5, 6.0)),
                  links=int(rng.choice([40, 140])), channel=bool(rng.random() < 1 / 3),
                  weight=0.000245 * float(rng.choice([1.0, 5.0])))
        if rng.random() < 1 / 3:
            kw["wall_stiffness"] = float(10 ** rng.uniform(-1, 4))
        scene = ActuatorScene(**kw)
        res, tol = _solve(scene)
        if tol is None or res.total_force <= 0:
            continue
        sens = sensitivities(res)
        if sens.one_sided.size:
            continue
        kept += 1
        tols[tol] = tols.get(tol, 0) + 1
        for p in sens.wrt:
            got = _pair(scene, res, tol, sens, p, getattr(scene, ATTR[p]), _moved,
                        p in ("weight", "wall_stiffness"))
            if isinstance(got, str):
                dropped[got] = dropped.get(got, 0) + 1
            else:
                got["scene"] = kw
                pairs.append(got)
    return _report1(pairs), {"kept": kept, "tried": tried, "pairs": len(pairs),
                             "dropped": dropped, "tols": tols, "list": pairs}


def _report1(pairs: list[dict]) -> list[str]:
    lines = ["| parameter | pairs | resolvable | within 1e-6 | largest relative | "
             "~0 | largest ~0, F per relative change of p |", "|---|---:|---:|---:|---:|---:|---:|"]
    for name in dict.fromkeys(q["p"].split("[")[0] for q in pairs):
        mine = [q for q in pairs if q["p"].split("[")[0] == name]
        big = [q["rel"] for q in mine if q["size"] >= TINY]
        tiny = [q["scaled"] for q in mine if q["size"] < TINY]
        lines.append(f"| {name} | {len(mine)} | {len(big)} | "
                     f"{np.mean(np.array(big) <= 1e-6):.1%} | "
                     f"{max(big, default=np.nan):.1e} | {len(tiny)} | "
                     f"{max(tiny, default=np.nan):.1e} |")
    return lines


def _summary(pairs: list[dict]) -> dict:
    big = [q for q in pairs if q["size"] >= TINY]
    rel = np.array([q["rel"] for q in big])
    tiny = [q for q in pairs if q["size"] < TINY]
    return {"big": len(big), "tiny": len(tiny),
            "within": int(np.sum(rel <= 1e-6)), "median": float(np.median(rel)),
            "p99": float(np.percentile(rel, 99)), "max": float(rel.max()),
            "central_within": int(np.sum(np.array([q["central"] for q in big]) <= 1e-6)),
            "all_within": int(np.sum(np.array([q["rel"] for q in pairs]) <= 1e-6)),
            "tiny_max": max((q["scaled"] for q in tiny), default=np.nan),
            "scaled_median": float(np.median([q["scaled"] for q in pairs])),
            "misses": sorted((q for q in big if q["rel"] > 1e-6), key=lambda q: -q["rel"]),
            # past 1e-6 (~0 ones included) yet within the oracle's own error bound
            "past_in_bound": sum(q["rel"] > 1e-6 and q["scaled"] <= q["bound"] for q in pairs),
            "past": sum(q["rel"] > 1e-6 for q in pairs),
            "bound_median": float(np.median([q["bound"] for q in pairs])),
            "steps": {r: sum(q["step"] == r for q in pairs) for r in STEPS_LINEAR}}


def _misses(misses: list[dict]) -> list[str]:
    if not misses:
        return []
    lines = ["| parameter | relative difference | F per relative change | oracle's bound | "
             "p ∂F/∂p / F | step | tol | scene |", "|---|---:|---:|---:|---:|---:|---:|---|"]
    for q in misses[:12]:
        sc = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                       for k, v in q.get("scene", {}).items())
        lines.append(f"| {q['p']} | {q['rel']:.1e} | {q['scaled']:.1e} | {q['bound']:.1e} | "
                     f"{q['size']:.1e} | "
                     f"{q['step']:.0e} | {q['tol']:.0e} | {sc} |")
    return lines


def _moved(scene, p, d):
    """``scene`` with parameter ``p`` moved by ``d``: a row of sections' θ_k, EI_k, w_k
    (``name[k]``), its height or every length scaled (``length_mm``); a profiled wall's
    ``height_mm`` by the profile moved up by d (no channel here); else the scene's own
    field."""
    if isinstance(scene, SectionedScene):
        secs = list(scene.sections)
        if p == "height_mm":
            return dataclasses.replace(scene, height=scene.height + d)
        if p == "length_mm":
            f = 1 + d / scene.length
            return dataclasses.replace(scene, length=None, sections=[
                dataclasses.replace(x, length=x.length * f) for x in secs])
        name, k = p.split("[")
        attr = {"theta_deg": "theta", "EI": "EI", "weight": "weight"}[name]
        k = int(k[:-1])
        secs[k] = dataclasses.replace(secs[k], **{attr: getattr(secs[k], attr) + d})
        return dataclasses.replace(scene, sections=secs)
    if p == "height_mm" and scene.wall_profile is not None:
        w = scene.wall_profile
        return dataclasses.replace(scene, wall_profile=WallProfile.from_function(
            lambda x: w(x) + d, w.slope, w.curvature, x_range=w.x_range))
    return dataclasses.replace(scene, **{ATTR[p]: getattr(scene, ATTR[p]) + d})


def _size(scene, p):
    if isinstance(scene, SectionedScene) and "[" in p:
        name, k = p.split("[")
        return getattr(scene.sections[int(k[:-1])],
                       {"theta_deg": "theta", "EI": "EI", "weight": "weight"}[name])
    if p == "height_mm" and getattr(scene, "wall_profile", None) is not None:
        return 3.0
    return getattr(scene, ATTR[p])


def target1_more(n_scenes: int, seed: int) -> tuple[list[str], dict]:
    """Rows of sections and walls of any profile: random scenes, every parameter against
    the same oracle (:func:`richardson`)."""
    rng = np.random.default_rng(seed + 1)
    pairs, kept, tried, dropped = [], {"sections": 0, "profile": 0}, 0, {}
    while min(kept.values()) < n_scenes and tried < 20 * n_scenes:
        tried += 1
        if kept["sections"] <= kept["profile"]:
            kind = "sections"
            k = int(rng.choice([2, 3]))
            secs = [(float(rng.uniform(90, 170) * rng.choice([1, -1] if kk else [1])),
                     30.0 / k, float(rng.uniform(20, 50)), 2.45e-4 * float(rng.choice([1, 5])))
                    for kk in range(k)]
            scene = SectionedScene(sections=secs, height=float(rng.uniform(1.0, 4.0)),
                                   links=60 * k // 2 * 2, channel=bool(rng.random() < 0.5))
        else:
            kind = "profile"
            depth, centre = float(rng.uniform(0.2, 1.0)), float(rng.uniform(8, 22))
            width, h0 = float(rng.uniform(2, 6)), float(rng.uniform(2.5, 4.5))
            wall = WallProfile.from_function(
                lambda x, h0=h0, d=depth, c=centre, w=width: h0 - d * np.exp(-((x - c) / w) ** 2),
                lambda x, d=depth, c=centre, w=width: 2 * d * (x - c) / w**2
                * np.exp(-((x - c) / w) ** 2), x_range=(-5.0, 40.0), name="bump")
            scene = ActuatorScene(theta=float(rng.uniform(120, 175)), links=int(rng.choice(
                [60, 140])), wall_profile=wall, weight=2.45e-4 * float(rng.choice([1, 5])))
        res, tol = _solve(scene)
        if tol is None or res.total_force <= 0:
            continue
        sens = sensitivities(res)
        if sens.one_sided.size:
            continue
        kept[kind] += 1
        for p in sens.wrt:
            got = _pair(scene, res, tol, sens, p, _size(scene, p), _moved,
                        p.startswith("weight"))
            if isinstance(got, str):
                dropped[got] = dropped.get(got, 0) + 1
            else:
                got["kind"], got["scene"] = kind, {"scene": kind, "links": scene.links}
                pairs.append(got)
    lines = ["| scenes | parameter | pairs | median relative difference | within 1e-6 | "
             "largest | ~0 |", "|---|---|---:|---:|---:|---:|---:|"]
    for kind in ("sections", "profile"):
        for name in dict.fromkeys(q["p"].split("[")[0] for q in pairs if q["kind"] == kind):
            mine = [q for q in pairs if q["kind"] == kind and q["p"].split("[")[0] == name]
            e = np.array([q["rel"] for q in mine if q["size"] >= TINY])
            lines.append(f"| {kind} | {name} | {len(mine)} | {np.median(e):.1e} | "
                         f"{np.mean(e <= 1e-6):.1%} | {e.max():.1e} | "
                         f"{sum(q['size'] < TINY for q in mine)} |")
    return lines, {"kept": kept, "tried": tried, "dropped": dropped, "pairs": len(pairs),
                   "list": pairs}


#: the scenes of target 2 (N = 140): the paper's, a row of two sections, a stenosis
STENOSIS = WallProfile.from_function(
    lambda x: 3.0 - 0.8 * np.exp(-((x - 14.0) / 3.0) ** 2),
    lambda x: 1.6 * (x - 14.0) / 9.0 * np.exp(-((x - 14.0) / 3.0) ** 2), name="stenosis")
COST_SCENES = {
    "one wall": ActuatorScene(theta=150, height=3.0, links=140),
    "two sections, channel": SectionedScene(sections=[(150.0, 15.0), (-150.0, 15.0)],
                                            height=1.0, links=140, channel=True),
    "wall profile (stenosis)": ActuatorScene(theta=150, links=140, wall_profile=STENOSIS),
}


def target2(rounds: int) -> list[str]:
    lines = ["| scene | call | median (ms) | × its solve |", "|---|---|---:|---:|"]
    for label, scene in COST_SCENES.items():
        res = lcpbench.solve(scene, tol=1e-10)
        first = sensitivities(res).wrt[0]
        calls = {"lcpbench.solve (tol 1e-10)": lambda sc=scene: lcpbench.solve(sc, tol=1e-10),
                 "sensitivities, all parameters": lambda r=res: sensitivities(r),
                 f"sensitivities, {first} alone": lambda r=res, p=first: sensitivities(
                     r, wrt=(p,))}
        times = {name: g["times"] for name, g in interleaved(
            {name: wall(call) for name, call in calls.items()}, rounds).items()}
        base = float(np.median(times["lcpbench.solve (tol 1e-10)"]))
        for name, t in times.items():
            lines.append(f"| {label} | {name} | {1e3 * np.median(t):.3f} | "
                         f"{np.median(t) / base:.2f} |")
    return lines


def design_rows(rounds: int) -> list[str]:
    lines = ["| query | answer θ (deg) | force at it (N) | relative to the limit | "
             "0.01° beyond (N) | solves | median time (ms) |", "|---|---:|---:|---:|---:|---:|---:|"]
    for kw in (dict(max_force=0.05), dict(max_force=0.3), dict(min_force=0.2),
               dict(max_force=0.05, peak=True)):
        scene = ActuatorScene(theta=150, height=4.0, links=140)
        times = []
        for _ in range(rounds):
            t0 = time.perf_counter()
            got = design(scene, **kw)
            times.append(time.perf_counter() - t0)
        limit = kw.get("max_force", kw.get("min_force"))
        name = ", ".join(f"{k}={v}" for k, v in kw.items())
        lines.append(f"| {name} | {got.theta_deg:.6f} | {got.value:.9g} | "
                     f"{got.value / limit - 1:+.1e} | {got.beyond:.9g} | {got.solves} | "
                     f"{1e3 * np.median(times):.2f} |")
    return lines


def _target1_text(s1: dict, s1b: dict, t1: list[str], t1b: list[str]) -> list[str]:
    m, mb = _summary(s1["list"]), _summary(s1b["list"])
    tols = ", ".join(f"{n} at {t:.0e}" for t, n in sorted(s1["tols"].items()))
    steps = ", ".join(f"{n} at {r:.0e}" for r, n in m["steps"].items() if n)
    dropped = "; ".join(f"{n}: {why}" for why, n in s1["dropped"].items()) or "none"
    return [
        "The oracle: Richardson extrapolation of central differences of solves at relative "
        "steps δ and 2δ, (4 D(δ) − D(2δ)) / 3 = ∂F/∂p + O(δ⁴), δ = 1e-3 (the weight and the "
        "wall stiffness, on which F is nearly linear: 1e-2), the next step down (to 1e-4) "
        "where a moved solve leaves the centre's contact set; every solve at the tightest "
        "tolerance the judge certifies (1e-13, else 1e-12, else 1e-11). A derivative is "
        f"**~0** where |p ∂F/∂p| < {TINY:g} F: the oracle's noise (solves to ~1e-12 of F over a "
        "relative step of 1e-3, ~1e-9 F per relative change of p) is then more than 1e-6 of "
        "it, so its relative difference says nothing; those are reported apart, by their "
        "difference in units of F per relative change of p.", "",
        f"{s1['kept']} random scenes with a stable contact set (of {s1['tried']} drawn; the "
        "rest touch no wall, are not certified at tol 1e-11 or have a node at a change of "
        f"contact set; centres certified: {tols}), {s1['pairs']} derivative pairs (steps: "
        f"{steps}; dropped: {dropped}). Of the {m['big']} resolvable pairs **{m['within']} "
        f"({m['within'] / m['big']:.1%}) are within 1e-6 relative** (median {m['median']:.1e}, "
        f"99th percentile {m['p99']:.1e}, largest {m['max']:.1e}); the central difference "
        f"D(δ) alone, at the same steps and solves, has {m['central_within']} within 1e-6. "
        f"Of all {s1['pairs']} pairs, ~0 ones included, {m['all_within']} "
        f"({m['all_within'] / s1['pairs']:.1%}) are within 1e-6. The {m['tiny']} ~0 "
        f"derivatives differ by at most {m['tiny_max']:.1e} F per relative change of p "
        f"(all pairs' median {m['scaled_median']:.1e}). The oracle's own error bound, "
        "1.5 ε/δ from the judge's force error bounds ε of its solves (O(δ⁴) aside; the "
        "bound carries the judge's round-off allowance, so it is loose), is "
        f"{m['bound_median']:.1e} F per relative change at the median; of the "
        f"{m['past']} pairs past 1e-6, {m['past_in_bound']} differ by less than it.", "",
        *t1, "",
        *(["The resolvable pairs past 1e-6:", "", *_misses(m["misses"]), ""]
          if m["misses"] else []),
        f"Rows of sections ({s1b['kept']['sections']}: 2 or 3 sections, θ_k in ±[90°, "
        "170°], EI_k in [20, 50] N mm², w 1× or 5×, h in [1, 4] mm, a channel in half) and "
        f"walls of any profile ({s1b['kept']['profile']}: a Gaussian narrowing of random "
        "depth, centre and width, θ in [120°, 175°], N 60 or 140), drawn from seed + 1 "
        f"({s1b['tried']} drawn), {s1b['pairs']} pairs against the same oracle (dropped: "
        f"{'; '.join(f'{n}: {w}' for w, n in s1b['dropped'].items()) or 'none'}): "
        f"{mb['within']} of {mb['big']} resolvable within 1e-6 (median {mb['median']:.1e}, "
        f"largest {mb['max']:.1e}), {mb['tiny']} ~0 (at most {mb['tiny_max']:.1e} F per "
        "relative change).", "", *t1b, "",
        *(["Their resolvable pairs past 1e-6:", "", *_misses(mb["misses"]), ""]
          if mb["misses"] else [])]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenes", type=int, default=200)
    p.add_argument("--seed", type=int, default=38)
    p.add_argument("--more", type=int, default=40,
                   help="random rows of sections and profiled scenes, each")
    p.add_argument("--rounds", type=int, default=31)
    p.add_argument("--out", type=Path, default=ROOT / "results" / "design-targets.md")
    p.add_argument("--force", action="store_true", help="overwrite a committed result")
    a = p.parse_args(argv)
    refuse_overwrite([a.out], a.force)
    cmd = command_line("design_targets.py", argv)
    start = timing_start()
    t1, s1 = target1(a.scenes, a.seed)
    t1b, s1b = target1_more(a.more, a.seed)
    t2 = target2(a.rounds)
    t4 = design_rows(max(3, a.rounds // 5))
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    text = "\n".join([
        "# Sensitivities and inverse queries (issue 38, targets 1, 2 and 4)", "",
        f"Measured {when}; {timing_note(start)} Command: `{cmd}`.", "",
        "## Target 1: sensitivities against finite differences of solves", "",
        *_target1_text(s1, s1b, t1, t1b),
        "## Target 2: cost", "", *t2, "",
        "## Targets 2 and 4: inverse queries (θ from 150°, h = 4 mm, N = 140)", "", *t4, ""])
    a.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
