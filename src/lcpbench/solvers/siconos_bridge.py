"""Siconos numerics LCP solvers, reached through a subprocess bridge.

Siconos (INRIA's C library for nonsmooth problems) installs for the *system*
interpreter -- Debian's ``python3-siconos`` puts it in
``/usr/lib/python3/dist-packages`` -- not for the project's Python. So the
solvers are run by a persistent worker process (``_siconos_worker.py``,
executed by :func:`system_python` through :class:`lcpbench.worker.WorkerProcess`,
the package's one subprocess worker) that exchanges length-prefixed messages
over its stdin/stdout: one JSON header line, then raw little-endian float64
arrays.

The worker is started lazily on the first call, reused by later calls
(guarded by a lock, so threads share it safely), restarted if it died, and
stopped at interpreter exit. A call that crashes the worker or runs past its
``timeout`` kills it and returns FAILED; the next call starts a new one.

Back-ends (our name -> Siconos solver ``SICONOS_LCP_<name>``), see
:data:`METHODS`: ``lemke`` (lexicographic Lemke), ``pgs`` (projected
Gauss-Seidel), ``newton-min`` (semismooth Newton on min(z, w)), ``newton-fb``
(Newton on the Fischer-Burmeister function with a line search), ``enum``
(enumeration of complementary bases, n ≤ :data:`ENUM_MAX_N`), and the
pivot rules ``murty`` (least index), ``bard`` and ``pathsearch``.
Not here: ``PATH`` (the Debian build has no PATH library: SICONOS_LCP_PATH
returns info 1 after 0 iterations on every problem, even a 2×2 SPD one),
``PIVOT`` with the path-search rule (aborts the process on a 12×12 SPD
problem: an assertion in lcp_pivot_covering_vector) and ``PIVOT_LUMOD``
(fails that 12×12 SPD problem).

Install with ``apt-get install python3-siconos``.
"""

from __future__ import annotations

import atexit
import glob
import gzip
import json
import os
import re
import tempfile
import threading
import time
from functools import cache
from pathlib import Path

import numpy as np

from lcpbench.errors import ProblemError
from lcpbench.solvers.base import LCPSolution, Settings, Status, lcp_residuals
from lcpbench.worker import WorkerDied, WorkerProcess

#: Our method names -> the worker's names (the suffix of ``SICONOS_LCP_*``).
METHODS: dict[str, str] = {
    "lemke": "LEMKE",
    "pgs": "PGS",
    "newton-min": "NEWTONMIN",
    "newton-fb": "NEWTON_FB_FBLSA",
    "enum": "ENUM",
    "murty": "MURTY",
    "bard": "BARD",
    "pathsearch": "PATHSEARCH",
}
#: Largest n enumerated: 2^n complementary bases (2^20 ≈ 1e6 small solves).
ENUM_MAX_N = 20

#: Floor of the lcpbench natural residual accepted as SOLVED.
ACCEPT_TOL = 1e-6
#: Slack on the accepted residual: Siconos measures ``||z - max(0, z - w)||_2
#: / ||q||_2``, lcpbench the max-norm scaled by ``max(1, |q|_inf)``; the two
#: differ by up to ``sqrt(n)``.
ACCEPT_SLACK = 10.0
#: Seconds allowed for the worker to start and import siconos.
STARTUP_TIMEOUT = 60.0

NOT_INSTALLED = "siconos not installed: apt-get install python3-siconos"
_WORKER_SCRIPT = Path(__file__).with_name("_siconos_worker.py")
_DEFAULT_PYTHON = "/usr/bin/python3"
_DEBIAN_DIST = "/usr/lib/python3/dist-packages"


# -- discovery (no subprocess, no native import) --------------------------------
def system_python() -> str | None:
    """The interpreter that runs the worker, or None.

    ``$LCPBENCH_SICONOS_PYTHON`` if set (returned even if it does not exist,
    so a wrong setting shows up as "not installed"), else ``/usr/bin/python3``
    if it exists.
    """
    env = os.environ.get("LCPBENCH_SICONOS_PYTHON")
    if env:
        return env
    return _DEFAULT_PYTHON if os.path.exists(_DEFAULT_PYTHON) else None


