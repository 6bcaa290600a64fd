"""The contact step handed to a back-end, and judged by lcpbench (step → back-end).

Scaling. The contact step is handed over nondimensionalised (lengths by ℓ,
forces by EI/ℓ², DESIGN.md): heights ũ = u/ℓ, reactions R̃ = R/(EI/ℓ²), so
P̃ = P ℓ/F and c̃ = c/F. ``scaled=False`` hands over the raw step (mm, N).

Residuals of a contact step (:func:`step_residuals`) are those of its LCP —
gaps g (at an elastic wall the compliant gap g + R/k, :mod:`lcpbench.model.elastic`)
and reactions R = K g + z, ``||min(g, R)||_inf``, the smallest g and R
and ``|gᵀR|`` — evaluated in O(N) from the gaps alone: the heights of nodes
with no wall row are re-solved exactly (the LCP condenses them out), and R is
minus the energy gradient, computed in factored form. Gaps are divided by ℓ
and reactions by EI/ℓ², so the numbers compare across scenes. The acceptance
rule is the solvers' one (:func:`lcpbench.solvers.judge.verdict`).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from ..linalg import banded_matvec
from ..numba_cache import kept
from ..solvers import spring_newton
from ..solvers.base import QPWarm, Settings, Status, StepSolution
from ..solvers.judge import EPS, accept_tol, requested, verdict
from ..solvers.lemke import too_large
from ..solvers.registry import DEFAULT, Backend, get_backend, get_settings
from ..solvers.runner import fallback_message
from ..thresholds import ROUNDOFF_ULPS
from .elastic import compliances
from .elastic_step import run_elastic_step
from .formulations import (  # F1 and F2, the forms the back-ends always had
    Formulation,
    gaps_answer,
    handed,
    resolve_formulation,
    run_formulation,
    step_lcp,
    step_qp,
    step_scales,
)
from .step import RESIDUALS, residuals_of

#: the LCP form is dense (:meth:`ContactStep.lcp`: H, its condensed Schur complement
#: and M, ~DENSE_COPIES n × n doubles at once); a larger step is FAILED before any
#: allocation: at n = 1e4 it took 2.6 GB and minutes, at n = 1e5 it would need 400 GB
MAX_DENSE_FORM_BYTES = 2**30
DENSE_COPIES = 5

#: a back-end's fallback with dense storage (the active set's Lemke) is run on a step
#: of at most this many free nodes: a dense pivoting step is O(n³), 0.08 s at n = 500,
#: 0.5 s at 1000, 3.5 s at 1500 and ~90 s at 4000 (one core), where the step it stands
#: in for is O(n). A larger step that the back-end cannot certify keeps its own status.
MAX_DENSE_FALLBACK = 1000


def dense_form_bytes(n: int) -> int:
    """Bytes the dense LCP form of a step with ``n`` free nodes holds at once."""
    return DENSE_COPIES * 8 * n * n


def dense_form_too_large(n: int) -> str | None:
    """Why the dense LCP form of an ``n``-node step is refused, or None."""
    need = dense_form_bytes(n)
    if need <= MAX_DENSE_FORM_BYTES:
        return None
    top = int((MAX_DENSE_FORM_BYTES / (8 * DENSE_COPIES)) ** 0.5)
    return (f"step too large for a dense LCP form: n = {n} free nodes need "
            f"{need / 2**30:.3g} GiB (limit {MAX_DENSE_FORM_BYTES / 2**30:.3g} GiB, n <= {top}); "
            f"use a banded or sparse back-end")


def _complete_heights(step, u: np.ndarray) -> np.ndarray:
    """Re-solve exactly the heights of the nodes that have no wall row.

    In increments (large N, a step with its own factor) the residual of a node that is
    at round-off (ROUNDOFF_ULPS ε of its terms) is left as it is: the re-solve holds the
    nodes at the ends of each run, and at N = 10⁵ a run of 10⁴ nodes turns
    residuals of 10⁻¹¹ N into 4·10⁻⁸ N on its end nodes (free nodes reported
    pulling, four times what the judge allows at tol 1e-9)."""
    rows = np.isfinite(step.upper) | np.isfinite(step.lower)
    F = np.flatnonzero(~rows)
    if F.size == 0:
        return u
    u = u.copy()
    grad = step.gradient(u)
    if getattr(step, "factor", None) is not None:
        grad = np.where(np.abs(grad) <= ROUNDOFF_ULPS * EPS * step.gradient_scale(u), 0.0, grad)
    u[F] -= step.solve_on(F, grad[F])
    return u


def step_residuals(step, u: np.ndarray) -> tuple[dict, np.ndarray]:
    """lcpbench's residuals of a step answer, and the reactions R = K g + z.

    Returns ``(residuals, R)``; R is the net reaction on every free node in
    newtons (positive: the upper wall pushes down), zero up to round-off on
    nodes with no wall row.
    """
    if (own := getattr(step, "compiled_residuals", None)) is not None:
        if (out := own(u)) is not None:  # model.compiled_driver
            return out
    nan = dict(zip(RESIDUALS[:4], (np.inf, -np.inf, -np.inf, np.inf), strict=True))
    if not np.all(np.isfinite(u)):
        return nan, np.full(step.size, np.nan)
    u = _complete_heights(step, np.asarray(u, dtype=float))
    R = -step.gradient(u)
    L, F = float(step.length_scale), float(step.force_scale)
    up, lo = np.isfinite(step.upper), np.isfinite(step.lower)
    # one-sided rows: R itself (a negative R is a sign error); two-sided: split
    r_up = np.where(lo, np.maximum(R, 0.0), R)[up] / F
    r_lo = np.where(up, np.maximum(-R, 0.0), -R)[lo] / F
    # the gaps; at an elastic wall the compliant gap g + R/k (model.elastic), 0 in contact
    c_up, c_lo = compliances(step)
    g_up = (step.upper[up] - u[up] + c_up[up] * np.maximum(r_up * F, 0.0)) / L
    g_lo = (u[lo] - step.lower[lo] + c_lo[lo] * np.maximum(r_lo * F, 0.0)) / L
    nat = max(np.max(np.abs(np.minimum(g_up, r_up)), initial=0.0),
              np.max(np.abs(np.minimum(g_lo, r_lo)), initial=0.0))
    size = banded_matvec(np.abs(step.bands), np.abs(u)) + np.abs(step.linear)
    return residuals_of((
        nat, min(np.min(g_up, initial=np.inf), np.min(g_lo, initial=np.inf)),
        min(np.min(r_up, initial=np.inf), np.min(r_lo, initial=np.inf)),
        abs(g_up @ r_up) + abs(g_lo @ r_lo), float(np.max(size[up | lo], initial=0.0)) / F)), R


def dense_fallback_refused(fallback: str, n: int) -> str | None:
    """Why the fallback back-end ``fallback`` is not run on a step of ``n`` free nodes
    (dense storage, ``n`` over :data:`MAX_DENSE_FALLBACK`), or None."""
    if n <= MAX_DENSE_FALLBACK or get_backend(fallback).storage != "dense":
        return None
    return (f"its fallback {fallback} is not run on n = {n} free nodes: a dense "
            f"pivoting step is O(n³) (about 0.5 s at n = 1000, 90 s at 4000), run up to "
            f"n = {MAX_DENSE_FALLBACK}")


def solve_step(step, solver: str | Backend = "auto", settings: str | Settings = "default",
               *, scaled: bool = True, warm: StepSolution | None = None,
               formulation: str | Formulation | None = None) -> StepSolution:
    """Solve one contact step with any back-end; never raises on solver trouble.

    ``formulation`` (:mod:`lcpbench.model.formulations`: a name, ``"best"`` or None)
    is the form the back-end is handed; None or the back-end's own form (F2, the box
    QP, for a QP back-end; F1, the LCP in gaps, for an LCP back-end) is today's path.
    A form with a recipe's ε (``"best"`` at ``default`` for some back-ends) hands the
    back-end that ε; the step is judged at ``settings`` all the same. ``sol.eps`` is
    the ε the back-end was handed (None: its own defaults).
    """
    backend = solver if isinstance(solver, Backend) else get_backend(solver)
    s = get_settings(settings)
    form = resolve_formulation(backend, formulation, s)
    t0 = time.perf_counter()
    if form is not None:
        sb = s if step.elastic else handed(s, form)  # elastic walls: their own forms
        out = _formulated(backend, step, sb, scaled, form)
        out.backend, out.settings, out.scaled, out.eps = backend.name, s.name, scaled, sb.eps
        out.formulation = "" if step.elastic else str(form)
        _judge_safely(step, out, s)  # the profile's judge, whatever ε the back-end had
        out.wall_time = time.perf_counter() - t0
        return out
    if backend.name == DEFAULT and (sol := _compiled_step(step, s, warm)) is not None:
        sol.backend, sol.settings, sol.scaled, sol.eps = backend.name, s.name, scaled, s.eps
        sol.status, sol.message = verdict(sol.status, sol.residuals["natural"],
                                          accept_tol(s, sol.residuals["term_size"]))
        sol.wall_time = time.perf_counter() - t0
        return sol
    try:
        sol = _run_step(backend, step, s, scaled, warm)
    except Exception as exc:
        n = step.size
        sol = StepSolution(np.full(n, np.nan), np.zeros(n), np.zeros(n), Status.FAILED,
                           message=f"{backend.name} raised {type(exc).__name__}: {exc}")
    sol.backend, sol.settings, sol.scaled, sol.eps = backend.name, s.name, scaled, s.eps
    _judge_safely(step, sol, s)
    if sol.status is not Status.SOLVED and backend.fallback:
        if refused := dense_fallback_refused(backend.fallback, step.size):
            sol.message = f"{sol.message}; {refused}" if sol.message else refused
        else:
            first = sol
            sol = solve_step(step, backend.fallback, s, scaled=scaled)
            sol.message = fallback_message(backend, first, sol)
            sol.iterations += first.iterations
            sol.solve_time += first.solve_time
            sol.backend = f"{backend.name}>{backend.fallback}"
    sol.wall_time = time.perf_counter() - t0
    return sol


_STEP_KERNEL: list = []  # the solve kernel's module, once loaded (numba_cache.use_aot empties it)


def _compiled_step(step, s: Settings, warm: StepSolution | None) -> StepSolution | None:
    """The default back-end's step in the solve kernel
    (:func:`lcpbench.model.compiled_kernel.solve_step`: the dual walk, its certificate
    and lcpbench's residuals, compiled), or None where it does not apply (a step in
    increments, joints or free nodes not consecutive) or the kernel stopped (a bail
    code): the caller runs the back-end's own call then (the same walk, handing over to
    the primal active set where it stops, :mod:`lcpbench.solvers.banded`)."""
    n = step.size
    free, base = step.free_nodes, step.base
    if (step.factor is not None or n == 0 or base.size == 0
            or not (free[-1] - free[0] == n - 1 and base[-1] - base[0] == base.size - 1)):
        return None
    k = kept(_STEP_KERNEL, "lcpbench.model.compiled_kernel", "solve_step")
    f64 = np.ascontiguousarray
    cu, cl = (f64(c, dtype=float) for c in compliances(step)) if step.elastic else (_NONE, _NONE)
    T = _no_newton(n) if step.geometric is None else f64(step.geometric[:2], dtype=float)
    w_u, w_up, w_lo, flags = _warm_args(warm, n)
    max_iter = s.max_iter if s.max_iter else 20 * n + 50
    t0 = time.perf_counter()
    code, u, r_up, r_lo, sigma, it, res, R = k.solve_step(
        f64(step.bands, dtype=float), f64(step.linear, dtype=float), f64(step.lower, dtype=float),
        f64(step.upper, dtype=float), cu, cl, f64(step.coef, dtype=float), int(base[0]),
        int(free[0]) + 1, int(step.links), f64(step.origin, dtype=float),
        f64(step.phi_origin, dtype=float), f64(step.stiffness, dtype=float),
        f64(step.rest_joint, dtype=float), f64(step.nodal_load, dtype=float), T,
        float(step.length_scale), float(step.force_scale), w_u, w_up, w_lo, flags,
        int(max_iter), float(requested(s)))
    elapsed = time.perf_counter() - t0
    if code != 0:
        return None
    return StepSolution(u, r_up, r_lo, Status.SOLVED, iterations=int(it), solve_time=elapsed,
                        active_upper=sigma > 0, active_lower=sigma < 0, time_source="wall",
                        residuals=residuals_of(res),
                        forces_net=R)


_NONE = np.zeros(0)


def _no_newton(n: int) -> np.ndarray:
    return np.zeros((2, n))


def _warm_args(warm: StepSolution | None, n: int):
    """(heights, upper set, lower set, flags) of the kernel's warm start from a step
    answer (its contact sets, else its heights)."""
    u, up, lo, flags = np.zeros(n), np.zeros(n, bool), np.zeros(n, bool), 0
    if warm is None:
        return u, up, lo, flags
    if warm.u is not None and np.size(warm.u) == n and np.all(np.isfinite(warm.u)):
        u, flags = np.ascontiguousarray(warm.u, dtype=float), flags | 1
    if warm.active_upper is not None and np.size(warm.active_upper) == n:
        up, flags = np.ascontiguousarray(warm.active_upper, dtype=bool), flags | 2
    if warm.active_lower is not None and np.size(warm.active_lower) == n:
        lo, flags = np.ascontiguousarray(warm.active_lower, dtype=bool), flags | 4
    return u, up, lo, flags


def _formulated(backend: Backend, step, s: Settings, scaled: bool,
                form: Formulation) -> StepSolution:
    """The back-end's answer in ``form`` (:func:`~.formulations.run_formulation`); a
    step with elastic walls keeps its own forms, a dense form its size limit."""
    n = step.size
    try:
        if step.elastic:
            return run_elastic_step(backend, backend.load(), step, s, scaled, None)
        if form.name in ("gaps", "reactions", "angles") and (why := dense_form_too_large(n)):
            return StepSolution(np.full(n, np.nan), np.zeros(n), np.zeros(n), Status.FAILED,
                                message=why)
        return run_formulation(backend, step, s, form, scaled)
    except Exception as exc:
        return StepSolution(np.full(n, np.nan), np.zeros(n), np.zeros(n), Status.FAILED,
                            message=f"{backend.name} ({form}) raised "
                                    f"{type(exc).__name__}: {exc}")


def _judge_safely(step, sol: StepSolution, s: Settings) -> None:
    try:
        _judge(step, sol, s)
    except np.linalg.LinAlgError as exc:  # the residuals' own solve: H not positive definite
        sol.status = Status.FAILED
        sol.message = f"lcpbench's residuals could not be computed ({exc})"


def _judge(step, sol: StepSolution, s: Settings) -> None:
    res, R = step_residuals(step, sol.u)
    sol.residuals, sol.forces_net = res, R
    status, why = verdict(sol.status, res["natural"], accept_tol(s, res.get("term_size", 0.0)))
    if why:
        sol.status, sol.message = status, why


def _run_step(backend: Backend, step, s: Settings, scaled: bool, warm) -> StepSolution:
    mod = backend.load()
    n = step.size
    if step.elastic and backend.name == DEFAULT and spring_newton.takes(step):
        return spring_newton.solve_step(step, warm)  # in increments (large N)
    if step.elastic:
        return run_elastic_step(backend, mod, step, s, scaled, warm)
    if hasattr(mod, "solve_step"):
        return mod.solve_step(step, s, warm, **backend.options)
    L, F = step_scales(step, scaled)
    if backend.form == "qp":
        t0 = time.perf_counter()
        qp = step_qp(step, scaled)
        build = time.perf_counter() - t0
        qwarm = None
        if warm is not None and backend.warm_start and np.all(np.isfinite(warm.u)):
            qwarm = QPWarm(warm.u / L, (warm.forces_upper - warm.forces_lower) / F)
        res = mod.solve_qp(qp, s, qwarm, **backend.options)
        y = res.y * F
        return StepSolution(res.x * L, np.maximum(y, 0.0), np.maximum(-y, 0.0), res.status,
                            res.iterations, res.solve_time, res.setup_time, res.message,
                            time_source=res.time_source, build_time=build)
    if (why := dense_form_too_large(n)) or (backend.storage == "dense"
                                            and (why := too_large(n))):  # before M is formed
        return StepSolution(np.full(n, np.nan), np.zeros(n), np.zeros(n), Status.FAILED,
                            message=why)
    t0 = time.perf_counter()
    form, M, q, dz, dw = step_lcp(step, scaled)
    build = time.perf_counter() - t0
    z0 = None
    if warm is not None and backend.warm_start and np.all(np.isfinite(warm.u)):
        gaps = form.heights - warm.u[form.rows]
        z0 = np.concatenate([gaps, warm.forces_lower[form.rows]])[: q.size] / dz
        z0 = np.maximum(z0, 0.0)
    res = mod.solve_lcp(M, q, s, z0, **backend.options)
    if not np.all(np.isfinite(res.z)):
        return StepSolution(np.full(n, np.nan), np.zeros(n), np.zeros(n),
                            res.status if res.status is not Status.SOLVED else Status.FAILED,
                            res.iterations, res.solve_time, res.setup_time, res.message,
                            build_time=build)
    z, w = res.z * dz, res.w * dw
    u, r_up, r_lo = gaps_answer(step, form, z, w)
    m = form.n_gap
    upper = np.zeros(n, bool)
    upper[form.rows] = z[:m] <= 0.0
    return StepSolution(u, r_up, r_lo, res.status, res.iterations, res.solve_time,
                        res.setup_time, res.message, active_upper=upper,
                        time_source=res.extra.get("time_source", "solver"), build_time=build)


def make_step_solver(solver: str = "auto", settings: str | Settings = "default",
                     scaled: bool = True,
                     formulation: str | Formulation | None = None) -> Callable:
    """A ``(step, warm) -> StepSolution`` callable for the driver (``formulation``: as
    :func:`solve_step`, resolved once here)."""
    backend = get_backend(solver)
    s = get_settings(settings)
    form = resolve_formulation(backend, formulation, s)

    def run(step, warm):
        return solve_step(step, backend, s, scaled=scaled, warm=warm, formulation=form)

    run.backend = backend  # type: ignore[attr-defined]  # read by the harness
    run.scaled = scaled  # type: ignore[attr-defined]  # model.compiled_driver.takes
    run.formulation = None if form is None else str(form)  # type: ignore[attr-defined]
    return run
