"""The test run does not depend on the machine's BLAS thread count (see conftest)."""

import os
import subprocess
import sys

import numpy as np
import pytest

#: What tests/conftest.py pins (at least these).
BLAS_THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def test_blas_threads_pinned_in_this_process_and_its_children():
    for name in BLAS_THREAD_VARIABLES:
        assert os.environ[name] == "1", name
    # a subprocess (sweep workers, the Siconos worker) inherits the pinning
    out = subprocess.run([sys.executable, "-c", "import os; print(os.environ['OMP_NUM_THREADS'],"
                          " os.environ['OPENBLAS_NUM_THREADS'])"],
                         capture_output=True, text=True, check=True).stdout.split()
    assert out == ["1", "1"]


def _openblas_thread_counts() -> dict[str, int]:
    """Threads of every OpenBLAS loaded in this process (Linux: read from /proc)."""
    import ctypes

    try:
        with open("/proc/self/maps") as fh:
            libs = {line.split()[-1] for line in fh if "openblas" in line.lower()}
    except OSError:
        return {}
    out = {}
    for path in libs:
        lib = ctypes.CDLL(path)
        for sym in ("openblas_get_num_threads", "openblas_get_num_threads64_",
                    "scipy_openblas_get_num_threads64_", "scipy_openblas_get_num_threads"):
            func = getattr(lib, sym, None)
            if func is not None:
                out[path] = int(func())
                break
    return out


def test_loaded_openblas_runs_one_thread():
    np.ones((2, 2)) @ np.ones((2, 2))  # make sure BLAS is loaded
    counts = _openblas_thread_counts()
    if not counts:
        pytest.skip("no OpenBLAS found in /proc/self/maps (another BLAS, or not Linux)")
    assert set(counts.values()) == {1}, counts
