"""The documented expected failures of a sweep, so a report can tell them from surprises.

Each entry is a back-end (and optionally a settings profile) with the run
statuses it is known to end in on the contact step, and where that is
documented. A failure that matches an entry is *expected*; every other
failure is *unexpected*. The list is short on purpose: only behaviour that
README.md and docs/ state and explain.

- PGS/SOR (ours and Siconos's) and Siconos Newton-min do not converge on a
  contact step: cond(K) ≈ 1e8 at N = 140 (README "Results", results/conditioning.md).
- The root-finding baselines give ``invalid`` where one midspan reaction is
  not the answer: no contact (a pulling wall) and h ≤ 3 mm (a shape through
  the wall, the paper's Fig. 27b) (docs/bench.md "The baseline").
- Clarabel, OSQP, ProxSuite (dense and sparse) and SCS end ``not_converged``
  on part of the scenes: lcpbench's result judge refuses their answer where
  their last contact step does not pass lcpbench's residual test or the force
  error bound (README "Results", docs/solvers.md "The result judge"). They
  succeed on the rest, so this is a *partial* expectation: it labels such a
  failure expected, but neither leaves the back-end out of the main job nor
  rules it out of selection.
- Siconos' enumeration and its Murty, Bard and path-search pivot rules do
  not converge on the N = 140 contact step (docs/solvers.md).
- The hard suite (``--grid hard``, results/hard/README.md): the undamped
  driver passes the vertical at θ = 180°, h ≤ 1 mm; at N = 2000 most
  back-ends run out of time or of their own iterations (the built-in active
  set, on the banded step, takes 0.2 s); the judge refuses answers whose total force is within τ of the
  reference but whose force error bound is not (its conservatism), and
  answers that fail lcpbench's residual checks or are off by more than τ.
  These entries (:data:`HARD_EXPECTED`) name more than a status: the
  driver, a part of the stored reason, the scene, and whether the run's error
  against the reference is within τ, so a new kind of failure stays
  unexpected.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..model.judge import force_tol

#: The status of a run that converged but is off the reference by more than the
#: success threshold (as in :func:`lcpbench.bench.report.failures`).
OFF_REFERENCE = "converged, error too large"


@dataclass(frozen=True)
class Expectation:
    """A back-end's documented failure: ``statuses`` at ``settings`` (None: any).

    ``min_links``: documented from N = ``min_links`` links on (None: at any N);
    selection uses it to rule a back-end out only where it is documented.
    """

    backend: str | None  # None: any back-end (a failure of the driver, not of a back-end)
    statuses: frozenset[str]
    why: str
    settings: str | None = None
    min_links: int | None = None
    partial: bool = False  # fails on some scenes only (never_converges and select ignore it)
    # The conditions below need the run itself (``run=`` of :func:`expectation`); an
    # entry with any of them never matches a failure given by its status alone.
    method: str | None = None  # the driver ("undamped"); None: any
    reason: str | None = None  # a part of the run's stored reason
    scene: tuple[tuple[str, float, float], ...] = ()  # (column, low, high), inclusive
    within_tol: bool = False  # only where |F − F_ref| / F₀ <= τ (the error is needed)
    #: only where τ·low < |F − F_ref| / F₀ <= τ·high: an answer off by a documented margin
    off_by: tuple[float, float] | None = None

    @property
    def needs_run(self) -> bool:
        return bool(self.method or self.reason or self.scene or self.within_tol
                    or self.off_by is not None)

    def matches_run(self, run: dict, error: float | None) -> bool:
        """The run-level conditions: driver, reason, scene and error within τ."""
        if self.method is not None and run.get("method") != self.method:
            return False
        if self.reason is not None and self.reason not in str(run.get("reason") or ""):
            return False
        for column, low, high in self.scene:
            value = run.get(column)
            if value is None or not low <= float(value) <= high:
                return False
        known = error is not None and math.isfinite(error)
        tau = force_tol(float(run["tol"])) if self.within_tol or self.off_by else math.nan
        if self.off_by is not None and not (
                known and self.off_by[0] * tau < error <= self.off_by[1] * tau):
            return False
        if self.within_tol:
            return known and error <= tau
        return True


_NO_CONTACT_STEP = "does not converge on a contact step, cond(K) ≈ 1e8 (README, Results)"
EXPECTED: tuple[Expectation, ...] = (
    *(Expectation(b, frozenset({"not_converged"}), _NO_CONTACT_STEP)
      for b in ("pgs", "psor", "siconos-pgs", "siconos-newton-min")),
    *(Expectation(b, frozenset({"invalid"}),
                  "one midspan reaction is not the answer without contact or at h ≤ 3 mm "
                  "(docs/bench.md, The baseline)")
      for b in ("baseline", "baseline-fd")),
    # Siconos' enumeration and pivot rules at N = 140 (docs/solvers.md, the Siconos rows)
    *(Expectation(f"siconos-{m}", frozenset({"not_converged"}),
                  f"{why} on the N = 140 contact step (docs/solvers.md)", min_links=140)
      for m, why in (("enum", "n = 113 > 20: 2^n complementary bases are not enumerated"),
                     ("murty", "the least-index rule reaches its 10000-pivot limit"),
                     ("bard", "Bard's rule cycles to its 10000-pivot limit"),
                     ("pathsearch", "the judge refuses its inaccurate last step"))),
    *(Expectation(b, frozenset({"not_converged"}),
                  "the result judge refuses an answer whose last step fails lcpbench's "
                  "residual test or whose force error bound misses the success rule "
                  "(README, Results; docs/solvers.md)", partial=True)
      for b in ("clarabel", "osqp", "proxsuite-dense", "proxsuite-sparse", "qpsolvers-scs")),
)

#: The judge's refusal where the total-force bound is the only check that failed (the
#: checks are listed in one order, :func:`lcpbench.model.judge.failed_checks`, the
#: total-force bound last: a reason that starts with it names nothing else)
BOUND_ONLY = "lcpbench's judge: force error bound: the total force"
#: The judge's refusal whose first failed check is the last step's residual test
LAST_STEP = "lcpbench's judge: last step"
#: any refusal by the judge
JUDGE = "not accepted by lcpbench's judge"
_INF = math.inf
#: the hard suite's grazing scene, weightless at θ = 120°, the wall 1e-9 mm below the
#: arc's highest node (grid.hard_scenes: h = 7.16203922413 mm; ±5e-10 mm keeps the
#: scene 1e-9 mm above it, which has no contact, out)
GRAZING = (("theta", 120.0, 120.0), ("weight", 0.0, 0.0),
           ("height", 7.16203922413 - 5e-10, 7.16203922413 + 5e-10))
_HARD = "results/hard/README.md"
_DENSE_TIMEOUT = ("clarabel", "lemke", "pgs", "pgs-sm", "psor", "proxsuite-dense", "qpsolvers-daqp",
                  "qpsolvers-highs", "qpsolvers-quadprog", "qpsolvers-scs",
                  *(f"siconos-{m}" for m in ("bard", "lemke", "murty", "newton-fb",
                                              "newton-min", "pathsearch", "pgs")))
HARD_EXPECTED: tuple[Expectation, ...] = (
    # (c) the driver: the paper's undamped iteration, not a back-end
    Expectation(None, frozenset({"not_converged"}),
                "the undamped (paper's) iteration carries a link past the vertical at "
                "θ = 180°, h ≤ 1 mm (README, Hard cases; results/hard-cases.md)",
                method="undamped", reason="diverged: a link passed the vertical",
                scene=(("theta", 180.0, 180.0), ("height", 0.0, 1.0)), partial=True),
    # (c) N = 2000: out of the time limit, or of the back-end's own iterations
    *(Expectation(b, frozenset({"timeout"}),
                  "does not finish the N = 2000 solve in the time limit (20 s a solve in "
                  "the hard suite; the built-in active set, on the banded step, takes "
                  f"0.2 s: results/hard-cases.md) ({_HARD})",
                  min_links=2000, scene=(("links", 2000, _INF),), partial=True)
      for b in _DENSE_TIMEOUT),
    *(Expectation(b, frozenset({"not_converged"}),
                  f"its contact step at N = 2000 ends {why} ({_HARD})",
                  min_links=2000, reason=f"contact step not solved ({key}",
                  scene=(("links", 2000, _INF),), partial=True)
      for b, key, why in (("cvxpy", "max_iterations", "at its iteration limit"),
                          ("qpsolvers-piqp", "max_iterations", "at its iteration limit"),
                          ("qpsolvers-highs", "failed", "without a solution"),
                          ("quantecon-lemke", "ray", "on a secondary ray"))),
    # (c) PGS-SM's subspace step minimises ½zᵀMz + qᵀz: it takes a symmetric M only
    Expectation("pgs-sm", frozenset({"not_converged"}),
                "it takes a symmetric M only (its subspace step minimises ½zᵀMz + qᵀz) and "
                "refuses the channel's contact step, whose M is not (max |M − Mᵀ| = 2), "
                f"with a failed status ({_HARD})",
                reason="pgs-sm needs symmetric M", partial=True),
    # (a) within τ of the reference, refused by the force error bound alone: the bound
    # |F_k − F_{k+1}| / (1 − ρ) takes ρ from the back-end's last step sizes, which an
    # inexact inner solve holds near 0.99 (κ = 100), so an answer 4e-9 off is bounded
    # by 4e-7 > τ = 1e-7 (results/hard/README.md, "Expected and unexpected failures")
    *(Expectation(b, frozenset({"not_converged"}),
                  "the judge's force error bound (×1/(1 − ρ) = ×100 on an inexact last "
                  "step) refuses an answer within τ of the reference: the bound is "
                  f"conservative ({_HARD})",
                  settings="high", reason=BOUND_ONLY, within_tol=True, partial=True)
      for b in ("cvxpy", "qpsolvers-daqp", "qpsolvers-piqp", "siconos-newton-fb")),
    # (b) the answer fails lcpbench's residual checks (its total force within τ)
    Expectation("qpsolvers-quadprog", frozenset({"not_converged"}),
                "its last contact step at h ≤ 1 mm fails lcpbench's residual test "
                f"(the total force within τ) ({_HARD})",
                settings="high", reason=LAST_STEP, scene=(("height", 0.0, 1.0),),
                within_tol=True, partial=True),
    Expectation("quantecon-lemke", frozenset({"not_converged"}),
                "its last contact step fails lcpbench's residual test (the total force "
                f"within τ) ({_HARD})",
                settings="high", reason=LAST_STEP, within_tol=True, partial=True),
    Expectation("qpsolvers-piqp", frozenset({"not_converged"}),
                "the interior point's last step leaves a reaction on a node off its wall "
                "(complementarity) or fails lcpbench's residual test (the total force "
                f"within τ) ({_HARD})",
                settings="high", reason=JUDGE, within_tol=True, partial=True),
    *(Expectation(b, frozenset({"not_converged"}),
                  "with the undamped driver its last step on the heavy chain (w = 0.05 "
                  "N/mm) fails lcpbench's residual test: a wall pulls by 1e-7 to 2e-6 N "
                  f"({_HARD})",
                  settings="high", method="undamped", reason=LAST_STEP,
                  scene=(("weight", 0.05, _INF),), partial=True)
      for b in ("lemke", "siconos-lemke", "quantecon-lemke", "qpsolvers-highs")),
    # (b) off by more than τ on the grazing scene (F_ref = 1e-10 N), refused
    *(Expectation(b, frozenset({"not_converged"}),
                  "on the grazing scene (contact by 1e-9 mm, F_ref = 1e-10 N) its answer is "
                  f"2e-7 to 2e-5 F₀ off, refused by the force error bound ({_HARD})",
                  settings="high", reason=BOUND_ONLY, scene=GRAZING, partial=True)
      for b in ("qpsolvers-highs", "qpsolvers-piqp")),
    # (c) the back-end's own failures on the hard N = 140 scenes
    Expectation("cvxpy", frozenset({"not_converged"}),
                "its QP solver (OSQP through cvxpy) reaches its iteration limit on a "
                f"θ = 180°, h ≤ 1 mm contact step ({_HARD})",
                settings="high", reason="cvxpy/OSQP: user_limit",
                scene=(("theta", 180.0, 180.0), ("height", 0.0, 1.0)), partial=True),
    Expectation("quantecon-lemke", frozenset({"not_converged"}),
                "quantecon's Lemke ends on a secondary ray, which it cannot in exact "
                "arithmetic on the positive definite step: round-off at cond(K) ≈ 1e8 "
                f"({_HARD})",
                reason="secondary ray termination", partial=True),
    # (b, c) Siconos' Newton-FB at high: inexact steps (its own merit function stops at
    # ~7e-9): the driver runs out of 200 outer iterations or the judge refuses the
    # answer; the standard run's 38 % at high are the scenes without contact (README)
    Expectation("siconos-newton-fb", frozenset({"not_converged"}),
                "at settings high it fails on most contact scenes: its steps stop at its "
                "own merit function, inexact by lcpbench's residuals, so the driver runs "
                "out of outer iterations or the judge refuses the answer (the standard "
                "run: 50 %, the 41 scenes without contact and 13 of the 67 with; "
                f"{_HARD})",
                settings="high", partial=True),
)


_STD = "docs/bench.md, Expected failures; results/sweep/report.md"
#: The standard run's (results/sweep) documented refusals beyond :data:`EXPECTED`, each
#: by back-end, settings, a part of the stored reason and, for the judge's refusals,
#: the run's error against the reference, so that a new kind of failure stays unexpected.
STANDARD_EXPECTED: tuple[Expectation, ...] = (
    # (a) the answer is within τ of the reference, and the judge refuses it all the
    # same: its force error bound (×1/(1 − ρ)) or the residual test of the last step
    # is conservative where the back-end's last step is inexact
    *(Expectation(b, frozenset({"not_converged"}),
                  "the answer is within τ of the reference, but the judge's force error "
                  "bound or its residual test of the (inexact) last step is over its "
                  f"allowance: the judge is conservative, the answer is not wrong ({_STD})",
                  settings=s, reason=JUDGE, within_tol=True, partial=True)
      for b, s in (("cvxpy", "default"), ("lemke", "high"), ("qpsolvers-daqp", "default"),
                   ("pgs-sm", "high"), ("qpsolvers-highs", "high"),
                   ("qpsolvers-quadprog", "high"),
                   ("quantecon-lemke", "high"), ("siconos-lemke", "high"),
                   ("siconos-newton-fb", "default"))),
    # (b) just over τ at high: an inexact last step, rightly refused (the margin: the
    # largest error of its refused answers in the standard run, rounded up)
    *(Expectation(b, frozenset({"not_converged"}),
                  "at settings high its last contact step is inexact (ε = 1e-9 on the "
                  "scaled step, cond(K) ≈ 1e8): the answer is off the reference by more "
                  f"than τ but at most {high:g} τ, and the judge rightly refuses it ({_STD})",
                  settings="high", reason=JUDGE, off_by=(1.0, high), partial=True)
      for b, high in (("cvxpy", 1.5), ("qpsolvers-piqp", 2.0), ("qpsolvers-daqp", 5.0),
                      ("qpsolvers-highs", 5.0))),
    # (c) the back-end's own stops
    Expectation("siconos-newton-fb", frozenset({"not_converged"}),
                "at default settings Siconos' Newton-FB reaches its 1000-iteration limit on "
                f"a contact step (its merit function stalls at cond(K) ≈ 1e8) ({_STD})",
                settings="default", reason="siconos newton-fb: iteration limit",
                partial=True),
    Expectation("cvxpy", frozenset({"not_converged"}),
                "at default settings cvxpy's QP solver (OSQP, eps 1e-5) returns inexact "
                "steps and the driver stalls above its tolerance in 200 outer steps "
                f"({_STD})",
                settings="default", reason="max|Δα| stalled", partial=True),
    Expectation("cvxpy", frozenset({"not_converged"}),
                "at settings high its QP solver (OSQP through cvxpy) reaches its iteration "
                f"limit on a θ = 180° contact step ({_STD})",
                settings="high", reason="cvxpy/OSQP: user_limit",
                scene=(("theta", 180.0, 180.0),), partial=True),
)


def expectation(backend: str, settings: str, status: str, *, run: dict | None = None,
                error: float | None = None) -> Expectation | None:
    """The documented expectation this failure matches, or None (unexpected).

    Parameters
    ----------
    backend, settings : str
        The run's back-end and settings profile.
    status : str
        Its stored status, or :data:`OFF_REFERENCE` for a converged run off the
        reference.
    run : dict, optional
        The stored run (``method``, ``reason``, ``tol`` and the scene columns):
        without it, entries that name more than a status do not match.
    error : float, optional
        Its error against the reference, |F − F_ref| / max(|F_ref|, EI/ℓ²)
        (:func:`lcpbench.bench.metrics.error_of`): entries ``within_tol`` match
        only where it is known and at most τ.
    """
    for e in (*EXPECTED, *HARD_EXPECTED, *STANDARD_EXPECTED):
        if e.backend not in (None, backend) or status not in e.statuses:
            continue
        if e.settings not in (None, settings):
            continue
        if e.needs_run and (run is None or not e.matches_run(run, error)):
            continue
        return e
    return None


def never_converges(backend: str) -> Expectation | None:
    """The documented expectation that ``backend`` never converges on a contact step
    (at any settings), or None. The main job (``lcpbench sweep`` without
    ``--standard``) leaves these back-ends out: they cost most of a sweep's time
    (PGS runs out its 10⁴ sweeps on every scene with contact) to confirm what is
    documented; the standard run keeps them."""
    for e in EXPECTED:
        if (e.backend == backend and e.settings is None and not e.partial
                and e.statuses == {"not_converged"}):
            return e
    return None


def is_expected(backend: str, settings: str, status: str, *, run: dict | None = None,
                error: float | None = None) -> bool:
    """True if a run of ``backend`` at ``settings`` ending in ``status`` is a documented
    failure (``run``, ``error``: as :func:`expectation`)."""
    return expectation(backend, settings, status, run=run, error=error) is not None


__all__ = ["EXPECTED", "HARD_EXPECTED", "OFF_REFERENCE", "STANDARD_EXPECTED", "Expectation",
           "expectation", "is_expected", "never_converges"]
