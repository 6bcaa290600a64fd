"""The contact result and its certificate, judged on the exact nonlinear geometry."""

from __future__ import annotations

from dataclasses import MISSING, asdict, dataclass, field, fields, is_dataclass
from typing import Any, NamedTuple

import numpy as np

from ..problems.scenes import Chain
from .chain import joint_angles, node_positions, torque_residual
from .elastic import compliances, wall_pressure
from .judge import Certificate, Judgement, judge  # noqa: F401 (Certificate: public here)
from .outer import DriverOutput, StepRecord
from .profile import joint_moments_xy, profile_gaps, wall_forces_xy


def certify(chain: Chain, alpha: np.ndarray, upper: np.ndarray, lower: np.ndarray) -> Certificate:
    """The certificate of link angles ``alpha`` with wall reactions ``upper``, ``lower`` (N)."""
    x, y = node_positions(chain, alpha)
    yf = y[chain.free_nodes]
    profile = chain.profiled_walls
    gaps = [chain.wall - yf] if np.isfinite(chain.wall) else []
    if profile:  # exact gaps h(x_k) − y_k at the nodes' x
        g_up, g_lo = profile_gaps(chain, alpha)
        gaps = [g_up] if g_lo is None else [g_up, g_lo]
    forces = [upper]
    if chain.channel:
        if not profile:
            gaps.append(yf + chain.wall)
        forces.append(lower)
    gap = np.concatenate(gaps) if gaps else np.array([np.inf])
    force = np.concatenate(forces)
    if gaps and chain.elastic_walls:
        # elastic walls: the compliant gap g + R/k (model.elastic); the node indents by R/k
        c_up, c_lo = compliances(chain)
        comp_ = np.concatenate([c_up, c_lo] if chain.channel else [c_up])
        gap = gap + comp_ * np.maximum(force, 0.0)
    comp = float(np.max(np.abs(gap * force), initial=0.0)) if gaps else 0.0
    closure = abs(float(y[-1])) if chain.free_nodes[-1] < chain.links else 0.0
    if profile:  # the reactions are normal to the wall: μ (h', −1), ν (−l', 1)
        fx, fy = wall_forces_xy(chain, alpha, upper, lower)
        res = chain.joint_stiffness * (joint_angles(chain, alpha) - chain.rest_joint) \
            - joint_moments_xy(chain, alpha, fx, fy)
    else:
        res = torque_residual(chain, alpha, lower - upper)
    spring = chain.joint_stiffness * np.abs(joint_angles(chain, alpha) - chain.rest_joint)
    worst = float(np.max(np.abs(res), initial=0.0))
    # over the largest spring torque, but never less than the chain's own scale EI/ℓ
    ref = max(float(np.max(spring, initial=0.0)), chain.force_scale * chain.length)
    return Certificate(
        min_gap=float(np.min(gap)),
        min_force=float(np.min(force, initial=0.0)),
        complementarity=comp,
        closure=closure,
        torque_residual=res,
        max_torque_residual=worst,
        relative_torque_residual=worst / ref,
    )


class Retry(NamedTuple):
    """One escalation that ran on a refused answer (:mod:`lcpbench.escalations`): its
    name in :data:`lcpbench.escalations.ESCALATIONS` and one line on why it ran and
    what came of it."""

    name: str
    why: str


class ReachedState(NamedTuple):
    """A distinct stable state (certified by the judge, the second-order check included)
    that one of the solve's starts reached: which start ("escape": a restart downhill
    of a saddle; "loading path": the bend angles grown from zero), its exact energy
    E(α) (N·mm, :func:`lcpbench.model.chain.energy`: springs, the loads' work and
    elastic walls), its total force F (N), whether it is the answer returned, and its
    link angles α (rad; a start for :func:`lcpbench.solve` of that state)."""

    start: str
    energy: float
    total_force: float
    answer: bool
    alpha: np.ndarray


