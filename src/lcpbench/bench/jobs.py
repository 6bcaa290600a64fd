"""Typed jobs of a sweep: what each kind runs, which store rows it writes, and how.

Kinds of job
------------
:class:`ReferenceJob`  the per-scene reference: the built-in active set at
    settings ``high`` and driver tolerance :data:`REFERENCE_TOL`, checked by
    re-solving its last contact step with Lemke (a different algorithm on
    the dense condensed LCP); computed once per scene.
:class:`RunJob`  ``lcpbench.solve(scene, solver=backend, settings=...,
    tol=..., method=driver)``.
:class:`BaselineJob`  the paper's root-finding baseline (Appendix A) with an
    analytic (``baseline``) or finite-difference (``baseline-fd``) Jacobian.
:class:`LineJob`  continuation (``--continuation``): one back-end × settings ×
    tol over a line of scenes that differ only in θ, θ ascending, solved in
    order by :func:`~lcpbench.studies.continuation.solve_sequence`, each scene
    started from its predecessors' answers. One row per scene, method
    ``globalised+quadratic`` (or ``+secant``, ``+previous``), so they never mix
    with the cold runs in the store.

Every job writes one row per store key (:attr:`Job.keys`); the store's
``method`` column is :attr:`Job.label`: the driver scheme of a run, the MINPACK
method of a baseline (``hybr``, ``lm``), ``globalised+<predictor>`` of a line.
:meth:`Job.execute` never raises and always returns :class:`Rows`, one row per
key, built by :mod:`.rows`.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, field
from typing import ClassVar

from ..solvers.base import PROFILES
from .grid import scene_from_key
from .rows import baseline_row, failed_row, repeated, solution_row

#: driver tolerance (rad) per settings profile, read from the one profile table
#: (:data:`lcpbench.solvers.base.PROFILES`): "default" keeps the paper's 1e-3
PROFILE_TOL = {name: s.driver_tol for name, s in PROFILES.items()}
REFERENCE_TOL = 1e-11  # rad, driver tolerance of the reference
#: the baselines: (Jacobian, MINPACK method). With finite differences Powell's
#: hybrid method (fsolve's default, "hybr") fails at N = 140 on every scene of
#: the paper grid tried (24 of 24 at h = 4-6 mm), so "baseline-fd" is
#: Levenberg-Marquardt (fsolve's other algorithm), which converges, slowly.
BASELINES = {"baseline": ("analytic", "hybr"), "baseline-fd": ("fd", "lm")}
BASELINE_TOL = 1e-10
DEFAULT_TIME_LIMIT = 60.0  # s per job (per scene for a line)


def continuation_method(predictor: str) -> str:
    """The method label of a continuation run: "globalised+secant" and the like."""
    return f"globalised+{predictor}"


@dataclass
class Rows:
    """What a job returns: one row per store key of the job, in order.

    ``complete`` is False when the job failed as a whole (it raised, timed out
    or crashed its worker) and ``rows`` are its failure rows: those must not
    replace answers already stored.
    """

    rows: list[dict]
    complete: bool = True


@dataclass(frozen=True)
class Job:
    """One unit of work of a sweep (a base class: see the kinds above).

    ``kind`` is a tag for display ("ref", "run", "baseline", "line"); what a
    job does is its class's, nothing branches on the tag.
    """

    kind: ClassVar[str] = ""
    scene: str  # scene_key (a line: its first scene)
    backend: str
    settings: str
    tol: float  # the driver tolerance (rad); the baseline's own tolerance
    #: solves timed per row (a converged run is repeated; its times are the median)
    repeat: int = field(default=1, kw_only=True, compare=False)

    @property
    def label(self) -> str:
        """The store's ``method`` column of the job's rows."""
        raise NotImplementedError

    @property
    def key(self) -> tuple:
        return (self.scene, self.backend, self.settings, self.tol, self.label)

    @property
    def keys(self) -> list[tuple]:
        """The store key of every row the job writes."""
        return [self.key]

    @property
    def scene_keys(self) -> tuple[str, ...]:
        """The scene of each row, in order."""
        return (self.scene,)

    @property
    def size(self) -> int:
        """How many rows the job writes."""
        return len(self.scene_keys)

    def time_limit(self, per_row: float) -> float:
        """The job's time limit: ``per_row`` seconds per row (per scene of a line) and repeat."""
        return per_row * self.size * max(1, self.repeat)

    def describe_limit(self, per_row: float) -> str:
        return f"{self.time_limit(per_row):g} s"

    # running
    def execute(self, time_limit: float | None = None) -> Rows:
        """Run the job (in a worker) and return its rows; never raises."""
        t0 = time.perf_counter()
        try:
            rows = self._run(time_limit)
        except Exception as exc:  # a back-end that raises costs its rows, not the sweep
            row = failed_row("error", f"{type(exc).__name__}: {exc}",
                             time.perf_counter() - t0)
            row["traceback"] = traceback.format_exc(limit=5)
            return self.failure(row)
        if len(rows) != self.size:  # never store rows against the wrong scenes
            return self.failure(failed_row("error", f"the job returned {len(rows)} rows "
                                           f"for {self.size} scenes",
                                           time.perf_counter() - t0))
        return Rows(rows)

    def _run(self, time_limit: float | None) -> list[dict]:
        raise NotImplementedError

    def failure(self, row: dict) -> Rows:
        """The rows of the job when it failed as a whole with ``row``."""
        return Rows([row], complete=False)

    # storing
    def is_stored(self, run_keys: set, ref_keys: set) -> bool:
        return all(k in run_keys for k in self.keys)

    def identity(self, scene: str, versions: dict[str, str]) -> dict:
        """The columns of a row that say which job and scene it belongs to."""
        return {"scene": scene, "backend": self.backend, "settings": self.settings,
                "tol": self.tol, "method": self.label, "version": versions[self.backend]}

    def put(self, store, row: dict, replace: bool) -> None:
        store.put_run(row, replace=replace)


