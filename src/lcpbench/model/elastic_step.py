"""An elastic contact step handed to any back-end (step → back-end, with compliance).

The forms are :mod:`lcpbench.model.elastic`'s: QP back-ends (the banded active
set among them) get the spring form's box QP with its bands, LCP back-ends the
LCP in the reactions (dense, as for rigid walls). Both are scaled like a rigid
step (lengths by ℓ, forces by EI/ℓ²: every unknown of the QP is a length, of the
LCP a force). The answer goes back as free-node heights u and the wall
reactions (the QP's multipliers of the wall rows, or the LCP's z); lcpbench's judge
(:func:`lcpbench.model.step_solver.step_residuals`) then checks the compliant
complementarity from u alone, the same for every back-end.
"""

from __future__ import annotations

import time

import numpy as np

from ..solvers.base import BoxQP, QPWarm, Settings, Status, StepSolution
from ..solvers.lemke import too_large
from ..solvers.registry import Backend
from .elastic import elastic_qp, scaled_qp
from .formulations import heights_from_reactions, reaction_lcp


def _nan(n: int, status: Status, message: str, **kw) -> StepSolution:
    return StepSolution(np.full(n, np.nan), np.zeros(n), np.zeros(n), status, message=message,
                        **kw)


def _answer(step, u, net, res, build: float, **kw) -> StepSolution:
    """Heights u and the net wall reactions ``net`` (N, + the upper wall) as the
    back-end's upper / lower reactions."""
    up = np.isfinite(step.upper) & (u >= step.upper)
    return StepSolution(u, np.maximum(net, 0.0), np.maximum(-net, 0.0), res.status,
                        res.iterations, res.solve_time, res.setup_time, res.message,
                        active_upper=up, build_time=build, **kw)


def run_elastic_step(backend: Backend, mod, step, s: Settings, scaled: bool,
                     warm: StepSolution | None) -> StepSolution:
    """Solve the elastic ``step`` with ``backend`` (its module ``mod`` loaded)."""
    L, F = (float(step.length_scale), float(step.force_scale)) if scaled else (1.0, 1.0)
    t0 = time.perf_counter()
    if backend.form == "qp" or hasattr(mod, "solve_qp"):
        qp = elastic_qp(step, "spring")
        P, c, lo, hi, bands = scaled_qp(qp, L, F)
        qwarm = None
        if warm is not None and backend.warm_start and np.all(np.isfinite(warm.u)):
            qwarm = QPWarm(qp.start(warm.u) / L)
        build = time.perf_counter() - t0
        res = mod.solve_qp(BoxQP(P, c, lo, hi, bands=bands), s, qwarm, **backend.options)
        if not np.all(np.isfinite(res.x)):
            return _nan(step.size, res.status if res.status is not Status.SOLVED
                        else Status.FAILED, res.message, iterations=res.iterations,
                        solve_time=res.solve_time, build_time=build)
        return _answer(step, qp.heights(res.x * L), qp.reactions(res.y * F), res, build,
                       time_source=res.time_source)
    rows = int(np.count_nonzero(np.isfinite(step.upper)) + np.count_nonzero(
        np.isfinite(step.lower)))
    if backend.storage == "dense" and (why := too_large(rows)):
        return _nan(step.size, Status.FAILED, why)
    # z = R (N), w = g + R/k (mm), the LCP in the reactions (F4 with the compliances):
    # scaled to EI/ℓ² and ℓ
    form = reaction_lcp(step, scaled=False)
    M, q = form.M * (F / L), form.q / L
    z0 = None
    if warm is not None and backend.warm_start and np.all(np.isfinite(warm.u)):
        z0 = np.where(form.signs > 0, warm.forces_upper[form.nodes],
                      warm.forces_lower[form.nodes]) / F
    build = time.perf_counter() - t0
    res = mod.solve_lcp(M, q, s, z0, **backend.options)
    if not np.all(np.isfinite(res.z)):
        return _nan(step.size, res.status if res.status is not Status.SOLVED
                    else Status.FAILED, res.message, iterations=res.iterations,
                    solve_time=res.solve_time, build_time=build)
    R = np.asarray(res.z, float) * F
    net = np.zeros(step.size)
    np.add.at(net, form.nodes, form.signs * R)
    return _answer(step, heights_from_reactions(step, form, R, scaled=False), net, res, build,
                   time_source=res.extra.get("time_source", "solver"))