def _site_dirs(python: str) -> list[str]:
    """Directories where ``python`` may find packages, guessed from its path."""
    prefix = os.path.dirname(os.path.dirname(os.path.realpath(python)))
    dirs = []
    for base in {prefix, os.path.dirname(os.path.dirname(python))}:
        dirs += glob.glob(os.path.join(base, "lib", "python3*", "site-packages"))
        dirs += glob.glob(os.path.join(base, "lib", "python3*", "dist-packages"))
    if prefix in ("/usr", "/usr/local") or python == _DEFAULT_PYTHON:
        dirs += [_DEBIAN_DIST] + glob.glob("/usr/local/lib/python3*/dist-packages")
    return list(dict.fromkeys(dirs))


def _package_dir(python: str | None) -> str | None:
    """The ``siconos`` package directory ``python`` would import, or None."""
    if not python or not os.path.isfile(python) or not os.access(python, os.X_OK):
        return None
    for d in _site_dirs(python):
        pkg = os.path.join(d, "siconos")
        if (os.path.isfile(os.path.join(pkg, "numerics.py"))
                and glob.glob(os.path.join(pkg, "_numerics*.so"))):
            return pkg
    return None


def available() -> bool:
    """True if the system interpreter and its siconos package are present.

    Cheap: looks at files only (no subprocess, no import of native code).
    A True here can still fail at import time (broken install); :func:`solve_lcp`
    then returns FAILED with the import error.
    """
    return _package_dir(system_python()) is not None


@cache
def _version_of(pkg: str) -> str | None:
    if pkg.startswith(_DEBIAN_DIST + "/"):
        v = _dpkg_version("python3-siconos")
        if v:
            return v
    try:
        text = Path(pkg, "__init__.py").read_text(errors="replace")
    except OSError:
        return None
    m = re.search(r"""^version\s*=\s*['"]([^'"]+)['"]""", text, re.M)
    return m.group(1) if m else None


def _dpkg_version(package: str) -> str | None:
    """Version of a Debian package from dpkg's database, without running dpkg."""
    try:
        with open("/var/lib/dpkg/status", encoding="utf-8", errors="replace") as fh:
            stanza = fh.read().split(f"\nPackage: {package}\n", 1)
    except OSError:
        stanza = []
    if len(stanza) == 2:
        block = stanza[1].split("\n\n", 1)[0]
        if "install ok installed" in block:
            m = re.search(r"^Version: (\S+)", block, re.M)
            if m:
                return m.group(1)
    try:  # fall back on the packaged changelog: "siconos (4.4.0+dfsg-2) unstable; ..."
        with gzip.open(f"/usr/share/doc/{package}/changelog.Debian.gz", "rt") as fh:
            m = re.match(r"\S+ \(([^)]+)\)", fh.readline())
        return m.group(1) if m else None
    except OSError:
        return None


def version() -> str | None:
    """Version of the siconos the worker would use, or None if not installed.

    For the Debian package this is the package version (e.g. ``4.4.0+dfsg-2``;
    note its ``siconos.version`` attribute says ``4.5.0``); otherwise the
    ``version`` string in the package's ``__init__.py``. Files only, cached.
    """
    pkg = _package_dir(system_python())
    return _version_of(pkg) if pkg else None


# -- the worker -----------------------------------------------------------------
_WorkerDied = WorkerDied


def _pack(header: dict, arrays=()) -> bytes:
    """A message of the worker's protocol: a JSON line, then raw float64 arrays."""
    parts = [json.dumps(header).encode() + b"\n"]
    parts += [np.ascontiguousarray(a, dtype="<f8").tobytes() for a in arrays]
    return b"".join(parts)


def _unpack(msg: bytes) -> tuple[dict, np.ndarray]:
    i = msg.find(b"\n")
    if i < 0:
        raise ValueError("a reply without its header line")
    data = msg[i + 1:]
    if len(data) % 8:
        raise ValueError("a reply whose data is not float64")
    return json.loads(msg[:i]), np.frombuffer(data, dtype="<f8").astype(float)


