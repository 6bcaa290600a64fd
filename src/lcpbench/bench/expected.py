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
"""

from __future__ import annotations

from dataclasses import dataclass

#: The status of a run that converged but is off the reference by more than the
#: success threshold (as in :func:`lcpbench.bench.report.failures`).
OFF_REFERENCE = "converged, error too large"


@dataclass(frozen=True)
class Expectation:
    """A back-end's documented failure: ``statuses`` at ``settings`` (None: any).

    ``min_links``: documented from N = ``min_links`` links on (None: at any N);
    selection uses it to rule a back-end out only where it is documented.
    """

    backend: str
    statuses: frozenset[str]
    why: str
    settings: str | None = None
    min_links: int | None = None
    partial: bool = False  # fails on some scenes only (never_converges and select ignore it)


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


def expectation(backend: str, settings: str, status: str) -> Expectation | None:
    """The documented expectation this failure matches, or None (unexpected).

    Parameters
    ----------
    backend, settings : str
        The run's back-end and settings profile.
    status : str
        Its stored status, or :data:`OFF_REFERENCE` for a converged run off the
        reference.
    """
    for e in EXPECTED:
        if e.backend == backend and status in e.statuses and e.settings in (None, settings):
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


def is_expected(backend: str, settings: str, status: str) -> bool:
    """True if a run of ``backend`` at ``settings`` ending in ``status`` is a documented failure."""
    return expectation(backend, settings, status) is not None


__all__ = ["EXPECTED", "OFF_REFERENCE", "Expectation", "expectation", "is_expected",
           "never_converges"]
