"""Test-suite configuration.

Hypothesis runs derandomized by default, so CI sees the same examples every
run (a red run is reproducible, a green one is not luck). Set
``HYPOTHESIS_PROFILE=explore`` to search with fresh random examples.
"""

import os

from hypothesis import settings

settings.register_profile("repeatable", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))

# solver="auto" reads back-end selections cached in a results store; the tests
# must not depend on whatever store the machine happens to hold.
os.environ["LCPBENCH_STORE"] = os.path.join(os.path.dirname(__file__), "no-such-store.sqlite")