class _Worker:
    """One running worker process (:class:`lcpbench.worker.WorkerProcess`) and its stderr."""

    def __init__(self, python: str):
        self.python = python
        self.err = tempfile.TemporaryFile()
        t0 = time.perf_counter()
        # isolated (-I), so the project's PYTHONPATH / user site cannot leak into
        # the system interpreter and the script's own directory is not on sys.path
        self.proc = WorkerProcess([str(_WORKER_SCRIPT)], python=python, stderr=self.err,
                                  isolated=True)
        try:
            self.hello, _ = _unpack(self.proc.recv(time.monotonic() + STARTUP_TIMEOUT))
        except BaseException:
            self.kill(force=True)
            raise
        self.start_time = time.perf_counter() - t0

    def alive(self) -> bool:
        return self.proc.alive()

    def stderr_tail(self, limit: int = 600) -> str:
        try:
            self.err.seek(0)
            text = self.err.read().decode(errors="replace").strip()
        except (OSError, ValueError):
            return ""
        return text[-limit:]

    def kill(self, force: bool = False) -> None:
        """Stop the worker: close its input and wait briefly, or (``force``,
        for a hung or misbehaving worker) SIGKILL it at once."""
        if self.proc.owner != os.getpid():
            return  # a forked child must not kill its parent's worker
        if force:
            self.proc.kill()
        else:
            self.proc.stop(1.0)
        self.err.close()

    def request(self, header: dict, payload: list[np.ndarray], deadline: float
                ) -> tuple[dict, np.ndarray]:
        """Send a request and return the reply's header and its float64 data.

        Neither writing nor reading blocks past ``deadline``, so a hung worker
        cannot block the caller. The worker's stderr file is emptied first,
        so a crash report shows this request's messages only.
        """
        try:
            self.err.seek(0)
            self.err.truncate()
        except (OSError, ValueError):
            pass
        self.proc.send(_pack(header, payload), deadline)
        return _unpack(self.proc.recv(deadline))


_LOCK = threading.Lock()
_WORKER: _Worker | None = None
_STATS = {"starts": 0, "last_start_time": None}


def _get_worker(python: str) -> _Worker:
    global _WORKER
    if _WORKER is not None and (not _WORKER.alive() or _WORKER.python != python):
        _WORKER.kill()
        _WORKER = None
    if _WORKER is None:
        w = _Worker(python)
        if not w.hello.get("ok"):
            err = w.hello.get("error")
            w.kill()
            raise ImportError(f"siconos failed to import under {python}: {err}")
        _WORKER = w
        _STATS["starts"] += 1
        _STATS["last_start_time"] = w.start_time
    return _WORKER


def shutdown() -> None:
    """Stop the worker process (it restarts on the next call)."""
    global _WORKER
    with _LOCK:
        if _WORKER is not None:
            _WORKER.kill()
            _WORKER = None


atexit.register(shutdown)


def worker_info() -> dict:
    """Start the worker if needed and return its hello (version, import time, pid),
    plus ``start_time`` (seconds to spawn it and import siconos) and ``starts``.

    Raises ``RuntimeError`` if siconos cannot be started (unlike the solvers).
    """
    python = system_python()
    if not available():
        raise RuntimeError(NOT_INSTALLED)
    with _LOCK:
        try:
            w = _get_worker(python)
        except (ImportError, TimeoutError, _WorkerDied, OSError, ValueError) as exc:
            raise RuntimeError(f"siconos worker failed to start: {exc!r}") from None
        return {**w.hello, "start_time": w.start_time, "starts": _STATS["starts"]}


def _worker_pid() -> int | None:
    """pid of the running worker, if any (for tests)."""
    w = _WORKER
    return w.proc.pid if w is not None and w.alive() else None


# -- solving --------------------------------------------------------------------
def _failed(n: int, message: str, **kw) -> LCPSolution:
    nan = np.full(n, np.nan)
    return LCPSolution(z=nan, w=nan.copy(), status=Status.FAILED, message=message, **kw)


def _as_problem(M, q) -> tuple[np.ndarray, np.ndarray]:
    M = np.asarray(M.toarray() if hasattr(M, "toarray") else M, dtype=float)
    q = np.asarray(q, dtype=float).ravel()
    n = q.size
    if n == 0 or M.shape != (n, n):
        raise ProblemError(f"M has shape {M.shape}, expected ({n}, {n}) with n >= 1")
    return M, q


