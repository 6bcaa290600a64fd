"""The friction grid (issue 39): the pull-out force over μ × input pressure × h.

One grid definition, :class:`FrictionGrid`, and its default :data:`FRICTION_GRID`: the
paper's actuator 1 (θ from its calibration, eq. 40) in the paper's channel (walls at
±h), sliders at both ends, the pull on the right end. Each point's result is
:func:`lcpbench.pull_out`; it is stored in the results store's table ``pull_outs``,
keyed by the frictionless scene's key and μ, so a killed run resumes where it stopped
(the points already there are skipped). ``normal_force_total`` and ``capacity`` are
those of the last state the pull-out held, at the pull ``held_pull`` (<= the pull-out
force: :class:`lcpbench.studies.pull_out.PullOut`). At μ = 0 nothing holds the chain along x (it
slides at any pull): the pull-out force is 0 by Coulomb's law, and ΣN is the
frictionless solve's.
"""

from __future__ import annotations

import math
import sqlite3
import time
from dataclasses import dataclass, replace

from ..errors import ProblemError, StoreError
from ..problems.calibrations import scene_from_pressure
from ..problems.scenes import DEFAULT_LINKS, ActuatorScene
from .grid import scene_key

#: default μ, input pressures (kPa: the paper's 10, 15, 20, 25 psi) and heights (mm)
FRICTION_MU = (0.0, 0.1, 0.3, 0.5)
FRICTION_PRESSURES = (68.95, 103.42, 137.9, 172.37)
FRICTION_HEIGHTS = (4.5, 5.5, 6.5)

TABLE = "pull_outs"
COLUMNS = ("scene", "friction", "tol", "actuator", "pressure", "theta", "height", "links",
           "channel",
           "pull_out_force", "normal_force_total", "capacity", "held_pull", "solves",
           "converged",
           "reason", "wall_time", "created", "sweep_id")
_CREATE = f"""CREATE TABLE IF NOT EXISTS {TABLE} (
    scene TEXT NOT NULL, friction REAL NOT NULL, tol REAL NOT NULL, actuator TEXT,
    pressure REAL, theta REAL,
    height REAL, links INTEGER, channel INTEGER, pull_out_force REAL,
    normal_force_total REAL, capacity REAL, held_pull REAL, solves INTEGER, converged INTEGER, reason TEXT,
    wall_time REAL, created TEXT, sweep_id TEXT, PRIMARY KEY (scene, friction, tol))"""


@dataclass(frozen=True)
class FrictionGrid:
    """μ × input pressure (kPa) × h (mm) for one actuator's calibration, N links."""

    friction: tuple[float, ...] = FRICTION_MU
    pressure: tuple[float, ...] = FRICTION_PRESSURES
    height: tuple[float, ...] = FRICTION_HEIGHTS
    links: int = DEFAULT_LINKS
    actuator: str = "1"
    channel: bool = True

    def __post_init__(self):
        for name in ("friction", "pressure", "height"):
            if len(getattr(self, name)) == 0:
                raise ProblemError(f"the friction grid is empty: {name} has no values")

    def points(self) -> list[tuple[float, ActuatorScene]]:
        """(μ, the frictionless scene) of every point, μ varying fastest; every scene
        is built (and so checked) here, before anything runs."""
        out = []
        for h in self.height:
            for p in self.pressure:
                base = scene_from_pressure(p, self.actuator, h, channel=self.channel,
                                           links=self.links)
                for mu in self.friction:
                    if mu > 0:  # (checks μ)
                        replace(base, friction=mu, left_end="slider", right_end="slider")
                    elif mu != 0:
                        raise ProblemError(f"friction must be >= 0, got {mu!r}")
                    out.append((float(mu), base))
        return out

    def __len__(self) -> int:
        return len(self.friction) * len(self.pressure) * len(self.height)


FRICTION_GRID = FrictionGrid()


def ensure_table(store) -> None:
    """Create the ``pull_outs`` table in the store if it is not there."""
    try:
        with store.db:
            store.db.execute(_CREATE)
    except sqlite3.Error as exc:
        raise StoreError(f"store {store.path}: cannot write to it ({exc})") from exc


