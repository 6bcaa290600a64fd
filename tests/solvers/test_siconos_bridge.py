"""Tests of the Siconos numerics bridge (subprocess worker under /usr/bin/python3).

Skipped as a whole when Siconos is not installed for the system interpreter
(``apt-get install python3-siconos``). Expected answers come from hand
derivation, from LCP theory, or from the facts documented with the peer
collection in tests/data/siconos-lcp/README.md -- never from the
bridge's own output.
"""

from __future__ import annotations

import os
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from lcpbench.errors import ProblemError
from lcpbench.solvers import siconos_bridge as sb
from lcpbench.solvers.base import PROFILES, Settings, Status, lcp_residuals

if not sb.available():
    pytest.skip("siconos not installed for the system python "
                "(apt-get install python3-siconos)", allow_module_level=True)

PEER = Path(__file__).resolve().parents[1] / "data" / "siconos-lcp"  # Siconos LCPs
DEFAULT = PROFILES["default"]
METHODS = list(sb.METHODS)
#: What the bridge accepts as SOLVED under the default settings.
ACCEPT = sb.ACCEPT_SLACK * sb.ACCEPT_TOL


def read_dense_dat(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Private reader of a dense Siconos LCP ``.dat`` file (see the README).

    Tokens after ``#`` are comments; the matrix is stored COLUMN-MAJOR;
    anything after q (free-text remarks) is ignored.
    """
    toks: list[str] = []
    for line in path.read_text().splitlines():
        toks += line.split("#", 1)[0].split()
    n, storage = int(toks[0]), int(toks[1])
    assert storage == 0, f"{path.name} is not dense"
    s0, s1 = int(toks[2]), int(toks[3])
    start = 6
    vals = np.array(toks[start:start + s0 * s1], dtype=float)
    M = vals.reshape(s1, s0).T  # M[i, j] = vals[i + j * s0]
    q = np.array(toks[start + s0 * s1:start + s0 * s1 + n], dtype=float)
    assert M.shape == (n, n) and q.shape == (n,)
    return M, q


def peer_problems() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    out = {}
    for path in sorted(PEER.glob("lcp_*.dat")):
        if path.stem.endswith("_block"):
            continue
        out[path.stem[len("lcp_"):]] = read_dense_dat(path)
    return out


@pytest.fixture(scope="module")
def peers():
    if not PEER.is_dir():
        pytest.skip(f"peer collection not found at {PEER}")
    return peer_problems()


def pentadiagonal(n: int) -> np.ndarray:
    """SPD pentadiagonal D'D (D: second difference), conditioned like n^4."""
    D = np.diff(np.eye(n + 2), 2, axis=0)[:, 1:-1]
    return D.T @ D


# -- small problems with known answers -------------------------------------------
@pytest.mark.parametrize("method", METHODS)
def test_symmetric_2x2(method):
    # z > 0 on both rows: M z = -q, z = (4/3, 7/3).
    M = np.array([[2.0, 1.0], [1.0, 2.0]])
    q = np.array([-5.0, -6.0])
    sol = sb.solve_lcp(M, q, DEFAULT, method=method)
    assert sol.status is Status.SOLVED, sol.message
    np.testing.assert_allclose(sol.z, [4 / 3, 7 / 3], atol=1e-5)
    np.testing.assert_allclose(sol.w, M @ sol.z + q, atol=1e-12)
    # Siconos' enumeration leaves its iteration count (iparam ITER_DONE) at 0
    assert sol.iterations >= (0 if method == "enum" else 1)
    assert 0.0 <= sol.solve_time < 1.0 and 0.0 <= sol.setup_time < 1.0


@pytest.mark.parametrize("method", METHODS)
def test_nonsymmetric_2x2_is_not_transposed(method):
    # M upper triangular: z = (0, 1), w = (1, 0). The transpose gives z = (1, 0).
    M = np.array([[1.0, 2.0], [0.0, 1.0]])
    q = np.array([-1.0, -1.0])
    sol = sb.solve_lcp(M, q, DEFAULT, method=method)
    assert sol.status is Status.SOLVED, sol.message
    np.testing.assert_allclose(sol.z, [0.0, 1.0], atol=1e-5)
    np.testing.assert_allclose(sol.w, [1.0, 0.0], atol=1e-5)


@pytest.mark.parametrize("method", METHODS)
def test_nonnegative_q_gives_zero(method):
    M = pentadiagonal(7)
    q = np.linspace(0.0, 3.0, 7)
    sol = sb.solve_lcp(M, q, DEFAULT, method=method)
    assert sol.status is Status.SOLVED
    np.testing.assert_array_equal(sol.z, 0.0)
    np.testing.assert_allclose(sol.w, q)


def test_sparse_input_is_densified():
    sp = pytest.importorskip("scipy.sparse")
    M = np.array([[2.0, 1.0], [1.0, 2.0]])
    sol = sb.solve_lcp(sp.csc_matrix(M), [-5.0, -6.0], DEFAULT)
    assert sol.solved
    np.testing.assert_allclose(sol.z, [4 / 3, 7 / 3], atol=1e-12)


def test_settings_reach_siconos():
    M = pentadiagonal(30)
    q = -np.ones(30)
    sol = sb.solve_lcp(M, q, Settings("t", 1e-8, max_iter=5), method="pgs")
    assert sol.status is Status.MAX_ITER, sol.message
    assert sol.iterations == 5
    assert sol.extra["siconos_tol"] == 1e-8 and sol.extra["siconos_max_iter"] == 5
    # Defaults are Siconos's own: 1e-6 and 10000 sweeps for PGS.
    dflt = sb.solve_lcp(M, q, DEFAULT, method="pgs", timeout=30)
    assert dflt.extra["siconos_tol"] == 1e-6 and dflt.extra["siconos_max_iter"] == 10000


def test_warm_start_is_used_by_pgs():
    M = pentadiagonal(10) + np.eye(10)
    q = np.cos(np.arange(10.0)) - 0.2
    cold = sb.solve_lcp(M, q, PROFILES["high"], method="pgs")
    assert cold.solved
    warm = sb.solve_lcp(M, q, PROFILES["high"], warm=cold.z, method="pgs")
    assert warm.solved and warm.iterations <= 2 < cold.iterations


def test_unknown_method_is_a_caller_error():
    with pytest.raises(ProblemError):
        sb.solve_lcp(np.eye(2), -np.ones(2), DEFAULT, method="simplex")


def test_version_and_worker_info():
    v = sb.version()
    assert v and v[0].isdigit()
    info = sb.worker_info()
    assert info["ok"] and info["start_time"] > 0


# -- the peer collection -----------------------------------------------------------
def test_reader_sees_17_dense_problems(peers):
    assert len(peers) == 17
    M, q = peers["exp_murty"]
    assert np.allclose(M, np.triu(M)) and not np.allclose(M, M.T)  # column-major read


def test_lemke_on_peer_collection_matches_readme(peers):
    names = list(peers)
    sols = dict(zip(names, sb.solve_many([peers[k] for k in names], DEFAULT, method="lemke")))
    solved = {k for k, s in sols.items() if s.solved}
    assert len(solved) == 15, sorted(set(names) - solved)
    assert sols["CPS_3"].status is Status.RAY
    assert "secondary ray" in sols["CPS_3"].message
    assert not sols["Pang_isolated_sol_perturbed"].solved
    assert sols["exp_murty2"].iterations == 63
    assert sols["tobenna"].iterations == 126


@pytest.mark.parametrize("method", METHODS)
def test_no_wrong_answer_is_marked_solved(peers, method):
    names = list(peers)
    sols = sb.solve_many([peers[k] for k in names], DEFAULT, method=method, timeout=30)
    assert len(sols) == len(names)
    for name, sol in zip(names, sols):
        assert isinstance(sol.status, Status)
        if sol.status is Status.SOLVED:
            M, q = peers[name]
            r = lcp_residuals(M, q, sol.z)
            assert r["natural"] <= ACCEPT, (method, name, r)
            assert r["min_z"] >= -1e-10, (method, name, r)
        else:
            assert sol.message, (method, name)


# -- robustness of the bridge --------------------------------------------------------
def test_timeout_kills_the_worker_and_next_call_restarts():
    sb.worker_info()
    pid = sb._worker_pid()
    n = 300
    sol = sb.solve_lcp(pentadiagonal(n), -np.ones(n), Settings("t", 1e-14, max_iter=10**6),
                       method="pgs", timeout=0.2)
    assert sol.status is Status.FAILED
    assert "timeout" in sol.message
    assert sb._worker_pid() is None
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
    again = sb.solve_lcp(np.eye(2), -np.ones(2), DEFAULT)
    assert again.solved and sb._worker_pid() not in (None, pid)


def test_worker_killed_between_calls_is_restarted():
    sb.worker_info()
    pid = sb._worker_pid()
    os.kill(pid, signal.SIGKILL)
    deadline = time.monotonic() + 5
    while sb._worker_pid() is not None and time.monotonic() < deadline:
        time.sleep(0.01)
    sol = sb.solve_lcp(np.eye(2), -np.ones(2), DEFAULT)
    assert sol.solved
    assert sb._worker_pid() not in (None, pid)


def test_worker_crash_mid_call_gives_failed():
    sb.worker_info()
    pid = sb._worker_pid()
    timer = threading.Timer(0.15, os.kill, (pid, signal.SIGKILL))
    timer.start()
    try:
        n = 300
        sol = sb.solve_lcp(pentadiagonal(n), -np.ones(n),
                           Settings("t", 1e-14, max_iter=10**6), method="pgs", timeout=20)
    finally:
        timer.cancel()
    assert sol.status is Status.FAILED
    assert "died" in sol.message
    assert sb.solve_lcp(np.eye(2), -np.ones(2), DEFAULT).solved


def test_missing_installation_gives_failed(monkeypatch, tmp_path):
    monkeypatch.setenv("LCPBENCH_SICONOS_PYTHON", str(tmp_path / "no-python"))
    assert not sb.available() and sb.version() is None
    sol = sb.solve_lcp(np.eye(2), -np.ones(2), DEFAULT)
    assert sol.status is Status.FAILED
    assert sol.message == sb.NOT_INSTALLED


def test_threads_share_the_worker():
    M = np.array([[2.0, 1.0], [1.0, 2.0]])
    results = []

    def run(k):
        for _ in range(5):
            sol = sb.solve_lcp(M, np.array([-5.0, -6.0]) * k, DEFAULT)
            results.append((k, sol))

    threads = [threading.Thread(target=run, args=(k,)) for k in (1, 2, 3, 4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(results) == 20
    for k, sol in results:
        assert sol.solved
        np.testing.assert_allclose(sol.z, np.array([4 / 3, 7 / 3]) * k, atol=1e-10)


# -- enumeration: exact where it can run, refused where it cannot ----------------------------
def test_enumeration_matches_lcpbench_enumeration_and_refuses_large_n():
    from lcpbench.solvers.enumeration import enumerate_lcp

    rng = np.random.default_rng(7)
    A = rng.normal(size=(10, 10))
    M = A @ A.T + 0.5 * np.eye(10)  # SPD: exactly one solution
    q = rng.normal(size=10)
    (ref,) = enumerate_lcp(M, q)
    big = pentadiagonal(sb.ENUM_MAX_N + 1)
    small, large = sb.solve_many([(M, q), (big, -np.ones(big.shape[0]))], DEFAULT,
                                 method="enum")
    assert small.status is Status.SOLVED, small.message
    np.testing.assert_allclose(small.z, ref, atol=1e-9)
    assert large.status is Status.FAILED and f"> {sb.ENUM_MAX_N}" in large.message
