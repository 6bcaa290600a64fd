"""The machine record of a sweep: what the times were measured on.

Recorded by :func:`~.sweep.sweep` when it starts (and the load average again
when it ends) into the store's ``sweeps`` table, and printed by the report:

- CPU model (py-cpuinfo's ``brand_raw``; ``/proc/cpuinfo`` or
  :func:`platform.processor` without it), cores (``os.cpu_count``) and the
  cores this process may use (``sched_getaffinity``);
- the 1, 5 and 15 minute load averages at the start and at the end;
- BLAS: threadpoolctl's view of the loaded BLAS/OpenMP libraries and their
  thread counts when threadpoolctl is installed, else numpy's build
  configuration (its BLAS and version); and the thread count the workers
  are pinned to (:data:`~.pool.SINGLE_THREAD`, 1);
- versions of Python, numpy, scipy, lcpbench and the platform;
- the sweep's workers and repeats.

:func:`overloaded` says when the load average exceeded the worker count (the
machine was busier than the sweep alone would make it), which the report
prints as a warning.
"""

from __future__ import annotations

import os
import platform
import shlex
import sys
from functools import lru_cache


@lru_cache(maxsize=1)
def cpu_model() -> str:
    """The CPU's model name (cached: py-cpuinfo takes about a second)."""
    try:
        import cpuinfo  # py-cpuinfo

        name = cpuinfo.get_cpu_info().get("brand_raw")
        if name:
            return str(name)
    except Exception:  # noqa: BLE001 - not installed, or it cannot read this machine
        pass
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.lower().startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def load_average() -> list[float] | None:
    """The 1, 5 and 15 minute load averages, or None where the OS has none."""
    try:
        return [round(v, 2) for v in os.getloadavg()]
    except (OSError, AttributeError):
        return None


@lru_cache(maxsize=1)
def blas_info() -> dict:
    """The BLAS this process uses and its threads (threadpoolctl), or numpy's build record."""
    try:
        from threadpoolctl import threadpool_info

        pools = [{k: p.get(k) for k in ("user_api", "internal_api", "version",
                                         "num_threads", "filepath")} for p in threadpool_info()]
        return {"source": "threadpoolctl", "pools": pools}
    except ImportError:
        pass
    import numpy as np

    try:
        blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
        return {"source": "numpy config", "name": blas.get("name"),
                "version": blas.get("version"),
                "configuration": blas.get("openblas configuration")}
    except Exception:  # noqa: BLE001 - older numpy: no dict mode
        return {"source": "unknown"}


def _versions() -> dict:
    import numpy
    import scipy

    from .. import __version__

    return {"python": platform.python_version(), "numpy": numpy.__version__,
            "scipy": scipy.__version__, "lcpbench": __version__,
            "platform": platform.platform()}


def machine_record(*, workers: int | None = None, repeat: int | None = None) -> dict:
    """Everything a sweep's times depend on, as plain data (see the module docstring)."""
    from .pool import SINGLE_THREAD

    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        usable = os.cpu_count()
    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "usable_cores": usable,
        "load_start": load_average(),
        "load_end": None,
        "blas": blas_info(),
        "blas_threads_parent": {k: os.environ.get(k) for k in SINGLE_THREAD
                                if os.environ.get(k) is not None},
        "blas_threads_workers": 1,
        "workers": workers,
        "repeat": repeat,
        "versions": _versions(),
        "executable": sys.executable,
    }


def timing_start() -> dict:
    """What a timing script records when it starts (``benchmarks/*.py``): the CPU
    model, the cores, the load average and the BLAS thread variables (each script sets
    them to 1 before numpy loads); :func:`timing_note` adds the load at the end."""
    from .pool import SINGLE_THREAD

    return {"cpu": cpu_model(), "cores": os.cpu_count(), "load_start": load_average(),
            "blas_threads": {k: os.environ.get(k) for k in SINGLE_THREAD}}


def refuse_overwrite(paths, force: bool) -> None:
    """A timing script's guard for committed results: when some of ``paths`` exists
    and ``force`` is not set, one line on stderr and exit status 2 (a run never
    overwrites results it was not told to)."""
    there = [str(p) for p in paths if os.path.exists(p)]
    if there and not force:
        verb = "exists" if len(there) == 1 else "exist"
        print(f"error: {', '.join(there)} {verb} (results); pass --force to overwrite, or "
              "--out to write elsewhere", file=sys.stderr)
        raise SystemExit(2)


def command_line(script: str, argv: list[str] | None, prefix: str = "") -> str:
    """The command that ran a script of benchmarks/, as a reader runs it again:
    ``prefix`` (settings of the environment, e.g. ``LCPBENCH_AOT=0 ``),
    ``python benchmarks/SCRIPT`` and the arguments it was given (``argv``; None: this
    process's own)."""
    args = sys.argv[1:] if argv is None else argv
    return f"{prefix}python benchmarks/{script} {shlex.join(args)}".strip()


