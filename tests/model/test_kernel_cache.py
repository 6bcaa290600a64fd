"""Start-up of the compiled solve (issue 19, item 5): what a first solve loads.

No timing here (times live in benchmarks/): these tests check the causes of a
slow start that the code controls. ``import lcpbench`` loads neither numba nor
scipy; the default solve loads neither scipy.linalg nor scipy.sparse (the
kernels' cache entries need none of numba's BLAS or array reductions, and the
QP back-ends' sparse matrices are built only when a QP back-end runs); the
light cache load (:mod:`lcpbench.model.kernel_cache`) gives bit-for-bit the
answer of numba's own loader.
"""

import json
import os
import subprocess
import sys

from lcpbench.model.kernel_cache import light_cache_load

PROBE = """
import json, sys
import lcpbench
at_import = sorted(m for m in ("numba", "scipy", "scipy.linalg") if m in sys.modules)
r = lcpbench.solve(lcpbench.ActuatorScene(theta=150, height=3.0, links=30))
loaded = sorted(m for m in ("scipy.linalg", "scipy.sparse", "numba.np.arraymath",
                            "numba.np.linalg") if m in sys.modules)
print(json.dumps({"at_import": at_import, "loaded": loaded, "engine": r.extra["engine"],
                  "judge": r.extra["judge"], "force": r.total_force.hex(),
                  "bound": r.force_error_bound}))
"""


def probe(**env) -> dict:
    out = subprocess.run([sys.executable, "-c", PROBE], check=True, capture_output=True,
                         text=True, timeout=600, env={**os.environ, **env})
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_default_solve_loads_no_scipy_linalg_sparse_or_numba_blas():
    light = probe()
    assert light["at_import"] == []
    assert (light["engine"], light["judge"]) == ("compiled", "compiled")
    assert light["loaded"] == []


def test_the_light_cache_load_gives_numbas_answer():
    light, full = probe(), probe(LCPBENCH_NUMBA_FULL_LOAD="1")
    assert light["force"] == full["force"] and light["bound"] == full["bound"]


def test_light_loading_leaves_other_objects_alone():
    assert light_cache_load(object()) is False  # no numba cache: nothing to change


def test_a_split_kernel_is_cached_under_a_hash_of_all_its_files(tmp_path):
    """numba invalidates a cache entry only when the function's own file changes;
    the solve kernel spans two files, so its cache directory is named by both."""
    from pathlib import Path

    from numba.core import config

    from lcpbench.model import compiled
    from lcpbench.model.kernel_cache import SPLIT, kernel_cache_dir

    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("x = 1\n")
    b.write_text("y = 1\n")
    first = kernel_cache_dir([a, b], str(tmp_path))
    b.write_text("y = 2\n")  # an edit of the second file alone moves the cache
    assert kernel_cache_dir([a, b], str(tmp_path)) != first
    assert first.startswith(str(tmp_path / "lcpbench-numba"))
    k = compiled._kernel()
    here = Path(compiled.__file__).parent
    where = kernel_cache_dir([here / f for f in SPLIT[k.__name__]], config.CACHE_DIR)
    for dispatcher in (k.solve_chain, k._dual):  # one in each file
        assert dispatcher._cache._cache_path.startswith(where)
