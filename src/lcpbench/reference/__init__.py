"""The independent references lcpbench is judged by and compared with.

- :mod:`.energy` (with :mod:`.energy_profile`): the equilibrium by minimising
  the exact nonlinear energy (SLSQP and a Newton polish), the tests' oracle.
  It shares the chain's kinematics and walls with the model, never its contact
  step, outer loops, judge or back-ends (an import-linter contract).
- :mod:`.dense`: the paper's dense path, eqs. 3–31 assembled as written and
  solved by Lemke; the contender of the speed targets.
- :mod:`.root_finding`: the paper's competitor, root finding on the
  single-reaction system of the appendix. Its equations use the model's
  geometry only, never the LCP path it is compared with. Its N comes from the
  Sec. III-D rule applied to its own answers (``baseline_links``); that rule
  is shared with the LCP model through :mod:`lcpbench.studies.discretisation`,
  which is why this package sits above ``studies``.

Nothing is imported here, so that loading one reference loads none of the
others.
"""
