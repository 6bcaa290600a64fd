"""Start-up of the compiled solve (issue 19, item 5): what a first solve loads.

No timing here (times live in benchmarks/): these tests check the causes of a
slow start that the code controls. ``import lcpbench`` loads neither numba nor
scipy; the default solve loads neither scipy.linalg nor scipy.sparse (the
kernels' cache entries need none of numba's BLAS or array reductions, and the
QP back-ends' sparse matrices are built only when a QP back-end runs); the
light cache load (:mod:`lcpbench.numba_cache`) gives bit-for-bit the
answer of numba's own loader.
"""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

from lcpbench.numba_cache import light_cache_load

PROBE = """
import json, sys
import lcpbench
at_import = sorted(m for m in ("numba", "scipy", "scipy.linalg") if m in sys.modules)
r = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links=30))
loaded = sorted(m for m in ("scipy.linalg", "scipy.sparse", "numba.np.arraymath",
                            "numba.np.linalg") if m in sys.modules)
print(json.dumps({"at_import": at_import, "loaded": loaded, "engine": r.engine,
                  "judge": r.judge, "force": r.total_force.hex(),
                  "bound": r.force_error_bound}))
"""


def probe(**env) -> dict:
    out = subprocess.run([sys.executable, "-c", PROBE], check=True, capture_output=True,
                         text=True, timeout=600, env={**os.environ, **env})
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_default_solve_loads_no_scipy_linalg_sparse_or_numba_blas():
    # what a first solve loads once its kernels are in the cache: a fresh checkout
    # compiles them at its first solve, and numba's compiler loads all of numba (with
    # -n 2 tests/conftest.py compiles them before the workers start; with -n 0 nothing
    # does), so one solve first
    probe()
    light = probe()
    assert light["at_import"] == []
    assert (light["engine"], light["judge"]) == ("compiled", "heights")
    assert light["loaded"] == []


def test_the_light_cache_load_gives_numbas_answer():
    """Route against route: loading the same cached kernels two ways must give the same
    bits; an oracle cannot tell two loads apart."""
    light, full = probe(LCPBENCH_AOT="0"), probe(LCPBENCH_NUMBA_FULL_LOAD="1")
    assert light["force"] == full["force"] and light["bound"] == full["bound"]


def test_light_loading_leaves_other_objects_alone():
    assert light_cache_load(object()) is False  # no numba cache: nothing to change


def test_the_kernels_are_cached_under_a_hash_of_all_their_files(tmp_path):
    """numba invalidates a cache entry only when the function's own file changes,
    and the kernels call each other across files; their cache directory is named
    by all of them, so an edit of any one moves it."""
    from numba.core import config

    from lcpbench.model import compiled
    from lcpbench.numba_cache import CONSTANT_FILES, KERNEL_FILES, jit_module, kernel_cache_dir

    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("x = 1\n")
    b.write_text("y = 1\n")
    first = kernel_cache_dir([a, b], str(tmp_path))
    b.write_text("y = 2\n")  # an edit of the second file alone moves the cache
    assert kernel_cache_dir([a, b], str(tmp_path)) != first
    assert first.startswith(str(tmp_path / "lcpbench-numba"))
    k = jit_module("lcpbench.model.compiled_kernel")
    here = Path(compiled.__file__).parent.parent
    where = kernel_cache_dir([here / f for f in KERNEL_FILES + CONSTANT_FILES],
                             config.CACHE_DIR)
    walk = jit_module("lcpbench.linalg.twisted_walk_kernel")
    twisted = jit_module("lcpbench.linalg.twisted_kernel")
    for dispatcher in (k.solve_chain, k.dual_active_set, walk.walk, twisted.factor):
        assert dispatcher._cache._cache_path.startswith(where)


def test_every_file_with_numba_kernels_is_listed_and_loaded_through_the_cache():
    """A kernel file missing from KERNEL_FILES, or imported directly by a module
    that is not itself a kernel, would be cached beside its source, out of reach
    of the hash."""
    from lcpbench.numba_cache import KERNEL_FILES

    root = Path(__file__).resolve().parents[2] / "src" / "lcpbench"
    with_njit = {str(p.relative_to(root)) for p in root.rglob("*.py")
                 if re.search(r"^from numba import|^import numba", p.read_text(), re.M)}
    assert with_njit == set(KERNEL_FILES)
    names = {Path(f).stem for f in KERNEL_FILES}
    for p in root.rglob("*.py"):
        if str(p.relative_to(root)) in KERNEL_FILES:
            continue  # kernels import kernels inside kernel_module's import
        for line in p.read_text().splitlines():
            m = re.match(r"\s*from \.+[\w.]* import (.+)|\s*import ([\w.]+)", line)
            if m:
                imported = set(re.findall(r"\w+", m.group(1) or m.group(2)))
                assert not imported & names, f"{p.name}: {line.strip()}"


def test_no_test_module_imports_a_kernel_file_directly():
    """A test that imports a kernel file at collection (``from lcpbench.model import
    angle_kernel``) registers its dispatchers, and those of every kernel it imports,
    with numba's default cache beside the sources before any solve loads them through
    the cache: the hash test above then fails, depending on the collection order."""
    from lcpbench.numba_cache import KERNEL_FILES

    tests = Path(__file__).resolve().parents[1]
    dotted = {"lcpbench." + f.removesuffix(".py").replace("/", ".") for f in KERNEL_FILES}
    for p in tests.rglob("*.py"):
        for line in p.read_text().splitlines():
            m = re.match(r"(?:from ([\w.]+) import (.+)|import ([\w.]+))", line)
            if not m:
                continue
            base = m.group(1) or m.group(3)
            names = {f"{base}.{n}" for n in re.findall(r"\w+", m.group(2) or "")} | {base}
            assert not names & dotted, f"{p.relative_to(tests)}: {line.strip()}"
