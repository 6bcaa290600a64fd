"""The frictional contact step handed to a back-end by name (issue 39, docs/friction.md).

Each back-end's registry record says how it takes the step
(:attr:`lcpbench.solvers.registry.Backend.friction_form`):

- "lcp": the Stewart–Trinkle LCP w = M z + q in z = (N, β⁺, β⁻, λ)
  (:func:`lcpbench.model.friction_step.frictional_lcp`): ``lemke`` (with the step's
  pivot tolerance and covering vectors, one :class:`~.friction_driver.StepLemke` per
  runner, as a path's default) and any LCP back-end's ``solve_lcp``;
- "fc2d": the Delassus form u = W r + q per wall row (:func:`fc2d_contacts`): Siconos'
  fc2d solvers (:mod:`lcpbench.solvers.siconos_fc2d`) and lcpbench's active set on the
  stick/slide/separate states (``active-set``, :mod:`lcpbench.solvers.fc2d_active`);
- "tresca": the fixed point of Tresca box QPs (:mod:`lcpbench.solvers.fc2d_tresca`) on
  any QP back-end.

Whatever the form, the answer comes back as the LCP's z and is judged the same way
(:func:`judged`): SOLVED only when the back-end said so and the LCP's scaled natural
residual, recomputed by lcpbench, is at most :data:`STEP_TOL` (Lemke's own bound).
"""

from __future__ import annotations

import time

import numpy as np

from ..errors import ProblemError
from ..solvers.base import LCPSolution, Settings, Status, lcp_residuals
from ..solvers.lemke import RESIDUAL_TOL
from ..solvers.registry import FRICTION_FORMS, backends, get_backend
from .friction_driver import StepLemke
from .friction_lemke import polish_step

#: the largest scaled natural residual of the step's LCP accepted as SOLVED (Lemke's)
STEP_TOL = RESIDUAL_TOL
#: Siconos' fc2d method of each Siconos back-end whose frictional form is "fc2d"
FC2D_METHODS = {"lemke": "lemke", "enum": "enum", "pgs": "nsgs"}
#: the most contacts handed to Siconos' fc2d enumeration (4^n states: on random problems
#: 6 contacts took 1.7 s, 8 took 115 s)
FC2D_ENUM_MAX = 6
#: the settings of the QP back-ends in the Tresca fixed point and of the LCP
#: back-ends: ε = 1e-12. The step's Delassus matrix is stiff (a chain in contact), so
#: a residual of 1e-9 leaves errors of 1e-4 in the forces (ProxSuite, OSQP on a
#: step at N = 60); at 1e-12 ProxSuite agrees with Lemke to 1e-6 there
STEP_SETTINGS = Settings("friction step", 1e-12, driver_tol=1e-9)
#: the default solver of the frictional step
DEFAULT = "lemke"


def friction_backends() -> dict[str, str]:
    """Every installed back-end that takes the frictional step, and its form."""
    return {name: b.friction_form for name, b in backends().items()
            if b.friction_form and b.available()}


