"""Many scenes in one call: ``lcpbench.solve_many(scenes, tol=..., solver=...)``.

With ``continuation=True`` (default) the actuator scenes are put in an order
that continuation can use: grouped by everything but θ and h (N, ℓ, EI, w,
channel), and within a group by h, then θ (lines in θ, the closest walls
first); each group is solved in that order by
:func:`lcpbench.studies.continuation.solve_sequence`, every scene starting
from the group's answers before it, on its own line and on the neighbouring
lines (:class:`lcpbench.studies.continuation.Solved`; a scene whose warm start
fails is solved again cold). In the line kernel, a scene none of whose plane's
answers is on its line or at its θ (scattered θ and h; elastic walls of another
stiffness each a plane of its own) starts from the nearest answer of its kin, the
scenes the same but for θ, h and the walls' stiffness (:func:`_kin`; not a
channel past 180°). Other scenes (the cantilever) are solved cold.
The results come back in the caller's order, one per scene.

With the default back-end and the globalised driver, each line runs in the
compiled kernels: a line of one plane (flat walls, rigid or elastic, one wall or a
channel, no heavy load) in one call of :func:`lcpbench.model.batch_kernel.solve_line` (prediction, solve
and judge of every scene; :mod:`lcpbench.studies.batch_line`), another one scene
by scene (:mod:`lcpbench.studies.batch_compiled`: the solve kernel and the judge
kernel per scene, the checks once per batch); otherwise each scene is one
:func:`lcpbench.solve` call.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from operator import attrgetter

import numpy as np

from ..api import check_tol, solve_internal
from ..errors import ProblemError
from ..escalations import Context, escalate
from ..model.compiled import reference
from ..model.finish import finish
from ..model.judge import chain_args
from ..model.kernel_call import BAIL_REASONS, kernel_args
from ..model.result import ContactResult
from ..model.step_solver import make_step_solver
from ..plan import make_plan, refuse_untabled
from ..problems.checks import describe
from ..problems.scenes import STIFFNESS_RANGE, ActuatorScene
from ..problems.sections import SectionedScene, check_scene
from ..solvers.registry import DEFAULT, get_settings
from .batch_compiled import solve_line, takes
from .batch_line import run_line, takes_line
from .batch_result import AUTO_WHY, LINE_KERNEL, Stopped
from .continuation import PLANE_FIELDS, PREDICTORS, solve_sequence


def _group_key(scene: ActuatorScene) -> tuple:
    return (scene.links, scene.length, scene.EI, scene.weight, scene.channel)


def continuation_order(scenes: list) -> list[list[int]]:
    """Indices of ``scenes`` as lines to solve in order (actuator scenes grouped
    and sorted by h then θ); every other scene is a line of its own."""
    groups: dict[tuple, list[int]] = {}
    lines = []
    for i, s in enumerate(scenes):
        if isinstance(s, ActuatorScene) and isinstance(s.links, int):
            groups.setdefault(_group_key(s), []).append(i)
        else:
            lines.append([i])
    for idx in groups.values():
        lines.append(sorted(idx, key=lambda i: (scenes[i].height, scenes[i].theta)))
    return lines


def solve_many(scenes: Iterable, tol: float | None = None, solver="auto", *,
               continuation: bool = True, predictor: str = "adaptive",
               **solve_kw) -> list[ContactResult]:
    """Solve every scene; one :class:`ContactResult` per scene, in the caller's order.

    ``tol``, ``solver`` and ``solve_kw`` are :func:`lcpbench.solve`'s (and
    :func:`lcpbench.api.solve_internal`'s ``engine`` and ``scaled``).
    ``continuation``: start each scene from its solved neighbours (the
    globalised or Newton driver; a failed warm start is redone cold, so the answer
    is the cold one's to the tolerance); ``predictor`` as in
    :func:`~lcpbench.studies.continuation.solve_sequence` (default "adaptive").
    False: every scene cold, in the given order.
    """
    if isinstance(scenes, (str, bytes)) or not isinstance(scenes, Iterable):
        raise ProblemError(f"scenes must be a sequence of scenes, got {describe(scenes)}")
    scenes = list(scenes)
    if not isinstance(continuation, bool):
        raise ProblemError(f"continuation must be True or False, got {continuation!r}")
    kw = dict(solve_kw, tol=tol, solver=solver)
    if not continuation:
        return [solve_internal(s, **kw) for s in scenes]
    out: list[ContactResult | None] = [None] * len(scenes)
    fast = takes(solver, dict(solve_kw, tol=tol)) and predictor in PREDICTORS
    if fast:  # the checks of solve(), once for the batch
        for s in scenes:
            if type(s) is not ActuatorScene:  # (an actuator scene needs no more check
                check_scene(s)  # but its walls' tables, which solve()'s plan checks)
            elif s.wall_profile is not None or s.lower_profile is not None:
                refuse_untabled(s.chain())
        settings = solve_kw.get("settings", "default")
        fast_kw = dict(tol=get_settings(settings).driver_tol if tol is None  # as solve()
                       else check_tol(tol), max_outer=solve_kw.get("max_outer", 200),
                       settings=settings)
        make_step_solver(DEFAULT, fast_kw["settings"], True)  # validates the settings
        m = fast_kw["max_outer"]
        if isinstance(m, bool) or not (isinstance(m, int) and m >= 1):
            fast = False  # solve() names the error
    done = _rows_of_sections(scenes, out, kw, fast_kw) if fast else set()
    for line in continuation_order(scenes):
        if line[0] in done:
            continue
        line_scenes = [scenes[i] for i in line]
        if fast and all(isinstance(s, ActuatorScene) for s in line_scenes):
            planes = []
            by_plane = _planes(line_scenes)
            kin, where = _kin(line_scenes, by_plane)
            for group in _kernel_groups(line_scenes, by_plane):
                # the planes of a group in one kernel call where it takes them all
                rows = [j for plane in group for j in plane]
                got = None if len(group) < 2 else run_line(
                    [line_scenes[j] for j in rows], predictor=predictor,
                    plane=[p for p, plane in enumerate(group) for _ in plane],
                    kin=kin[rows], where=where[rows], **fast_kw)
                if got is None:
                    planes.extend(group)
                    continue
                for j, res in zip(rows, got, strict=True):
                    out[line[j]] = _kept(res, line_scenes[j], predictor, fast_kw)
            for plane in planes:
                # a plane in one kernel call where it takes it, else scene by scene
                ps = [line_scenes[j] for j in plane]
                got = run_line(ps, predictor=predictor, kin=kin[plane], where=where[plane],
                               **fast_kw)
                results = got if got is not None else solve_line(ps, predictor=predictor,
                                                                 **fast_kw)
                for j, res in zip(plane, results, strict=True):
                    out[line[j]] = _kept(res, line_scenes[j], predictor, fast_kw)
            continue
        results = solve_sequence(line_scenes, predictor=predictor, **kw)
        for i, res in zip(line, results, strict=True):
            out[i] = res
    return out  # type: ignore[return-value]  # every index was filled


#: the farthest neighbouring row :func:`neighbouring_row` hands to a refused row: every
#: section's bend angle within this many degrees of the row's (twice the loading path's
#: step, :data:`lcpbench.model.ramp.STEP_DEG`; results/row-neighbours.md audits it)…
NEIGHBOUR_DEG = 20.0
#: …and its wall height h within this many mm
NEIGHBOUR_MM = 1.0


def _rows_of_sections(scenes: list, out: list, kw: dict, fast_kw: dict) -> set[int]:
    """The rows of sections of the batch (each a line of its own, cold) in one call of the
    line kernel, each row a plane of its own (:func:`run_line`), where it takes them
    all: their results put in ``out``; a row the kernel stopped on in its cold contact
    solve goes on from that stop as :func:`lcpbench.solve` goes on from the same stop of
    the same kernel (:func:`_after_stop`: the compiled fall-back; the cold solve is not
    run twice), another stopped row is one :func:`lcpbench.solve` (``kw``). A refused
    answer goes on to its plan's escalations (:func:`_retried`) as
    :func:`lcpbench.solve`'s does, but first, where a row before it in the batch was
    solved along the loading path and is its neighbour (:func:`neighbouring_row`), SQP
    steps in the link angles from that row's answer (the escalation ``from_neighbour``).
    Only the loading path's answers serve as neighbours: a row certified cold, or by
    ``from_neighbour``, can hold another stable state than the loading path's of the rows
    near it (a review found both: a continuation from them certified 0 N where the
    path, and the energy minimum followed along the load, give 1.67 N). The rows the
    kernel refuses are those with links near the vertical, which the loading path
    reaches in 9-18 steps, a few of them by that SQP (~2 ms a row), and one SQP from a
    neighbour in ~0.7 ms. The indices solved; empty where the kernel does not take the
    rows (they are solved one by one)."""
    rows = [i for i, s in enumerate(scenes) if type(s) is SectionedScene]
    if len(rows) < 2:
        return set()
    got = run_line([scenes[i] for i in rows], plane=list(range(len(rows))), **fast_kw)
    if got is None:
        return set()
    along_path: list = []  # (row_shape, scene, result) of the rows the loading path solved
    for i, res in zip(rows, got, strict=True):
        if isinstance(res, Stopped):
            res = (solve_internal(scenes[i], **kw) if res.bail is None else
                   _after_stop(scenes[i], res.bail, **fast_kw))
        if not res.converged:
            res = _retried(res, scenes[i], neighbour=neighbouring_row(scenes[i], along_path),
                           **fast_kw)
            if res.converged and res.retried("ramped") is not None:
                along_path.append((row_shape(scenes[i]), scenes[i], res))
        out[i] = res
    return set(rows)


def neighbouring_row(row: SectionedScene, certified: list) -> ContactResult | None:
    """The answer of the nearest row of ``certified`` ((:func:`row_shape`, scene, result)
    triples, in the order they were solved) that is ``row`` but for its sections'
    bend angles and its h: each section's θ within :data:`NEIGHBOUR_DEG` of ``row``'s, of
    the same sign, and h within :data:`NEIGHBOUR_MM`; nearest by the larger of the two
    distances, each over its limit (the first certified of equals). None where no row is
    that close."""
    best, far = None, 1.0
    shape = row_shape(row)
    thetas = [a.theta for a in row.sections]
    for other, scene, res in certified:
        if abs(row.height - scene.height) > NEIGHBOUR_MM or other != shape:
            continue
        d = abs(row.height - scene.height) / NEIGHBOUR_MM
        for t, a in zip(thetas, scene.sections, strict=True):
            d = max(d, abs(t - a.theta) / NEIGHBOUR_DEG)
        if d < far or (d == far and best is None):
            best, far = res, d
    return best


def row_shape(row: SectionedScene) -> tuple:
    """What two rows of sections must share to be neighbours: everything but the
    sections' bend angles (their signs kept) and the wall height."""
    return (row.links, row.channel, row.length, row.gravity, row.friction, row.left_end,
            row.right_end, row.pull, tuple((a.theta > 0, a.length, a.EI, a.weight)
                                           for a in row.sections))


def _after_stop(scene, bail: int, *, tol: float, max_outer: int,
                settings: str) -> ContactResult:
    """The result of a row whose cold contact solve the line kernel stopped on (``bail``,
    the solve kernel's code), as :func:`lcpbench.solve` has it after the same stop of
    the same kernel from the same cold start (:func:`lcpbench.model.compiled.run_kernel`):
    the kernel's compiled fall-back (:func:`lcpbench.model.compiled.reference`; for a
    refused step, the not-converged arc), judged; the caller escalates a refusal as
    ``solve`` does (:func:`_retried`: the loading path)."""
    t0 = time.perf_counter()
    chain = scene.chain()
    got, used = reference(chain, lambda: make_step_solver(DEFAULT, settings, True),
                          BAIL_REASONS[bail], tol=tol, max_outer=max_outer,
                          method="globalised", start=None, settings=settings)
    return finish(scene, chain, got, solver=DEFAULT, method="globalised", tol=tol,
                  elapsed=time.perf_counter() - t0, settings=settings, engine=used,
                  why=AUTO_WHY, judge_args=chain_args(chain, kernel_args(chain)),
                  route=LINE_KERNEL)


def _kept(res: ContactResult | Stopped, scene: ActuatorScene, predictor: str,
          fast_kw: dict) -> ContactResult:
    """A line kernel's result of an actuator scene, as the batch keeps it: a refused
    answer escalated (:func:`_retried`); :class:`Stopped` (the kernel stopped on the
    scene, alone in its plane): the scene solved by the per-scene loop, as its plane
    would be."""
    if isinstance(res, Stopped):
        res = solve_line([scene], predictor=predictor, **fast_kw)[0]
    return res if res.converged else _retried(res, scene, **fast_kw)


def _retried(res: ContactResult, scene, *, tol: float, max_outer: int, settings: str,
             neighbour: ContactResult | None = None) -> ContactResult:
    """A kernel line's answer that the judge did not certify, as :func:`lcpbench.solve`
    treats it: the escalations its plan lists (:func:`lcpbench.plan.make_plan`, run by
    :func:`lcpbench.escalations.escalate`; ``scene``: ``res``'s), and those that start
    from ``neighbour``, a neighbouring row's answer, where one is given."""
    chain = scene.chain()
    plan = make_plan(chain, DEFAULT, "globalised", "auto", tol,
                     neighbour=neighbour is not None)
    ctx = Context(chain, lambda: make_step_solver(DEFAULT, settings, True), DEFAULT, settings,
                  "auto", tol, max_outer, "globalised", AUTO_WHY, None, neighbour)
    return escalate(res, ctx, plan.escalations)


def _kernel_groups(scenes: list, planes: list[list[int]]) -> list[list[list[int]]]:
    """``planes`` (of ``scenes``) in groups the line kernel may take in one call: those
    it takes (:func:`lcpbench.studies.batch_line.takes_line`) by whether their walls
    yield and whether they are a channel; each plane it does not take a group of its
    own."""
    groups: dict = {}
    alone = []
    for plane in planes:
        chain = scenes[plane[0]].chain()
        if takes_line(chain):
            groups.setdefault((chain.elastic_walls, chain.channel), []).append(plane)
        else:
            alone.append([plane])
    return [*groups.values(), *alone]


#: what makes two actuator scenes kin: the same scene but for θ, h and the walls'
#: stiffness (a scene that no answer of its own plane predicts starts from the nearest
#: answer of its kin, :func:`_kin`)
KIN_FIELDS = tuple(f for f in PLANE_FIELDS if f != "wall_stiffness")
#: the length of a unit of each coordinate of :func:`_kin`'s distance: θ (degrees), h
#: (mm), log10 of the walls' stiffness (N/mm²; rigid: 1e12, the top of its range)
KIN_SCALES = (30.0, 1.0, 2.0)
#: θ (degrees) past which a scene in a channel has no kin (:func:`_kin`)
KIN_THETA_MAX = 180.0


def _kin(scenes: list, planes: list[list[int]]) -> tuple[np.ndarray, np.ndarray]:
    """Each scene's kin (an index from 0; −1: none) and its coordinates (θ, h, log10 k
    over :data:`KIN_SCALES`), for the line kernel's rule 5
    (:func:`lcpbench.model.predictor_kernel.predict_start`): a scene none of whose plane's answers
    is on its line in θ or at its θ starts from the nearest answer of its kin (its own
    walls solved; only the start is shared). ``planes``: :func:`_planes` of ``scenes``
    (a plane lies in one kin). None: a scene in a channel bent past
    :data:`KIN_THETA_MAX` (it may have several stable states: a neighbour's answer can
    start it into another than its cold start reaches), and every scene where a field
    does not hash."""
    kins: dict = {}
    key = attrgetter(*KIN_FIELDS)
    kin = np.full(len(scenes), -1, np.int64)
    try:
        for plane in planes:
            kin[plane] = kins.setdefault(key(scenes[plane[0]]), len(kins))
    except TypeError:
        kin[:] = -1
    theta = np.array([s.theta for s in scenes], dtype=float)
    height = np.array([s.height for s in scenes], dtype=float)
    stiffness = np.array([s.wall_stiffness for s in scenes], dtype=float)
    kin[np.array([s.channel for s in scenes], dtype=bool) & (theta > KIN_THETA_MAX)] = -1
    where = np.column_stack((theta, height,
                             np.log10(np.minimum(stiffness, STIFFNESS_RANGE[1]))))
    return kin, where / KIN_SCALES


def _planes(scenes: list) -> list[list[int]]:
    """Indices of ``scenes`` (actuator scenes, in continuation order) by plane (the
    same scene but for θ and h), each in order. Solving them one plane after the other
    scene by scene gives the answers of solving them in the given order:
    :class:`~lcpbench.studies.continuation.Solved` predicts a scene from its own plane
    only (the line kernel also from its kin, :func:`_kin`, where its plane has no
    answer to predict it from; the planes of one call). A field that does not hash:
    one list, as given."""
    planes: dict = {}
    key = attrgetter(*PLANE_FIELDS)
    try:
        for j, s in enumerate(scenes):
            planes.setdefault(key(s), []).append(j)
    except TypeError:
        return [list(range(len(scenes)))]
    return list(planes.values())


__all__ = ["NEIGHBOUR_DEG", "NEIGHBOUR_MM", "continuation_order", "neighbouring_row", "row_shape",
           "solve_many"]
