"""The dual walks' working-set key (linalg/walk_key.walk_key) is the splitmix64 finaliser
of (2i + 1 or 2)·γ, written out here from the published finaliser with Python integers
modulo 2⁶⁴ (the oracle), compiled and as plain Python (``NUMBA_DISABLE_JIT=1``, the
debugging path), where numpy's uint64 scalars wrap the same but would warn of overflow."""

from __future__ import annotations

import os
import subprocess
import sys

MASK = (1 << 64) - 1


GAMMA = 0x9E3779B97F4A7C15  # splitmix64's increment, the golden ratio in 64 bits


def finaliser(z: int) -> int:
    """splitmix64's output function (Steele, Lea & Flood 2014; Stafford's mix variant 13),
    on Python integers."""
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
    return z ^ (z >> 31)


CASES = [(0, 1.0), (0, -1.0), (7, 1.0), (123456, -2.5), (10**6, 1.0), (3, 0.0)]


def expected(i: int, s: float) -> int:
    """The key of node i on the upper (s > 0, 2i + 1) or lower (2i + 2) wall; 0 off them."""
    return 0 if s == 0.0 else finaliser(((2 * i + (1 if s > 0 else 2)) * GAMMA) & MASK)


def test_the_compiled_key_is_the_splitmix64_finaliser_of_node_and_wall():
    from lcpbench.numba_cache import kernel_module

    key = kernel_module("lcpbench.linalg.walk_key").walk_key
    assert [int(key(i, s)) for i, s in CASES] == [expected(i, s) for i, s in CASES]


def test_the_plain_python_hash_is_the_same_without_an_overflow_warning():
    # the plain-Python path needs NUMBA_DISABLE_JIT=1 before numba is imported: a fresh
    # interpreter imports the kernel file itself (not through kernel_module)
    code = ("from lcpbench.linalg.walk_key import walk_key; "
            f"print([int(walk_key(i, s)) for i, s in {CASES!r}])")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", OPENBLAS_NUM_THREADS="1")
    out = subprocess.run([sys.executable, "-W", "error::RuntimeWarning", "-c", code],
                         capture_output=True, text=True, env=env, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == str([expected(i, s) for i, s in CASES])