@dataclass
class ContactResult:
    """The equilibrium of a scene: shape, gaps, forces and how it was found.

    Per-node arrays (gaps, forces) run over the free nodes: the interior
    nodes 2..N for the actuator, 2..N+1 for the cantilever.

    Attributes
    ----------
    x, y : node coordinates (mm), nodes 1..N+1.
    alpha : link angles (rad).
    gaps : distance of each free node below the upper wall, h − y (mm).
    forces : the reaction R of eq. (30): the upper wall's force on each free
        node (N, >= 0, pushing away from the wall). lcpbench's one name for R
        (``forces_upper`` in the step and driver types). Computed by lcpbench
        as R = K g + z from the last step's primal gaps, whichever back-end
        solved it; the back-end's own multipliers are ``multipliers``.
    gaps_lower, forces_lower : the same for the lower wall of a channel (else None).
    total_force : F = ΣR, the sum of ``forces`` (N): the upper wall's, the paper's
        load cell (in a channel too).
    total_force_lower : the lower wall's ΣR in a channel (N), else None.
    outer_iterations : contact steps taken.
    steps : per-step inner statistics.
    converged, reason : whether lcpbench's judge accepts the answer
        (:mod:`lcpbench.model.judge`: the driver's criterion, every step
        solved, signs, complementarity, geometry, and a force error bound
        within min(1e-3, 100·tol)), and why not.
    certificate : :class:`Certificate` from the exact geometry.
    multipliers, multipliers_lower : the back-end's own reactions of the last
        step (N), for comparison only (None when no step was solved).
    judgement : the :class:`~lcpbench.model.judge.Judgement` behind ``converged``;
        ``force_error_bound`` is its bound on the relative error of F.
    indentation : per free node, the depth (mm) by which it indents an elastic
        wall (0 at a rigid wall); ``max_indentation`` its largest.
    pressure : per free node, the contact pressure per length p = R / share (N/mm),
        the reaction over the node's share of wall length; ``max_pressure`` its
        largest (:func:`lcpbench.model.elastic.wall_pressure`).
    pressure_limit, pressure_exceeded : the safety threshold asked for (N/mm, None:
        none) and whether ``max_pressure`` passes it.
    solver, method, tol, time_s : how it was computed; wall time of the solve (s).
    eps : the tolerance ε lcpbench handed the back-end in every step: the profile's,
        or the ``formulation="best"`` recipe's where it gives one (at ``default``:
        OSQP's and SCS's, docs/formulations.md); None: the back-end's own defaults
        (``default``), or a bare :func:`~lcpbench.model.finish.finish`. Each back-end
        translates ε into its own parameters (docs/solvers.md, settings profiles).
    route : the plan's route, the first solve (:data:`lcpbench.plan.ROUTES`; a batch's
        "line kernel" or "batch scene"); "" where no plan was made (a bare
        :func:`lcpbench.model.finish.finish`).
    engine : what produced the answer returned
        (:data:`lcpbench.model.compiled.ENGINES_RUN`): "compiled" (the solve kernel),
        "compiled driver" (another back-end, the driver around it compiled),
        "increments driver" (large N: the loop in Python, its steps on the
        tridiagonal factor compiled) or "compiled SQP" (a heavy chain's SQP steps),
        with why in parentheses where it was not the plan's ("increments driver (large
        N: ...)", "compiled driver (the kernel stopped: ...)").
    judge : where the result judge took its exact steps: "heights" (the judge
        kernel) or "increments" (from ``LARGE_N`` links: the same kernel, its steps in
        increments, :func:`lcpbench.model.judge_exact_kernel.increments_step`).
    retries : the escalations that ran after the route, in order
        (:class:`Retry`: name and why); () where the first answer was kept.
    states : where the solve's starts reached more than one distinct stable state
        (the restarts of ``escaped`` and the loading path it then follows), each of
        them (:class:`ReachedState`), lowest energy first, the answer's marked;
        () where the solve reached one. Not a search for every state:
        :func:`lcpbench.stable_states` solves the cold start and the loading path.
    """

    scene: object
    links: int
    x: np.ndarray
    y: np.ndarray
    alpha: np.ndarray
    gaps: np.ndarray
    forces: np.ndarray
    gaps_lower: np.ndarray | None
    forces_lower: np.ndarray | None
    total_force: float
    outer_iterations: int
    steps: list[StepRecord]
    converged: bool
    reason: str
    certificate: Certificate
    solver: str
    method: str
    tol: float
    time_s: float = 0.0
    extra: dict = field(default_factory=dict)
    multipliers: np.ndarray | None = None
    multipliers_lower: np.ndarray | None = None
    judgement: Judgement | None = None
    #: 0-based indices into ``x``, ``y`` of the nodes of ``forces`` and ``gaps``
    free_nodes: np.ndarray | None = None
    indentation: np.ndarray | None = None
    pressure: np.ndarray | None = None
    pressure_limit: float | None = None
    route: str = ""
    engine: str = ""
    judge: str = ""
    retries: tuple[Retry, ...] = ()
    states: tuple[ReachedState, ...] = ()
    eps: float | None = None

    def __getstate__(self) -> dict:
        """Pickled (and copied) with every derived field computed (``DERIVED``)."""
        if "_derive_from" in self.__dict__:
            _derive(self)
        return dict(self.__dict__)

    @property
    def total_force_lower(self) -> float | None:
        """The lower wall's total force ΣR in a channel (N); None with one wall."""
        return None if self.forces_lower is None else float(np.sum(self.forces_lower))

    @property
    def max_indentation(self) -> float:
        """Largest indentation of an elastic wall (mm); 0 for rigid walls."""
        return float(np.max(self.indentation, initial=0.0)) if self.indentation is not None \
            else 0.0

    @property
    def max_pressure(self) -> float:
        """Largest contact pressure per length (N/mm)."""
        return float(np.max(self.pressure, initial=0.0)) if self.pressure is not None else 0.0

    @property
    def pressure_exceeded(self) -> bool:
        """Whether ``max_pressure`` passes the safety threshold ``pressure_limit``."""
        return self.pressure_limit is not None and self.max_pressure > self.pressure_limit

    @property
    def force_error_bound(self) -> float:
        """lcpbench's a-posteriori bound on the error of ``total_force``, relative to
        max(|F|, EI/ℓ²) (:mod:`lcpbench.model.judge`); NaN if not judged that far."""
        return self.judgement.force_error_bound if self.judgement else float("nan")

    def retried(self, name: str) -> str | None:
        """The why of escalation ``name`` where it ran (the last time), else None."""
        return next((r.why for r in reversed(self.retries) if r.name == name), None)

    def __repr__(self) -> str:
        return (f"ContactResult(N={self.links}, F={1e3 * self.total_force:.6g} mN on "
                f"{self.contact_nodes.size} contact nodes, converged={self.converged}, "
                f"force_error_bound={self.force_error_bound:.1e}, solver={self.solver!r}, "
                f"outer={self.outer_iterations}, time={1e3 * self.time_s:.3g} ms, "
                f"reason={self.reason!r})")

    def summary(self) -> str:
        """A few lines of text: scene, verdict, F and the contact nodes, the judge's
        force error bound, the certificate and what it cost."""
        from .result_view import summary_text

        return summary_text(self)

    def _repr_html_(self) -> str:
        from .result_view import summary_html

        return summary_html(self)

    def nodes(self, *, frame: bool | None = None):
        """A tidy table, one row per free node: node number i, x, y (mm), gap h − y
        (mm), reaction R (N), contact (and the lower wall's gap and reaction in a
        channel). A pandas DataFrame indexed by node when pandas is installed (or
        ``frame=True``), else (or ``frame=False``) a dict of numpy columns."""
        from .result_view import node_table

        return node_table(self, frame=frame)

    @property
    def inner_iterations(self) -> int:
        return int(sum(s.iterations for s in self.steps))

    @property
    def span(self) -> float:
        """x-distance between the two ends (mm)."""
        return float(self.x[-1] - self.x[0])

    @property
    def contact_nodes(self) -> np.ndarray:
        """Free-node indices whose upper-wall reaction exceeds the judge's contact
        threshold, NODE_SHARE·τ·F₀ (below it a reaction is below the accuracy asked
        for, :mod:`lcpbench.model.judge`)."""
        eps = self.judgement.contact_threshold if self.judgement else 0.0
        return np.flatnonzero(self.forces > eps)

    def to_dict(self) -> dict:
        """A JSON-ready summary (the fields of ``lcpbench solve --json``)."""
        scene = asdict(self.scene) if is_dataclass(self.scene) and not isinstance(
            self.scene, type) else {}
        if scene.get("wall_stiffness", 0.0) == np.inf:  # rigid: the key of old outputs
            scene.pop("wall_stiffness")
        for key in ("wall_profile", "lower_profile"):  # flat walls: the JSON as before
            if key in scene and scene[key] is None:
                del scene[key]
            elif key in scene:  # a WallProfile: its name and x range
                scene[key] = getattr(self.scene, key).to_dict()
        if not getattr(self.scene, "frictional", True):  # (issue 39) the JSON as before
            for key in ("friction", "left_end", "right_end", "pull"):
                scene.pop(key, None)
        out = {
            "scene": {**scene, "links": self.links},
            "total_force": self.total_force,
            "forces": self.forces.tolist(),
            "gaps": self.gaps.tolist(),
            "x": self.x.tolist(),
            "y": self.y.tolist(),
            "alpha": self.alpha.tolist(),
            "converged": self.converged,
            "reason": self.reason,
            "outer_iterations": self.outer_iterations,
            "inner_iterations": self.inner_iterations,
            "steps": [asdict(s) for s in self.steps],
            "solver": self.solver,
            "method": self.method,
            "tol": self.tol,
            "time_s": self.time_s,
            "certificate": self.certificate.to_dict(),
            "force_error_bound": self.force_error_bound,
            "judgement": self.judgement.to_dict() if self.judgement else None,
            "multipliers": None if self.multipliers is None else self.multipliers.tolist(),
            "max_indentation": self.max_indentation,
            "max_pressure": self.max_pressure,
            "pressure_limit": self.pressure_limit,
            "pressure_exceeded": self.pressure_exceeded,
            # what ran (lcpbench.plan): the route, the engine, the judge, the escalations
            "route": self.route,
            "engine": self.engine,
            "judge": self.judge,
            "retries": [{"name": r.name, "why": r.why} for r in self.retries],
            "states": [{**s._asdict(), "alpha": s.alpha.tolist()} for s in self.states],
            "eps": self.eps,
        }
        if "formulation" in self.extra:  # the step's form, when one was asked for
            out["formulation"] = self.extra["formulation"]
        if self.indentation is not None and self.pressure is not None:
            out["indentation"] = self.indentation.tolist()
            out["pressure"] = self.pressure.tolist()
        if self.forces_lower is not None and self.gaps_lower is not None:
            out["forces_lower"] = self.forces_lower.tolist()
            out["gaps_lower"] = self.gaps_lower.tolist()
            out["total_force_lower"] = self.total_force_lower
        return out