def fc2d_contacts(fs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(W, q, μ) of the step ``fs`` in Siconos' fc2d form, dimensionless: one contact
    per wall row r, u = (g_r, s_p), r = (N_r, T_p) with p its friction pair. A row
    without a pair gets a tangential direction of its own that nothing moves
    (W 1 on its diagonal, q 0) and μ = 0, so its T is 0. Each pair must belong to one
    row (ProblemError otherwise)."""
    mn, mt = fs.normal_node.size, fs.friction_node.size
    pairs = fs.pair[fs.pair >= 0]
    if np.unique(pairs).size != pairs.size or pairs.size != mt:
        raise ProblemError("the fc2d form needs each friction pair on exactly one wall row")
    scale = fs.force / fs.length
    W = np.zeros((2 * mn, 2 * mn))
    q = np.zeros(2 * mn)
    src = np.where(fs.pair >= 0, mn + fs.pair, -1)
    n_idx, t_idx = 2 * np.arange(mn), 2 * np.arange(mn) + 1
    has = src >= 0
    W[np.ix_(n_idx, n_idx)] = fs.W[:mn, :mn] * scale
    W[np.ix_(n_idx, t_idx[has])] = fs.W[:mn][:, src[has]] * scale
    W[np.ix_(t_idx[has], n_idx)] = fs.W[src[has]][:, :mn] * scale
    W[np.ix_(t_idx[has], t_idx[has])] = fs.W[np.ix_(src[has], src[has])] * scale
    W[t_idx[~has], t_idx[~has]] = 1.0
    q[n_idx] = fs.g_f / fs.length
    q[t_idx[has]] = fs.s_f[fs.pair[has]] / fs.length
    mu = np.where(has, fs.mu, 0.0)
    return W, q, mu


def lcp_z(fs, r: np.ndarray) -> np.ndarray:
    """The LCP's z = (N, β⁺, β⁻, λ) of an fc2d answer r (dimensionless): N = max(r_n, 0),
    β± the positive and negative parts of T, λ = |s| the slip's size
    (s = s_f + W_tn N + W_tt T recomputed)."""
    mn, mt = fs.normal_node.size, fs.friction_node.size
    N = np.maximum(r[0::2], 0.0)
    T = np.zeros(mt)
    has = fs.pair >= 0
    T[fs.pair[has]] = r[1::2][has]
    scale = fs.force / fs.length
    s = (fs.s_f / fs.length + scale * (fs.W[mn:, :mn] @ N + fs.W[mn:, mn:] @ T)
         if mt else np.zeros(0))
    return np.concatenate([N, np.maximum(T, 0.0), np.maximum(-T, 0.0), np.abs(s)])


def judged(fs, sol: LCPSolution) -> LCPSolution:
    """``sol`` with lcpbench's verdict: SOLVED stays SOLVED only when the step's LCP
    natural residual (recomputed, scaled by max(1, |q|)) is at most :data:`STEP_TOL`;
    never raised to SOLVED."""
    if not np.all(np.isfinite(sol.z)):
        if sol.solved:
            sol.status, sol.message = Status.FAILED, "answer not finite"
        return sol
    res = lcp_residuals(fs.M, fs.q, sol.z)
    sol.extra["residuals"] = res
    if sol.solved and res["natural"] > STEP_TOL:
        sol.status = Status.INACCURATE
        sol.message = (f"lcpbench's natural residual {res['natural']:.3g} > {STEP_TOL:g} "
                       f"({sol.message})" if sol.message else
                       f"lcpbench's natural residual {res['natural']:.3g} > {STEP_TOL:g}")
    return sol


def from_fc2d(fs, peer, t0: float) -> LCPSolution:
    """The LCP solution of an fc2d answer ``peer`` (an FC2DSolution), judged."""
    z = lcp_z(fs, peer.r) if np.all(np.isfinite(peer.r)) else np.full(fs.q.size, np.nan)
    w = fs.M @ z + fs.q
    sol = LCPSolution(z, w, peer.status, int(peer.iterations),
                      solve_time=time.perf_counter() - t0, message=peer.message,
                      extra={"coulomb_residual": peer.residual})
    return judged(fs, sol)


def step_runner(solver: str | None = None):
    """The frictional step's solver ``(fs) -> LCPSolution`` (z in the LCP's form) for a
    back-end named ``solver`` (default :data:`DEFAULT`, Lemke). SolverNotFound for an
    unknown or absent name; ProblemError for a back-end that does not take friction."""
    if solver is not None and not isinstance(solver, str):
        raise ProblemError(f"solver must be a back-end's name (a str), got "
                           f"{type(solver).__name__}")
    name = DEFAULT if solver in (None, "auto") else solver
    backend = get_backend(name)
    form = backend.friction_form
    if form not in FRICTION_FORMS:
        raise ProblemError(f"solver {name!r} does not take the frictional step; solvers "
                           f"that do: {', '.join(sorted(friction_backends()))}")
    settings = STEP_SETTINGS
    if form == "lcp":
        if name == "lemke":
            lemke = StepLemke()  # one per runner, as a path's default (its last covering first)

            def run(fs):  # (polished by guarded, as every back-end's answer)
                return judged(fs, lemke(fs, polish=False))
        else:
            mod = backend.load()

            def run(fs):
                return judged(fs, mod.solve_lcp(fs.M, fs.q, settings, None, **backend.options))
    elif form == "fc2d" and name == "active-set":
        from ..solvers.fc2d_active import initial_states, solve_fc2d_active

        last: dict = {}  # the states at the last step, by free node: the next one's start

        def run(fs):
            t0 = time.perf_counter()
            W, q, mu = fc2d_contacts(fs)
            start = None
            if last:
                guess = np.array([last.get(int(j), -1) for j in fs.normal_node])
                fresh = initial_states(q, mu)
                start = np.where(guess >= 0, guess, fresh)
            peer = solve_fc2d_active(W, q, mu, states=start)
            if start is not None and not peer.solved:  # the last step's states misled it
                peer = solve_fc2d_active(W, q, mu)
            last.clear()
            last.update(zip(fs.normal_node.tolist(), peer.extra["states"].tolist()))
            return from_fc2d(fs, peer, t0)
    elif form == "fc2d":
        from ..solvers.siconos_fc2d import solve_fc2d

        method = FC2D_METHODS.get(backend.options.get("method", ""))
        if method is None:
            raise ProblemError(f"solver {name!r}: no Siconos fc2d method for it")

        def run(fs):
            t0 = time.perf_counter()
            W, q, mu = fc2d_contacts(fs)
            if method == "enum" and mu.size > FC2D_ENUM_MAX:
                nan = np.full(fs.q.size, np.nan)
                return LCPSolution(nan, nan.copy(), Status.FAILED, message=(
                    f"Siconos' fc2d enumeration is run up to {FC2D_ENUM_MAX} contacts "
                    f"(4^n states), the step has {mu.size}"))
            return from_fc2d(fs, solve_fc2d(W, q, mu, method=method), t0)
    else:
        from ..solvers.fc2d_tresca import solve_fc2d_tresca

        mod = backend.load()

        def run(fs):
            t0 = time.perf_counter()
            W, q, mu = fc2d_contacts(fs)
            peer = solve_fc2d_tresca(W, q, mu, mod.solve_qp, settings,
                                     options=backend.options, warm=backend.warm_start)
            return from_fc2d(fs, peer, t0)

    def guarded(fs, polish: bool = True):
        """``run``, a back-end that raises answering FAILED (as the LCP runner does); a
        SOLVED answer, judged, leaves through the primal polish (:func:`polish_step`:
        kept only where lcpbench's residual still passes) unless ``polish`` is False
        (the driver's intermediate steps: it polishes the answer that would end a state,
        ``guarded.polish``)."""
        try:
            sol = run(fs)
        except Exception as exc:  # a back-end failure is a status, never an exception
            nan = np.full(fs.q.size, np.nan)
            return LCPSolution(nan, nan.copy(), Status.FAILED,
                               message=f"{name} raised {type(exc).__name__}: {exc}")
        return polish_step(fs, sol) if polish else sol
    guarded.takes_step = True  # type: ignore[attr-defined]  # friction_driver.solve_state
    # Lemke's intermediate steps go unpolished (the driver polishes the answer that would
    # end a state); the peers' answers are polished at every step, as their paths need:
    # deferred, on benchmarks/friction_agreement.py's paths ProxSuite's converged states
    # fell from 193 to 179 and PIQP's from 163 to 121 (a residual of 1e-9 leaves the
    # unpolished iterates too rough to settle to tol)
    guarded.defers_polish = name == "lemke"  # type: ignore[attr-defined]
    # (Lemke's: StepLemke.polish, the same polish; a refused answer is returned as it was)
    guarded.polish = lemke.polish if form == "lcp" and name == "lemke" \
        else polish_step  # type: ignore[attr-defined]
    # Newton's steps near the answer for Lemke, the default (StepLemke.newton); the peers
    # get the paper's Gauss–Newton steps, as they were measured
    guarded.newton = name == "lemke"  # type: ignore[attr-defined]
    guarded.backend = name  # type: ignore[attr-defined]
    guarded.form = form  # type: ignore[attr-defined]
    return guarded