#: how many times a run's time limit the reference of a scene may take
REFERENCE_TIME_FACTOR = 10.0


@dataclass(frozen=True)
class ReferenceJob(Job):
    """The reference of one scene (stored among the references, not the runs)."""

    kind: ClassVar[str] = "ref"

    backend: str = "reference"
    settings: str = "high"
    tol: float = REFERENCE_TOL

    @property
    def label(self) -> str:
        return "globalised"

    def time_limit(self, per_row: float) -> float:
        """A reference is not a timed contestant: it gets :data:`REFERENCE_TIME_FACTOR` times
        a run's limit (at N = 2000 its dense Lemke check alone took 31 s on a loaded 2-core
        machine, and a killed reference costs every run of its scene)."""
        return REFERENCE_TIME_FACTOR * per_row

    def _run(self, time_limit):
        return [reference_row(scene_from_key(self.scene))]

    def is_stored(self, run_keys, ref_keys):
        return self.scene in ref_keys

    def identity(self, scene, versions):
        return {"scene": scene}

    def put(self, store, row, replace):
        row.setdefault("tol", self.tol)
        row.setdefault("check_error", float("nan"))
        store.put_ref(row, replace=replace)


@dataclass(frozen=True)
class RunJob(Job):
    """One back-end at one settings profile and tolerance on one scene."""

    kind: ClassVar[str] = "run"

    driver: str = "globalised"  # the driver's scheme (model.outer.METHODS)
    #: the contact step's form (model.formulations), None: the back-end's own
    formulation: str | None = None

    @property
    def label(self) -> str:
        """The stored method: the driver, and ``@formulation`` where one was asked for."""
        return self.driver if self.formulation is None else f"{self.driver}@{self.formulation}"

    def _run(self, time_limit):
        from ..api import solve

        warm_up(self.backend, self.settings)
        scene = scene_from_key(self.scene)

        def once():
            return solution_row(solve(scene, solver=self.backend, tol=self.tol,
                                      settings=self.settings, method=self.driver,
                                      formulation=self.formulation))

        first = once()
        return [repeated(first, once, self.repeats(first))]

    def repeats(self, first: dict) -> int:
        """How many solves time a run whose first solve gave ``first`` (the median of them)."""
        return self.repeat


@dataclass(frozen=True)
class BaselineJob(Job):
    """The root-finding baseline (``backend`` a key of :data:`BASELINES`) on one scene."""

    kind: ClassVar[str] = "baseline"

    settings: str = "-"
    tol: float = BASELINE_TOL

    @property
    def jacobian(self) -> str:
        return BASELINES[self.backend][0]

    @property
    def minpack_method(self) -> str:
        return BASELINES[self.backend][1]

    @property
    def label(self) -> str:
        return self.minpack_method

    def _run(self, time_limit):
        from ..reference.root_finding import solve_baseline

        scene = scene_from_key(self.scene)
        if ("baseline", "") not in _WARM:
            _WARM.add(("baseline", ""))
            solve_baseline(scene.with_links(WARMUP_SCENE["links"]), tol=self.tol)
        def once():
            return baseline_row(scene, solve_baseline(
                scene, tol=self.tol, method=self.minpack_method, jacobian=self.jacobian,
                time_limit=time_limit))

        return [repeated(once(), once, self.repeat)]