def _judge(M, q, z, w, res: dict, method: str, accept_tol: float) -> LCPSolution:
    """Map the worker's result for one problem onto lcpbench's status set."""
    info = res["info"]
    extra = {"siconos_info": info, "siconos_solver_info": res.get("solver_info"),
             "siconos_residual": res["residu"],
             "siconos_tol": res["tol"], "siconos_max_iter": res["max_iter"],
             "method": method}
    sol = LCPSolution(z=z, w=w, status=Status.SOLVED, iterations=res["iterations"],
                      solve_time=res["solve_time"], setup_time=res["setup_time"],
                      extra=extra)
    if res["error"]:
        sol.status, sol.message = Status.FAILED, f"siconos error: {res['error']}"
        return sol
    if not (np.all(np.isfinite(z)) and np.all(np.isfinite(w))):
        sol.status = Status.FAILED
        sol.message = f"siconos {method}: non-finite solution (info={info})"
        return sol
    with np.errstate(all="ignore"):
        r = lcp_residuals(M, q, z)
    extra["residuals"] = r
    it, max_iter = res["iterations"], res["max_iter"]
    ok = r["natural"] <= accept_tol
    err = "n/a" if res["residu"] is None else f"{res['residu']:.3g}"
    if info == 0:
        if not ok:
            sol.status = Status.INACCURATE
            sol.message = (f"siconos {method} reports success (info=0) but the lcpbench "
                           f"natural residual is {r['natural']:.3g} > {accept_tol:.1e}")
    elif max_iter is not None and it >= max_iter:
        sol.status = Status.MAX_ITER
        sol.message = (f"siconos {method}: iteration limit {max_iter} reached "
                       f"(info={info}, error {err})")
    elif ok:
        sol.status = Status.INACCURATE
        sol.message = (f"siconos {method}: its error {err} exceeds its tolerance "
                       f"{res['tol']:.1e} (info={info}); lcpbench residual "
                       f"{r['natural']:.3g} is within {accept_tol:.1e}")
    elif method == "lemke":
        z0 = _lemke_artificial(res, q)
        extra["siconos_z0"] = z0
        if z0 is not None:
            sol.status = Status.RAY
            sol.message = (f"siconos lemke: secondary ray after {it} pivots, artificial "
                           f"z0 = {z0:.3g} still basic (info={info}, error {err}); "
                           f"the LCP may be infeasible")
        else:
            sol.status = Status.INACCURATE
            sol.message = (f"siconos lemke: complementary basis after {it} pivots fails "
                           f"its error check: error {err} > {res['tol']:.1e} (info={info}), "
                           f"lcpbench natural residual {r['natural']:.3g}")
    else:
        why = _INFO_TEXT.get((method, info), "no convergence")
        sol.status = Status.FAILED
        sol.message = f"siconos {method}: {why} (info={info}, {it} iterations, error {err})"
    return sol


def _lemke_artificial(res: dict, q: np.ndarray) -> float | None:
    """Value of Lemke's artificial variable z0 if it was still basic, else None.

    Siconos 4.4's Lemke returns the basic ``w``, which equals
    ``M z + q + z0 * 1`` while z0 is basic (a secondary ray); after a proper
    termination it equals ``M z + q`` up to round-off. A ray shows as a
    positive, (nearly) constant difference.
    """
    lo, hi = res.get("gap_min"), res.get("gap_max")
    if lo is None or hi is None:
        return None
    floor = 1e3 * np.finfo(float).eps * max(1.0, float(np.abs(q).max()))
    if lo > floor and hi - lo <= 1e-6 * hi + floor:
        return 0.5 * (lo + hi)
    return None


#: Known Siconos info codes other than 0 (success) and 1 (no convergence).
_INFO_TEXT = {
    ("pgs", 2): "vanishing diagonal term, PGS not applicable",
    ("newton-min", 2): "singular Newton system (DGESV failed)",
}