#: The fields of :class:`ContactResult` derived from the answer (the node
#: positions by forward kinematics, the gaps, the wall pressure): computed at
#: their first access, all at once, by the same functions as before.
DERIVED = ("x", "y", "gaps", "gaps_lower", "indentation", "pressure")
_PENDING: Any = object()  # a derived field not computed yet (typed Any: it stands in for arrays)


class _Derived:
    """A field of :class:`ContactResult` computed on first access (``DERIVED``)."""

    def __init__(self, name: str):
        self.name = name

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        value = obj.__dict__[self.name]
        if value is _PENDING:
            _derive(obj)
            value = obj.__dict__[self.name]
        return value

    def __set__(self, obj, value) -> None:
        obj.__dict__[self.name] = value


def _derive(res: ContactResult) -> None:
    """Fill the derived fields still pending, from the chain and answer kept with
    the result (:func:`build_result`)."""
    d = res.__dict__
    source = d.get("_derive_from")
    if source is None:  # another thread derived them meanwhile
        return
    chain, alpha, upper, lower = source
    x, y = node_positions(chain, alpha)
    yf = y[chain.free_nodes]
    gaps, gaps_lower = chain.wall - yf, (yf + chain.wall if chain.channel else None)
    if chain.profiled_walls:
        gaps, gaps_lower = profile_gaps(chain, alpha)
    depth, pressure = wall_pressure(chain, yf, upper, lower if chain.channel else None)
    values = dict(x=x, y=y, gaps=gaps, gaps_lower=gaps_lower, indentation=depth,
                  pressure=pressure)
    for name in DERIVED:
        if d[name] is _PENDING:  # a field set by hand in between keeps its value
            d[name] = values[name]
    d.pop("_derive_from", None)


