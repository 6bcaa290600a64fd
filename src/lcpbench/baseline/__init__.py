"""The paper's competitor: root finding on the single-reaction system of the appendix.

Its equations use the model's geometry only, never the LCP path it is
compared with. Its N comes from the Sec. III-D rule applied to its own
answers (:func:`.root_finding.baseline_links`); that rule is shared with the
LCP model through :mod:`lcpbench.studies.discretisation`, which is why this
package sits above ``studies`` (the rule's default force function, unused
here, is the library call).
"""

from .root_finding import BaselineResult, BaselineSystem, baseline_links, solve_baseline

__all__ = ["BaselineResult", "BaselineSystem", "baseline_links", "solve_baseline"]
