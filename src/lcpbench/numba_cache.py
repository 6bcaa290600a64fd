"""Loading the compiled kernels from numba's on-disk cache without numba's full start-up.

When numba loads a function from its cache it first refreshes its whole target
context: it imports and registers the implementations of everything numba can
compile (the typed containers, the random generators, the polynomial module,
the BLAS bindings, which import scipy.linalg, and more). That costs about half
a second per process, longer than loading the kernels themselves, and none of
it is needed to run object code that is already compiled: the code needs
numba's runtime (NRT, for the arrays it allocates) and the symbols of the
process, nothing else.

:func:`light_cache_load` makes one dispatcher load from the cache after
initialising only the runtime. Where the cache has no entry for the call (the
first run after an edit, a new signature), it hands over to numba's own
loader, which refreshes the context and compiles as usual; any error on the
light path does the same. ``LCPBENCH_NUMBA_FULL_LOAD=1`` turns it off.

Every numba kernel of lcpbench (:data:`KERNEL_FILES`) is imported through
:func:`kernel_module` and cached under one directory named by a hash of all
their sources (:func:`kernel_cache_dir`). numba invalidates a function's cache
entry only when *its own* file changes, and kernels call each other across
files (``compiled_kernel.py`` the dual walk of ``compiled_dual.py``,
``walk_kernel.py`` the twisted factor, which calls the face kernel): without the
hash an edit of one file could leave another file's cached code running stale.
Any edit of any kernel moves the directory, so every kernel compiles once
afresh. The base is numba's ``NUMBA_CACHE_DIR`` where set, else the user's cache
directory (``$XDG_CACHE_HOME`` or ``~/.cache``). This module is at the bottom of
the layers, so ``linalg`` can load its kernels through it too.

It uses two private methods of numba's cache (``_load_overload`` and
``_guard_against_spurious_io_errors``, numba 0.5x–0.6x); where they are
missing it does nothing, so a numba that changed them loads as before.
"""

from __future__ import annotations

import hashlib
import importlib
import os
from pathlib import Path

_LOADED: dict = {}  # module name -> the kernel module, once imported and hooked
_DIR: list = []  # the cache directory of this process's kernels, once computed
#: every file of lcpbench with numba kernels, relative to the package
#: (tests/test_numba_cache.py checks that no file with ``@njit`` is missing)
KERNEL_FILES = ("model/compiled_kernel.py", "model/compiled_dual.py", "model/judge_kernel.py",
                "model/driver_kernel.py", "model/large_kernel.py", "linalg/givens_kernel.py",
                "linalg/face_kernel.py", "linalg/twisted_kernel.py", "linalg/walk_kernel.py",
                "linalg/ldl_kernel.py")


def kernel_cache_dir(files, base: str | None = None) -> str:
    """``<base>/lcpbench-numba/<sha>``: the cache of a kernel made of ``files``,
    named by the SHA-256 of their sources (in order)."""
    sha = hashlib.sha256()
    for f in files:
        sha.update(Path(f).read_bytes())
    if not base:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "lcpbench-numba", sha.hexdigest()[:20])


def kernel_module(name: str, entry: str | None = None):
    """The compiled module ``name`` (imports numba; loads or compiles it) under the
    kernels' cache directory (:func:`kernel_cache_dir` of :data:`KERNEL_FILES`),
    its dispatcher ``entry`` hooked to :func:`light_cache_load`, once per process."""
    module = _LOADED.get(name)
    if module is None:
        from numba.core import config  # numba's locator reads it at each @njit

        if not _DIR:
            here = Path(__file__).parent
            _DIR.append(kernel_cache_dir([here / f for f in KERNEL_FILES], config.CACHE_DIR))
        saved = config.CACHE_DIR
        config.CACHE_DIR = _DIR[0]
        try:
            module = importlib.import_module(name)
        finally:
            config.CACHE_DIR = saved
        if entry is not None:
            light_cache_load(getattr(module, entry))
        _LOADED[name] = module
    return module


def light_cache_load(dispatcher) -> bool:
    """Make ``dispatcher`` (an ``@njit(cache=True)`` function) load from the cache
    without refreshing numba's target context; False where that is not possible."""
    cache = getattr(dispatcher, "_cache", None)
    load = getattr(cache, "_load_overload", None)
    guard = getattr(cache, "_guard_against_spurious_io_errors", None)
    full = getattr(cache, "load_overload", None)
    if load is None or guard is None or full is None or os.environ.get(
            "LCPBENCH_NUMBA_FULL_LOAD"):
        return False
    if getattr(full, "_lcpbench_light", False):
        return True

    def light(sig, target_context):
        found = None
        try:
            from numba.core.runtime import nrt

            nrt.rtsys.initialize(target_context)  # the runtime the kernels allocate with
            with guard():
                found = load(sig, target_context)
        except Exception:  # anything unexpected: numba's own loader decides
            found = None
        return found if found is not None else full(sig, target_context)

    light._lcpbench_light = True  # type: ignore[attr-defined]
    cache.load_overload = light
    return True