def solve_many(problems, settings: Settings, *, method: str = "lemke",
               warm=None, timeout: float = 60.0,
               accept_tol: float | None = None) -> list[LCPSolution]:
    """Solve several LCPs with one Siconos solver in one round trip.

    Parameters
    ----------
    problems : sequence of (M, q)
        Dense (or scipy sparse, densified) matrices and vectors; sizes may differ.
    settings : Settings
        ``eps`` None keeps Siconos's default tolerance (``dparam[TOL]``: 1e-6
        for Lemke, PGS and NewtonMin, 1e-10 for NewtonFB), else it is set to
        ``settings.eps``; ``max_iter`` None keeps Siconos's default iteration
        limit (``iparam[MAX_ITER]``: 10000 for Lemke pivots and PGS sweeps,
        1000 for the Newton methods). ``time_limit`` is not supported by
        Siconos and is ignored; use ``timeout``.
    method : str
        A key of :data:`METHODS`.
    warm : sequence of (ndarray or None), optional
        Initial z per problem (see :func:`solve_lcp`).
    timeout : float
        Seconds for the whole batch (worker start-up excluded); on expiry the
        worker is killed and every problem not yet answered gets FAILED.
    accept_tol : float, optional
        Largest lcpbench natural residual accepted as SOLVED, default
        ``ACCEPT_SLACK * max(ACCEPT_TOL, settings.eps)``.

    Returns
    -------
    list of LCPSolution
        One per problem, in order; see :func:`solve_lcp`.

    Raises
    ------
    ProblemError
        Unknown ``method`` or inconsistent shapes (caller errors).
    """
    global _WORKER
    if method not in METHODS:
        raise ProblemError(f"unknown siconos method {method!r}; available: {', '.join(METHODS)}")
    probs = [_as_problem(M, q) for M, q in problems]
    warms = [None] * len(probs) if warm is None else list(warm)
    if len(warms) != len(probs):
        raise ProblemError("warm must have one entry per problem")
    for i, ((_, q), z0) in enumerate(zip(probs, warms)):
        if z0 is not None:
            warms[i] = np.asarray(z0, dtype=float).ravel()
            if warms[i].shape != q.shape:
                raise ProblemError(f"warm start {i} has shape {warms[i].shape}, expected {q.shape}")
    if accept_tol is None:
        accept_tol = ACCEPT_SLACK * max(ACCEPT_TOL, settings.eps or 0.0)
    if not probs:
        return []
    if method == "enum" and any(q.size > ENUM_MAX_N for _, q in probs):
        # one batch, one method: too large for any is answered for each, nothing sent
        big = [q.size > ENUM_MAX_N for _, q in probs]
        small = [(p, z0) for p, z0, b in zip(problems, warms, big) if not b]
        done = iter(solve_many([p for p, _ in small], settings, method=method,
                               warm=[z0 for _, z0 in small], timeout=timeout,
                               accept_tol=accept_tol))
        return [_failed(q.size, f"siconos enum: n = {q.size} > {ENUM_MAX_N}, 2^n complementary "
                                "bases are beyond reach") if b else next(done)
                for (_, q), b in zip(probs, big)]

    python = system_python()
    if not available():
        return [_failed(q.size, NOT_INSTALLED) for _, q in probs]

    header = {"op": "solve", "method": METHODS[method], "tol": settings.eps,
              "max_iter": settings.max_iter,
              "problems": [{"n": q.size, "warm": z0 is not None}
                           for (_, q), z0 in zip(probs, warms)]}
    payload = []
    for (M, q), z0 in zip(probs, warms):
        payload += [M.T, q] + ([z0] if z0 is not None else [])  # M column-major

    with _LOCK:
        try:
            worker = _get_worker(python)
        except ImportError as exc:
            return [_failed(q.size, f"{NOT_INSTALLED} ({exc})") for _, q in probs]
        except (TimeoutError, _WorkerDied, OSError, ValueError) as exc:
            reason = "timed out" if isinstance(exc, TimeoutError) else f"died ({exc!r})"
            return [_failed(q.size, f"siconos worker start-up {reason}") for _, q in probs]
        t0 = time.perf_counter()
        deadline = time.monotonic() + timeout
        try:
            reply, data = worker.request(header, payload, deadline)
            if not reply.get("ok"):
                return [_failed(q.size, f"siconos worker: {reply.get('error')}") for _, q in probs]
            if data.size != 2 * sum(q.size for _, q in probs):
                raise ValueError(f"{data.size} numbers for {len(probs)} problems")
            answers, at = [], 0
            for (_, q), res in zip(probs, reply["results"]):
                z, w = data[at:at + q.size], data[at + q.size:at + 2 * q.size]
                at += 2 * q.size
                answers.append((z.copy(), w.copy(), res))
        except (TimeoutError, _WorkerDied, OSError, ValueError) as exc:
            if isinstance(exc, TimeoutError):
                reason = f"siconos worker exceeded the {timeout:g} s timeout and was killed"
            elif isinstance(exc, ValueError) and worker.proc.returncode is None:
                reason = f"siconos worker sent a malformed reply ({exc}); killed"
            else:
                code = worker.proc.returncode
                tail = worker.stderr_tail()
                reason = (f"siconos worker died (exit code {code})"
                          + (f": {tail}" if tail else ""))
            worker.kill(force=True)
            _WORKER = None
            return [_failed(q.size, reason) for _, q in probs]
        wall = time.perf_counter() - t0

    out = []
    for (M, q), (z, w, res) in zip(probs, answers):
        sol = _judge(M, q, z, w, res, method, accept_tol)
        sol.extra["wall_time"] = wall / len(probs)
        out.append(sol)
    return out


