"""Worker run by the SYSTEM interpreter to call Siconos numerics LCP solvers.

This file is a script, not part of the lcpbench import graph: it is executed
as ``/usr/bin/python3 -I _siconos_worker.py`` by
:mod:`lcpbench.solvers.siconos_bridge` and imports only the standard library,
numpy, siconos and, by file path, :mod:`lcpbench.worker` (standard library
only) -- never the lcpbench package, which is not installed for that
interpreter.

Protocol (length-prefixed messages of :mod:`lcpbench.worker`)
-------------------------------------------------------------
Every message is one JSON line followed by raw little-endian float64 data.
On start the worker sends ``{"ok": true, "version": ..., "import_time": ...}``
or ``{"ok": false, "error": ...}``.

A request::

    {"op": "solve", "method": "LEMKE", "tol": null | float,
     "max_iter": null | int, "problems": [{"n": n, "warm": bool}, ...]}
    then per problem: M (n*n, column-major: Siconos's own dense storage,
    which it copies fastest), q (n), and z0 (n) if "warm"

The reply is ``{"ok": true, "results": [...]}`` (one dict per problem:
``info`` (as the Siconos driver returns it), ``solver_info`` (the solver's
own, before the driver's error check), ``iterations``, ``residu``, ``tol``,
``max_iter``, ``solve_time``, ``setup_time``, ``error``; for Lemke
``gap_min``/``gap_max`` of ``w_basic - (M z + q)``) followed by z (n) and w
(n) of every problem. ``{"op": "ping"}`` answers the start message again;
``{"op": "exit"}`` or end of input stops the worker. ``{"op": "fc2d", "method":
"NSGS" | "LEMKE" | "ENUM", "tol", "max_iter", "problems": [{"nc": nc}, ...]}`` then per
problem W (2nc × 2nc, column-major), q (2nc), mu (nc) solves 2-D frictional contact
problems (``fc2d_driver``); the reply carries ``info``, ``iterations``, ``residu`` per
problem, then r and u (2nc each) of every problem.

Siconos's C code prints to file descriptor 1 (e.g. NewtonMin on
non-convergence), so the protocol uses a duplicate of the original stdout and
fd 1 is redirected to stderr before siconos is imported
(:func:`lcpbench.worker.child_channel`). The worker dies with the process
that started it (:func:`lcpbench.worker.die_with_parent`).
"""

import json
import os
import sys
import time

import numpy as np

_CHANNEL = None  # (input, output) of the protocol, set in main()


def _load_worker_module():
    """lcpbench/worker.py, loaded by path (lcpbench is not importable here)."""
    import importlib.util

    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                        "worker.py")
    spec = importlib.util.spec_from_file_location("_lcpbench_worker", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


_W = None  # the lcpbench.worker module


def _send(header, arrays=()):
    data = [json.dumps(header).encode() + b"\n"]
    data.extend(np.ascontiguousarray(a, dtype="<f8").tobytes() for a in arrays)
    _W.write_message(_CHANNEL[1], b"".join(data))


class _Reader:
    """Arrays read one after the other from a request's float64 data."""

    def __init__(self, data):
        self.data, self.at = data, 0

    def array(self, shape, order="C"):
        n = int(np.prod(shape))
        end = self.at + 8 * n
        if end > len(self.data):
            raise EOFError("request shorter than its header says")
        flat = np.frombuffer(self.data[self.at:end], dtype="<f8")
        self.at = end
        return np.array(flat.reshape(shape, order=order), order=order)


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


def _solve_fc2d(sn, name, W, q, mu, tol, max_iter):
    """One 2-D frictional contact problem u = W r + q, r in the Coulomb cones (fc2d)."""
    nc = mu.size
    res = {"info": -1, "iterations": 0, "residu": None, "solve_time": 0.0, "error": None}
    r, u = np.zeros(2 * nc), np.zeros(2 * nc)
    try:
        problem = sn.FrictionContactProblem(2, nc, W, q, mu)
        options = sn.SolverOptions(getattr(sn, "SICONOS_FRICTION_2D_" + name))
        if tol is not None:
            options.dparam[sn.SICONOS_DPARAM_TOL] = tol
        if max_iter is not None:
            options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = max_iter
        t0 = time.perf_counter()
        res["info"] = int(sn.fc2d_driver(problem, r, u, options))
        res["solve_time"] = time.perf_counter() - t0
        res["iterations"] = int(options.iparam[sn.SICONOS_IPARAM_ITER_DONE])
        res["residu"] = float(options.dparam[sn.SICONOS_DPARAM_RESIDU])
    except Exception as exc:  # a Siconos error must not kill the worker
        res["error"] = f"{type(exc).__name__}: {exc}"
    return res, r, u


def _fc2d_request(sn, req, data):
    """The ``fc2d`` op: per problem W (2nc × 2nc, column-major), q (2nc), mu (nc)."""
    reader, results, arrays = _Reader(data), [], []
    for p in req["problems"]:
        m = 2 * int(p["nc"])
        W = reader.array((m, m), order="F")
        q = reader.array((m,))
        mu = reader.array((m // 2,))
        res, r, u = _solve_fc2d(sn, str(req["method"]), W, q, mu, req.get("tol"),
                                req.get("max_iter"))
        results.append(res)
        arrays += [r, u]
    _send({"ok": True, "results": results}, arrays)


def main():
    global _CHANNEL, _W
    _W = _load_worker_module()
    _W.die_with_parent()
    _CHANNEL = _W.child_channel()
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
        msg = _W.read_message(_CHANNEL[0])
        if msg is None:
            return 0
        i = msg.find(b"\n")
        line, data = (msg, b"") if i < 0 else (msg[:i], memoryview(msg)[i + 1:])
        req = json.loads(line)
        op = req.get("op")
        if op == "exit":
            return 0
        if op == "ping":
            _send(hello)
            continue
        if op == "fc2d":  # (issue 39: the frictional step's peers)
            _fc2d_request(sn, req, data)
            continue
        if op != "solve":
            _send({"ok": False, "error": f"unknown op {op!r}"})
            continue
        problems = []
        reader = _Reader(data)
        for p in req["problems"]:
            n = int(p["n"])
            M = reader.array((n, n), order="F")
            q = reader.array((n,))
            z0 = reader.array((n,)) if p.get("warm") else None
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
