"""Worker run by the SYSTEM interpreter to call Siconos numerics LCP solvers.

This file is a script, not part of the lcpbench import graph: it is executed
as ``/usr/bin/python3 _siconos_worker.py`` by
:mod:`lcpbench.solvers.siconos_bridge` and imports only the standard library
(``json``, ``os``, ``sys``, ``time``), numpy and siconos -- never lcpbench,
which is not installed for that interpreter.

Protocol (binary, over stdin / a private copy of stdout)
--------------------------------------------------------
On start the worker writes one JSON line, ``{"ok": true, "version": ...,
"import_time": ...}`` or ``{"ok": false, "error": ...}``.

Each request is one JSON line followed by raw little-endian float64 data::

    {"op": "solve", "method": "LEMKE", "tol": null | float,
     "max_iter": null | int, "problems": [{"n": n, "warm": bool}, ...]}
    then per problem: M (n*n, column-major: Siconos's own dense storage,
    which it copies fastest), q (n), and z0 (n) if "warm"

The reply is one JSON line ``{"ok": true, "results": [...]}`` (one dict per
problem: ``info`` (as the Siconos driver returns it), ``solver_info`` (the
solver's own, before the driver's error check), ``iterations``, ``residu``, ``tol``,
``max_iter``, ``solve_time``, ``setup_time``, ``error``; for Lemke
``gap_min``/``gap_max`` of ``w_basic - (M z + q)``) followed by z (n)
and w (n) of every problem. ``{"op": "ping"}`` answers the start line again;
``{"op": "exit"}`` or end of input stops the worker.

Siconos's C code prints to file descriptor 1 (e.g. NewtonMin on
non-convergence), so the protocol uses a duplicate of the original stdout and
fd 1 is redirected to stderr before siconos is imported.
"""

import json
import os
import sys
import time

import numpy as np

_PROTO = None  # the protocol's output: a private duplicate of the original stdout
_IN = None  # the protocol's input: stdin, binary


def _setup_streams():
    """Keep stdout for the protocol and send everything else printed to stderr.

    Done in :func:`main` only, so importing this module has no side effects.
    """
    global _PROTO, _IN
    _PROTO = os.fdopen(os.dup(1), "wb", buffering=0)
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    _IN = sys.stdin.buffer


def _send(header, arrays=()):
    data = [json.dumps(header).encode() + b"\n"]
    data.extend(np.ascontiguousarray(a, dtype="<f8").tobytes() for a in arrays)
    _PROTO.write(b"".join(data))


def _read_array(shape, order="C"):
    """Read ``prod(shape)`` little-endian float64 numbers from stdin."""
    out = np.empty(shape, dtype="<f8", order=order)
    view = memoryview(out.reshape(-1, order="A")).cast("B")
    got = 0
    while got < len(view):
        k = _IN.readinto(view[got:])
        if not k:
            raise EOFError("end of input inside a request")
        got += k
    return out


def _solve_one(sn, solver_id, M, q, z0, tol, max_iter, lemke=False):
    n = q.size
    res = {"info": -1, "solver_info": -1, "iterations": 0, "residu": None, "tol": None,
           "max_iter": None, "solve_time": 0.0, "setup_time": 0.0, "error": None}
    z = np.zeros(n) if z0 is None else np.array(z0, dtype=float)
    w = np.zeros(n)
    try:
        t0 = time.perf_counter()
        problem = sn.LCP(M, q)
        options = sn.SolverOptions(solver_id)
        if tol is not None:
            options.dparam[sn.SICONOS_DPARAM_TOL] = tol
        if max_iter is not None:
            options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = max_iter
        res["tol"] = float(options.dparam[sn.SICONOS_DPARAM_TOL])
        res["max_iter"] = int(options.iparam[sn.SICONOS_IPARAM_MAX_ITER])
        # The driver's a-posteriori check (filterOn, on by default) is run
        # separately below, exactly as the driver would run it, so that the
        # solver's own w can be seen first: for Lemke it is the basic w, and
        # w_basic - (M z + q) = z0 * 1 when the artificial variable z0 is
        # still basic, i.e. Lemke stopped on a secondary ray (Siconos 4.4
        # returns info 0 in that case and relies on the check alone).
        check = bool(options.filterOn)
        options.filterOn = False
        t1 = time.perf_counter()
        raw = int(sn.linearComplementarity_driver(problem, z, w, options))
        t2 = time.perf_counter()
        res["setup_time"] = t1 - t0
        res["solve_time"] = t2 - t1
        res["solver_info"] = raw
        res["iterations"] = int(options.iparam[sn.SICONOS_IPARAM_ITER_DONE])
        if lemke:
            gap = w - (M @ z + q)
            res["gap_min"], res["gap_max"] = float(gap.min()), float(gap.max())
        if check:  # as the driver: w = M z + q recomputed, info from the error
            err = float(sn.lcp_compute_error(problem, z, w, res["tol"]))
            res["info"] = raw if raw > 0 else int(err > res["tol"])
        else:
            err = float(sn.lcp_compute_error(problem, z, w.copy(), res["tol"]))
            res["info"] = raw
        res["residu"] = err if np.isfinite(err) else None
    except Exception as exc:  # a Siconos error must not kill the worker
        res["error"] = f"{type(exc).__name__}: {exc}"
    return res, z, w


def main():
    _setup_streams()
    t0 = time.perf_counter()
    try:
        import siconos
        import siconos.numerics as sn
    except Exception as exc:
        _send({"ok": False, "error": f"{type(exc).__name__}: {exc}"})
        return 1
    hello = {"ok": True, "version": getattr(siconos, "version", None),
             "import_time": time.perf_counter() - t0, "pid": os.getpid(),
             "python": sys.version.split()[0]}
    _send(hello)
    while True:
        line = _IN.readline()
        if not line:
            return 0
        req = json.loads(line)
        op = req.get("op")
        if op == "exit":
            return 0
        if op == "ping":
            _send(hello)
            continue
        if op != "solve":
            _send({"ok": False, "error": f"unknown op {op!r}"})
            continue
        problems = []
        for p in req["problems"]:
            n = int(p["n"])
            M = _read_array((n, n), order="F")
            q = _read_array((n,))
            z0 = _read_array((n,)) if p.get("warm") else None
            problems.append((M, q, z0))
        solver_id = getattr(sn, "SICONOS_LCP_" + str(req["method"]), None)
        if solver_id is None:
            _send({"ok": False, "error": f"siconos has no LCP solver {req['method']!r}"})
            continue
        results, arrays = [], []
        for M, q, z0 in problems:
            res, z, w = _solve_one(sn, solver_id, M, q, z0, req.get("tol"),
                                  req.get("max_iter"), lemke=solver_id == sn.SICONOS_LCP_LEMKE)
            results.append(res)
            arrays += [z, w]
        _send({"ok": True, "results": results}, arrays)


if __name__ == "__main__":
    sys.exit(main())