def solve_lcp(M, q, settings: Settings, warm=None, *, method: str = "lemke",
              timeout: float = 60.0, accept_tol: float | None = None) -> LCPSolution:
    """Solve one LCP with a Siconos numerics solver in the worker process.

    Parameters
    ----------
    M : array_like, shape (n, n)
        LCP matrix (dense; a scipy sparse matrix is densified).
    q : array_like, shape (n,)
        LCP vector.
    settings : Settings
        ``eps`` None keeps Siconos's defaults, else sets its tolerance
        ``dparam[SICONOS_DPARAM_TOL]``; ``max_iter`` sets
        ``iparam[SICONOS_IPARAM_MAX_ITER]`` (pivots for Lemke). For Lemke the
        tolerance only enters Siconos's a-posteriori error check.
        ``time_limit`` is not supported by Siconos and is ignored (see ``timeout``).
    warm : ndarray, shape (n,), optional
        Initial z, passed to Siconos as the in/out ``z`` array. PGS and
        NewtonFB start from it; Lemke and NewtonMin ignore it (Lemke starts
        from its artificial basis, NewtonMin from z = w = 1).
    method : str
        A key of :data:`METHODS` (``"lemke"``, ``"pgs"``, ``"newton-min"``,
        ``"newton-fb"``, ``"enum"``, ``"murty"``, ``"bard"``, ``"pathsearch"``).
    timeout : float
        Seconds allowed for the round trip; a worker that exceeds it is killed.
    accept_tol : float, optional
        Largest lcpbench natural residual (:func:`lcp_residuals`) accepted as
        SOLVED; default ``10 * max(1e-6, settings.eps)`` (the factor covers
        the difference between Siconos's 2-norm error and our max-norm).

    Returns
    -------
    LCPSolution
        ``z`` and ``w`` as Siconos returns them (``w = M z + q`` recomputed by
        its error check). Status: SOLVED only if Siconos reports success
        (info 0, after its own error check) *and* the lcpbench natural
        residual is at most ``accept_tol``; INACCURATE if only one of them
        holds; MAX_ITER when the iteration (pivot) limit was reached; RAY when
        Lemke stops without a complementary basis (secondary ray); FAILED for
        other solver failures, a missing installation ("siconos not installed:
        apt-get install python3-siconos"), a crashed worker or a timeout.
        ``iterations`` is Siconos's ``iparam[SICONOS_IPARAM_ITER_DONE]``;
        ``solve_time`` is measured inside the worker around the solver call
        only and ``setup_time`` around building the problem and options;
        ``extra`` holds Siconos's info codes, error, tolerance and iteration
        limit, lcpbench's residuals and ``wall_time`` (the round trip).

    Raises
    ------
    ProblemError
        Unknown ``method`` or inconsistent shapes (caller errors, not solver ones).
    """
    return solve_many([(M, q)], settings, method=method,
                      warm=None if warm is None else [warm], timeout=timeout,
                      accept_tol=accept_tol)[0]


def call_worker(header: dict, payload: list, timeout: float = 60.0) -> tuple[dict, np.ndarray]:
    """(reply, data) of one request of another op (:mod:`.siconos_fc2d`); RuntimeError if
    siconos is absent or the worker fails (it is then killed)."""
    global _WORKER
    with _LOCK:
        if not available():
            raise RuntimeError(NOT_INSTALLED)
        try:
            worker = _get_worker(system_python())
            return worker.request(header, payload, time.monotonic() + timeout)
        except (ImportError, TimeoutError, _WorkerDied, OSError, ValueError) as exc:
            _WORKER = _WORKER.kill(force=True) if _WORKER is not None else None
            raise RuntimeError(f"siconos worker failed: {exc!r}") from exc


__all__ = ["ENUM_MAX_N", "METHODS", "available", "version", "system_python", "solve_lcp",
           "solve_many", "shutdown", "worker_info", "call_worker"]