def stored_keys(store) -> set[tuple[str, float, float]]:
    """(scene, μ, tol) of every point stored (a point at another tol is another point)."""
    ensure_table(store)
    return {(s, float(m), float(t)) for s, m, t in
            store.db.execute(f"SELECT scene, friction, tol FROM {TABLE}")}


def point_row(mu: float, scene: ActuatorScene, pressure: float, actuator: str, *,
              tol: float = 1e-10) -> dict:
    """The pull-out of one grid point as a row of ``pull_outs`` (N, mm, kPa)."""
    from ..api import solve
    from ..studies.pull_out import pull_out

    t0 = time.perf_counter()
    row = {"scene": scene_key(scene), "friction": mu, "tol": tol, "actuator": str(actuator),
           "pressure": pressure, "theta": scene.theta, "height": scene.height,
           "links": scene.links, "channel": int(scene.channel)}
    if mu == 0:
        res = solve(scene, tol=tol)
        row.update(pull_out_force=0.0, normal_force_total=res.total_force, capacity=0.0,
                   held_pull=0.0, solves=0, converged=int(res.converged),
                   reason="μ = 0: no friction holds the chain along x (pull-out force 0)")
    else:
        po = pull_out(replace(scene, friction=mu, left_end="slider", right_end="slider"),
                      tol=tol)
        row.update(pull_out_force=po.force, normal_force_total=po.normal_force_total,
                   capacity=po.capacity, solves=po.solves,
                   held_pull=po.path[-1].pull if po.path else None, converged=int(po.converged),
                   reason=po.reason)
    row["wall_time"] = time.perf_counter() - t0
    return row


def run_friction_grid(store, grid: FrictionGrid = FRICTION_GRID, *, rerun: bool = False,
                      progress=None, tol: float = 1e-10) -> tuple[int, int]:
    """Compute every point of ``grid`` not yet in ``store`` (all with ``rerun``) and
    store each as it is done. ``progress(row)`` is called after each point (``row``
    None for a point already stored). Returns
    (points computed, points already there)."""
    from datetime import datetime, timezone

    ensure_table(store)
    have = set() if rerun else stored_keys(store)
    done = skipped = 0
    for (mu, scene), pressure in zip(grid.points(), _pressures(grid), strict=True):
        if (scene_key(scene), mu, float(tol)) in have:
            skipped += 1
            if progress is not None:
                progress(None)
            continue
        row = point_row(mu, scene, pressure, grid.actuator, tol=tol)
        row["created"] = datetime.now(timezone.utc).isoformat(timespec="seconds")
        row["sweep_id"] = store.sweep_id
        values = tuple(_cell(row.get(c)) for c in COLUMNS)
        try:
            with store.db:  # one transaction per point: a killed run keeps the points done
                store.db.execute(f"INSERT OR REPLACE INTO {TABLE} ({', '.join(COLUMNS)}) "
                                 f"VALUES ({', '.join('?' * len(COLUMNS))})", values)
        except sqlite3.Error as exc:
            raise StoreError(f"store {store.path}: cannot write to it ({exc})") from exc
        done += 1
        if progress is not None:
            progress(row)
    return done, skipped


def _pressures(grid: FrictionGrid) -> list[float]:
    return [float(p) for _ in grid.height for p in grid.pressure for _ in grid.friction]


def _cell(v):
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def friction_rows(store, grid: FrictionGrid | None = None, tol: float | None = None
                  ) -> list[dict]:
    """The stored pull-outs as dicts (every row, or the points of ``grid``; every tol, or
    ``tol``'s), ordered by h, pressure, μ; ``converged`` as bool."""
    ensure_table(store)
    rows = [dict(zip(COLUMNS, r, strict=True)) for r in store.db.execute(
        f"SELECT {', '.join(COLUMNS)} FROM {TABLE} ORDER BY height, pressure, friction")]
    for r in rows:
        r["converged"] = bool(r["converged"])
        r["channel"] = bool(r["channel"])
    if grid is not None:
        want = {(scene_key(sc), mu) for mu, sc in grid.points()}
        rows = [r for r in rows if (r["scene"], r["friction"]) in want]
    if tol is not None:
        rows = [r for r in rows if r["tol"] == float(tol)]
    return rows
