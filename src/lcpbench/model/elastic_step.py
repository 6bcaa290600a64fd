"""An elastic contact step handed to any back-end (step → back-end, with compliance).

The forms are :mod:`lcpbench.model.elastic`'s: QP back-ends (the banded active
set among them) get the box QP in x = (v, δ) with its bands, LCP back-ends its
standard LCP (dense, as for rigid walls). Both are scaled like a rigid step
(lengths by ℓ, forces by EI/ℓ²; every unknown of x is a length). The answer
goes back as free-node heights u = v + δ⁺ − δ⁻ and the multipliers of the v
rows (the wall reactions R = k δ); lcpbench's judge
(:func:`lcpbench.model.step_solver.step_residuals`) then checks the compliant
complementarity from u alone, the same for every back-end.
"""

from __future__ import annotations

import time

import numpy as np

from ..solvers.base import BoxQP, QPWarm, Settings, Status, StepSolution
from ..solvers.lemke import too_large
from ..solvers.registry import Backend
from .elastic import box_lcp, elastic_qp, lcp_solution, scaled_qp


def _nan(n: int, status: Status, message: str, **kw) -> StepSolution:
    return StepSolution(np.full(n, np.nan), np.zeros(n), np.zeros(n), status, message=message,
                        **kw)


def _answer(step, qp, x, y, res, build: float, **kw) -> StepSolution:
    """Heights u = E x and the wall rows' multipliers as upper / lower reactions (N)."""
    u = qp.heights(x)
    net = qp.reactions(y)
    up = np.isfinite(step.upper) & (u >= step.upper)
    return StepSolution(u, np.maximum(net, 0.0), np.maximum(-net, 0.0), res.status,
                        res.iterations, res.solve_time, res.setup_time, res.message,
                        active_upper=up, build_time=build, **kw)


def run_elastic_step(backend: Backend, mod, step, s: Settings, scaled: bool,
                     warm: StepSolution | None) -> StepSolution:
    """Solve the elastic ``step`` with ``backend`` (its module ``mod`` loaded)."""
    L, F = (float(step.length_scale), float(step.force_scale)) if scaled else (1.0, 1.0)
    t0 = time.perf_counter()
    use_qp = backend.form == "qp" or hasattr(mod, "solve_qp")
    qp = elastic_qp(step, "spring" if use_qp else "split")
    P, c, lo, hi, bands = scaled_qp(qp, L, F)
    start = None
    if warm is not None and backend.warm_start and np.all(np.isfinite(warm.u)):
        start = qp.start(warm.u) / L
    if use_qp:
        build = time.perf_counter() - t0
        qwarm = QPWarm(start) if start is not None else None
        res = mod.solve_qp(BoxQP(P, c, lo, hi, bands=bands), s, qwarm, **backend.options)
        if not np.all(np.isfinite(res.x)):
            return _nan(step.size, res.status if res.status is not Status.SOLVED
                        else Status.FAILED, res.message, iterations=res.iterations,
                        solve_time=res.solve_time, build_time=build)
        return _answer(step, qp, res.x * L, res.y * F, res, build,
                       time_source=res.time_source)
    if backend.storage == "dense" and (why := too_large(qp.size)):
        return _nan(step.size, Status.FAILED, why)
    Pd = P.toarray()
    form = box_lcp(Pd, c, lo, hi)  # of the scaled QP: z, w in its units
    build = time.perf_counter() - t0
    z0 = None
    if start is not None:
        m = form.n_gap
        z0 = np.zeros(form.q.size)
        z0[:m] = np.maximum(form.sign * (start[form.rows] - form.base), 0.0)
    res = mod.solve_lcp(form.M, form.q, s, z0, **backend.options)
    if not np.all(np.isfinite(res.z)):
        return _nan(step.size, res.status if res.status is not Status.SOLVED
                    else Status.FAILED, res.message, iterations=res.iterations,
                    solve_time=res.solve_time, build_time=build)
    x, y = lcp_solution(Pd, c, form, np.asarray(res.z, float))
    return _answer(step, qp, x * L, y * F, res, build,
                   time_source=res.extra.get("time_source", "solver"))
