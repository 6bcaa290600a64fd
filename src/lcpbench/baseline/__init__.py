"""The paper's competitor: root finding on the single-reaction system of the appendix.

It depends on the model's geometry only, never on the LCP path it is compared
with: its N comes from the Sec. III-D rule applied to its own answers
(:func:`.root_finding.baseline_links`).
"""

from .root_finding import BaselineResult, BaselineSystem, baseline_links, solve_baseline

__all__ = ["BaselineResult", "BaselineSystem", "baseline_links", "solve_baseline"]