for _name in DERIVED:
    setattr(ContactResult, _name, _Derived(_name))


def build_result(scene, chain: Chain, out: DriverOutput, *, judged_by=judge,
                 **how) -> ContactResult:
    """The result of a driver run, judged by :func:`lcpbench.model.judge.judge`
    (``judged_by``: a judgement made already, with the same arguments, e.g.
    :func:`lcpbench.model.lazy_result.stats_judge`). The fields in
    :data:`DERIVED` are computed at their first access."""
    verdict = judged_by(chain, out.alpha, out.forces_upper, out.forces_lower, tol=how["tol"],
                        driver_converged=out.converged, driver_reason=out.reason,
                        step_statuses=[s.status for s in out.steps],
                        step_sizes=[s.max_dalpha for s in out.steps],
                        certificate=lambda up, lo: certify(chain, out.alpha, up, lo))
    if verdict.forces_upper is not None and verdict.forces_lower is not None:
        # R with its round-off set to zero (the certificate is of these)
        out.forces_upper, out.forces_lower = verdict.forces_upper, verdict.forces_lower
    channel = chain.channel
    return new_result(dict(
        scene=scene,
        links=chain.links,
        x=_PENDING,
        y=_PENDING,
        alpha=out.alpha,
        gaps=_PENDING,
        forces=out.forces_upper,
        gaps_lower=_PENDING,
        forces_lower=out.forces_lower if channel else None,
        total_force=float(_add_reduce(out.forces_upper)),  # ndarray.sum, without its wrapper
        outer_iterations=len(out.steps),
        steps=out.steps,
        converged=verdict.converged,
        reason=verdict.reason,
        certificate=verdict.certificate,
        multipliers=out.multipliers_upper,
        multipliers_lower=out.multipliers_lower if channel else None,
        judgement=verdict,
        free_nodes=np.array(chain.free_nodes, dtype=int),
        indentation=_PENDING,
        pressure=_PENDING,
        _derive_from=(chain, out.alpha, out.forces_upper, out.forces_lower),
        **how,
    ))


