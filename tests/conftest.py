"""Test-suite configuration.

BLAS runs on one thread for the whole test run, in this process and in every
subprocess it starts (sweep workers, the Siconos worker): the path of a
Newton-type method through a nearly singular system depends on the order of
the floating-point sums, hence on the BLAS thread count, and a test must not
depend on the machine it runs on. The variables are set before numpy is
imported (pytest imports this file before any test module); threadpoolctl, if
installed, also limits pools already loaded by a plug-in.

Hypothesis runs derandomized by default, so CI sees the same examples every
run (a red run is reproducible, a green one is not luck). Set
``HYPOTHESIS_PROFILE=explore`` to search with fresh random examples.
"""

import os
import sys

#: Thread-count variables of the BLAS/OpenMP builds numpy and the solvers use.
BLAS_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                         "BLIS_NUM_THREADS", "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS")
for _name in BLAS_THREAD_VARIABLES:
    os.environ[_name] = "1"

try:  # pools loaded before this file (by a plug-in) ignore the variables above
    from threadpoolctl import threadpool_limits
except ImportError:  # optional: the variables suffice when numpy is not yet loaded
    _BLAS_LIMIT = None
else:
    _BLAS_LIMIT = threadpool_limits(limits=1)  # kept alive for the whole run

from hypothesis import settings  # noqa: E402  (after the thread pinning, on purpose)

settings.register_profile("repeatable", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "repeatable"))

# `lcpbench select` and the sweep read and write a results store; the tests must not
# depend on whatever store the machine holds, nor share one between tests (or between the
# two workers of the suite): a store in a folder that does not exist cannot be created, so
# a test that forgets its own store (`--store`, tmp_path) fails at once.
os.environ["LCPBENCH_STORE"] = os.path.join(os.path.dirname(__file__), "no-such-folder",
                                            "store.sqlite")


import pytest  # noqa: E402


@pytest.fixture
def skip_escalations(monkeypatch):
    """``skip("tightened", ...)``: those escalations of lcpbench.escalations.ESCALATIONS
    never apply (their rows' ``applies`` answers False) for the rest of the test."""
    from dataclasses import replace

    from lcpbench.escalations import ESCALATIONS

    def skip(*names: str) -> None:
        for name in names:
            monkeypatch.setitem(ESCALATIONS, name,
                                replace(ESCALATIONS[name], applies=lambda res, ctx: False))

    return skip


def _walk_on_any_qp():
    """The active set on a bare LCP (``solvers.dual_kernel.box_qp``): its two kinds of
    face, banded (a 3 × 3 M: two sub-diagonals) and dense (4 × 4), compiled once here
    (not in the AOT module: the dense faces call LAPACK through numba)."""
    import numpy as np

    from lcpbench.solvers import solve_lcp

    for n in (3, 4):
        solve_lcp(np.eye(n) + 0.1, -np.ones(n), solver="active-set")


def pytest_sessionstart(session):
    """Where the suite runs in worker processes (pytest-xdist), the controller first runs
    the solves whose kernels every worker loads (:func:`lcpbench.aot.representative_solves`),
    so that on a fresh checkout they are compiled into numba's on-disk cache once, before
    the workers start: numba's cache is not safe for two processes saving entries of one
    kernel at the same moment (its index names a data file by the number of entries, so
    both can write the same file and one index entry can name the other's code)."""
    workers = getattr(session.config.option, "numprocesses", None)
    if not workers or os.environ.get("PYTEST_XDIST_WORKER"):
        return
    from lcpbench import numba_cache
    from lcpbench.aot import representative_solves

    print("lcpbench: the kernels every worker loads, before the workers start (a fresh "
          "checkout compiles them: about a minute)", file=sys.stderr, flush=True)
    numba_cache.use_aot(False)  # the JIT kernels, whose cache the workers read
    try:
        representative_solves()
        _walk_on_any_qp()
    except Exception as exc:  # a broken solve is the tests' to report, not the session's
        print(f"lcpbench: those solves failed ({type(exc).__name__}: {exc}); the workers "
              "compile the kernels as they go", file=sys.stderr, flush=True)
    finally:
        numba_cache.use_aot(None)