def timing_note(start: dict) -> str:
    """One sentence for a result file: the machine, one BLAS thread or not, and the load
    average (1/5/15 min) at the start (``start`` from :func:`timing_start`) and now."""
    start["load_end"] = load_average()
    env = start["blas_threads"]
    if all(env.get(k) == "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                        "MKL_NUM_THREADS")):
        blas = "one BLAS thread"
    else:
        blas = "BLAS threads not pinned (" + (", ".join(
            f"{k}={v}" for k, v in env.items() if v is not None) or "no variable set") + ")"

    def load(x):
        return "n/a" if not x else "/".join(f"{a:g}" for a in x)

    return (f"{start['cpu']}, {start['cores']} cores, {blas}; load average (1/5/15 min) "
            f"{load(start['load_start'])} at the start, {load(start['load_end'])} at the end.")


def overloaded(record: dict) -> str | None:
    """A warning when the 1-minute load average exceeded the worker count, else None.

    A sweep of ``w`` workers makes a load of about ``w``; more means other
    processes shared the cores while the times were measured.
    """
    workers = record.get("workers") or 1
    high = [(when, load[0]) for when, load in (("start", record.get("load_start")),
                                               ("end", record.get("load_end")))
            if load and load[0] > workers]
    if not high:
        return None
    where = " and ".join(f"{v:g} at the {w}" for w, v in high)
    return (f"the load average ({where}) exceeded the {workers} worker(s): other processes "
            "shared the cores, so the times are slower than on an idle machine")


def describe(record: dict) -> str:
    """One paragraph of the record, for the report."""
    blas = record.get("blas") or {}
    if blas.get("source") == "threadpoolctl":
        libs = "; ".join(f"{p.get('internal_api')} {p.get('version')} "
                         f"({p.get('num_threads')} threads in the sweep process)"
                         for p in blas.get("pools", [])) or "none loaded"
    else:
        libs = f"{blas.get('name', '?')} {blas.get('version', '')}".strip()
    v = record.get("versions") or {}

    def load(x):
        return "n/a" if not x else "/".join(f"{a:g}" for a in x)

    return (f"{record.get('cpu', '?')}, {record.get('cores', '?')} cores "
            f"({record.get('usable_cores', '?')} usable); load average (1/5/15 min) "
            f"{load(record.get('load_start'))} at the start, {load(record.get('load_end'))} "
            f"at the end; BLAS {libs}, workers pinned to "
            f"{record.get('blas_threads_workers', 1)} thread; {record.get('workers', '?')} "
            f"worker(s), each time the median of {record.get('repeat') or 1} solve(s); "
            f"Python {v.get('python', '?')}, numpy {v.get('numpy', '?')}, scipy "
            f"{v.get('scipy', '?')}, lcpbench {v.get('lcpbench', '?')}, "
            f"{v.get('platform', '?')}.")


def timing_rows(runs: list[dict]) -> list[dict]:
    """Per (back-end, settings, method): how the times split and how much they spread.

    Over the converged runs: the median share of the wall time spent in setup
    (assembling the steps, building the back-end's form, its own setup) and
    in the back-end's solve, the repeats, and the median and largest relative
    spread (max − min) / median of the repeated wall times. Runs stored
    before schema 3 have no setup time or repeats (shown as missing).
    """
    import numpy as np

    groups: dict[tuple, list[dict]] = {}
    for r in runs:
        if r["converged"] and r["wall_time"] and r["wall_time"] > 0:
            groups.setdefault((r["backend"], r["settings"], r["method"]), []).append(r)
    out = []
    for (b, s, m), rs in sorted(groups.items()):
        setup = [r["setup_time"] / r["wall_time"] for r in rs
                 if r.get("setup_time") is not None and np.isfinite(r["setup_time"])]
        solve = [r["solver_time"] / r["wall_time"] for r in rs
                 if r.get("solver_time") is not None and np.isfinite(r["solver_time"])]
        spread = [(r["wall_time_max"] - r["wall_time_min"]) / r["wall_time"] for r in rs
                  if (r.get("repeats") or 1) > 1 and r.get("wall_time_max") is not None]
        reps = sorted({int(r["repeats"]) for r in rs if r.get("repeats")})
        out.append({"backend": b, "settings": s, "method": m, "runs": len(rs),
                    "repeats": reps,
                    "setup_share": float(np.median(setup)) if setup else float("nan"),
                    "solve_share": float(np.median(solve)) if solve else float("nan"),
                    "spread_median": float(np.median(spread)) if spread else float("nan"),
                    "spread_max": float(np.max(spread)) if spread else float("nan")})
    return out


def machine_section(sweeps: list[dict], runs: list[dict]) -> str:
    """The report's section: each recorded sweep's machine, and the timing table."""
    lines = ["", "## Machine and timing", ""]
    recorded = [s for s in sweeps if s.get("machine")]
    if not recorded:
        lines += ["No machine record in the store (sweeps before schema 3, or run without "
                  "the store's lock).", ""]
    for s in recorded[-5:]:
        rec = s["machine"]
        lines += [f"- sweep `{s['sweep_id'][:8]}` ({s.get('started', '?')}, host "
                  f"{s.get('host', '?')}): {describe(rec)}"]
        warn = overloaded(rec)
        if warn:
            lines += [f"  **Warning:** {warn}."]
    if len(recorded) > 5:
        lines += [f"- … and {len(recorded) - 5} earlier sweep(s)."]
    rows = timing_rows(runs)
    if rows:
        def pct(v):
            return "—" if v != v else f"{100 * v:.0f} %"

        lines += ["", "Over the converged runs: the median share of the wall time spent in "
                  "setup (assembling each contact step, building the back-end's form, the "
                  "back-end's own setup) and in the back-end's solve (the rest is the "
                  "driver: certificate, line search), and the spread (max − min) / median "
                  "of the repeated wall times.", "",
                  "| back-end | settings | driver | runs | repeats | setup | solve | "
                  "spread (median) | spread (max) |",
                  "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
        for r in rows:
            reps = ",".join(map(str, r["repeats"])) or "—"
            lines.append(f"| `{r['backend']}` | {r['settings']} | {r['method']} | "
                         f"{r['runs']} | {reps} | {pct(r['setup_share'])} | "
                         f"{pct(r['solve_share'])} | {pct(r['spread_median'])} | "
                         f"{pct(r['spread_max'])} |")
    return "\n".join(lines + [""])