@dataclass(frozen=True)
class LineJob(Job):
    """A line of scenes (θ ascending, ``scenes``) by continuation with ``predictor``.

    ``scene`` is the line's first scene. A line is skipped only when all its
    rows are stored; a partly stored line is run again in full and its rows
    replaced.
    """

    kind: ClassVar[str] = "line"

    predictor: str = "quadratic"
    scenes: tuple[str, ...] = field(default=())

    @property
    def label(self) -> str:
        return continuation_method(self.predictor)

    @property
    def scene_keys(self):
        return self.scenes

    @property
    def keys(self):
        return [(s, self.backend, self.settings, self.tol, self.label) for s in self.scenes]

    def describe_limit(self, per_row):
        return f"{self.time_limit(per_row):g} s ({per_row:g} s per scene)"

    def _run(self, time_limit):
        """One row per scene, each its own solve's numbers.

        ``wall_time`` and the iterations of a row are those of the scene's own
        solve inside the line (``ContactResult.time_s``), as for a cold run;
        with ``repeat`` K the whole line is solved K times and each scene's
        times are its median over them.
        """
        warm_up(self.backend, self.settings)
        scenes = [scene_from_key(k) for k in self.scenes]
        runs = [self._line(scenes) for _ in range(max(1, self.repeat))]
        # the line solved ``repeat`` times; each scene's times the median over them
        return [repeated(rows[0], iter(rows[1:]).__next__, len(rows))
                for rows in zip(*runs)]

    def _line(self, scenes) -> list[dict]:
        from ..studies.batch import solve_many

        # one batch: the default back-end's line runs in the compiled loop; the order
        # (θ ascending on one line) is the continuation order, so this is solve_sequence
        results = solve_many(scenes, predictor=self.predictor, solver=self.backend,
                             tol=self.tol, settings=self.settings, method="globalised")
        rows = []
        for res in results:
            row = solution_row(res)
            row["continuation"] = res.extra.get("continuation", "?")  # not a store column
            # a warm start that failed and was redone cold: its work counts too
            lost = res.extra.get("discarded")
            if lost:
                row["outer_iterations"] += int(lost["outer_iterations"])
                row["inner_iterations"] += int(lost["inner_iterations"])
                row["wall_time"] += float(lost["time_s"])
                row["reason"] += f" (after a failed warm start: {lost['reason']})"
            rows.append(row)
        return rows

    def failure(self, row):
        """One failure row per scene: the line's time shared, the reason says so."""
        rows = []
        for _ in self.scenes:
            r = dict(row)
            r["wall_time"] = float(row["wall_time"]) / self.size
            r["reason"] = f"{row['reason']}, for the continuation line of {self.size} scenes"
            rows.append(r)
        return Rows(rows, complete=False)


# -- what a worker does before its first timed solve ----------------------------------
_WARM: set[tuple[str, str]] = set()
WARMUP_SCENE = {"theta": 150.0, "height": 3.0, "links": 20}


def warm_up(backend: str, settings: str) -> None:
    """One untimed solve of a small scene per (back-end, settings) and process.

    The first call of a back-end pays for importing its library, JIT and
    caches (cvxpy's first solve took 0.5 s more than its second); a benchmark
    of the solve must not charge that to the first scene of the grid.
    """
    if (backend, settings) in _WARM:
        return
    _WARM.add((backend, settings))
    from ..api import solve
    from ..problems.scenes import ActuatorScene

    try:
        solve(ActuatorScene(**WARMUP_SCENE), solver=backend, settings=settings)
    except Exception:  # noqa: BLE001 - the timed run will report it
        pass


def reference_row(scene) -> dict:
    """The reference of ``scene``: its solution row plus ``tol`` and ``check_error``."""
    from ..api import solve
    from ..model.compiled_driver import assemble_step
    from ..model.step_solver import solve_step

    res = solve(scene, solver="active-set", tol=REFERENCE_TOL, settings="high")
    tol = REFERENCE_TOL
    if not res.converged:  # round-off can stop the tightest tolerance: relax, and say so
        for tol in (1e-10, 1e-9, 1e-8):
            res = solve(scene, solver="active-set", tol=tol, settings="high")
            if res.converged:
                break
    row = solution_row(res)
    row["tol"] = tol
    # The check: the last contact step again, by Lemke on the dense condensed LCP.
    check = float("nan")
    if res.converged:
        step = assemble_step(scene.with_links(res.links).chain(), res.alpha)
        sol = solve_step(step, "lemke", "high")
        if sol.solved:
            scale = max(abs(res.total_force), scene.EI / scene.length**2)
            check = abs(float(sol.forces_upper.sum()) - res.total_force) / scale
    row["check_error"] = check
    return row