_add_reduce = np.add.reduce


def _field_defaults() -> tuple[dict, tuple]:
    """ContactResult's plain defaults and its fields with a default factory."""
    plain, made = {}, []
    for f in fields(ContactResult):
        if f.default is not MISSING:
            plain[f.name] = f.default
        elif f.default_factory is not MISSING:
            made.append((f.name, f.default_factory))
    return plain, tuple(made)


_DEFAULTS, _FACTORIES = _field_defaults()
_FIELDS = frozenset(f.name for f in fields(ContactResult))


def new_result(values: dict) -> ContactResult:
    """``ContactResult(**values)`` with every field set at once (what the dataclass's
    ``__init__`` does one attribute at a time; the result of every solve is built
    here). ``values`` may hold ``_derive_from`` (see :data:`DERIVED`); a field it
    lacks takes its default, as in the constructor (TypeError: a field without one)."""
    res = object.__new__(ContactResult)
    d = res.__dict__
    d.update(_DEFAULTS)
    for name, make in _FACTORIES:
        d[name] = make()
    d.update(values)
    if len(d) != len(_FIELDS) + ("_derive_from" in d):  # (one test, not per field)
        wrong = sorted(_FIELDS.symmetric_difference(d.keys() - {"_derive_from"}))
        raise TypeError(f"ContactResult fields missing or unknown: {wrong}")
    return res
