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
files (``compiled_kernel.py`` the dual walk of ``solvers/dual_kernel.py``,
``twisted_walk_kernel.py`` the twisted factor, which calls the face kernel): without the
hash an edit of one file could leave another file's cached code running stale.
Any edit of any kernel moves the directory, so every kernel compiles once
afresh. The base is numba's ``NUMBA_CACHE_DIR`` where set, else the user's cache
directory (``$XDG_CACHE_HOME`` or ``~/.cache``). This module is at the bottom of
the layers, so ``linalg`` can load its kernels through it too.

**Ahead of time.** Importing numba alone costs about a third of a second, so a
fresh process that loads the kernels through numba cannot start its first solve
in under half a second. :func:`build_aot` compiles the kernels' entries (the
functions a solve calls from Python, with the signatures their dispatchers were
called with) into one CPython extension module with ``numba.pycc``, for this
machine's CPU, beside the JIT cache: ``<cache dir>/aot-<machine>/``. The module
needs numpy and nothing of numba at run time. :func:`kernel_module` returns it
(an :class:`AotKernels`: the exported functions and the module's constants;
any other name, or a call whose argument types differ from the exported
signature, goes to the JIT module) when it exists for the current hash and
machine and imports; otherwise the JIT module as before. The hash directory
makes a stale module unreachable: an edited kernel file moves the directory.
``LCPBENCH_AOT=0`` (or ``LCPBENCH_NUMBA_FULL_LOAD=1``) turns it off;
``LCPBENCH_AOT_DIR`` names another directory to look in (tests, debugging). The module
is built by ``lcpbench compile`` (:mod:`lcpbench.aot`), never at import or in a
solve; a failed build leaves the JIT path as it was.

It uses two private methods of numba's cache (``_load_overload`` and
``_guard_against_spurious_io_errors``, numba 0.5x–0.6x); where they are
missing it does nothing, so a numba that changed them loads as before.
"""

from __future__ import annotations

import hashlib
import importlib
import os
import sys
from pathlib import Path

_LOADED: dict = {}  # module name -> what kernel_module returns (AOT kernels or the module)
_JIT: dict = {}  # module name -> the numba module, once imported and hooked
_ENTRIES: dict = {}  # module name -> the entries kernel_module was asked for
_DIR: list = []  # the cache directory of this process's kernels, once computed
_AOT: list = []  # [(extension module, manifest) or None], once looked for
_AOT_KERNELS: dict = {}  # module name -> its AotKernels, once made
_USE_AOT: list = [None]  # use_aot's setting; None: the environment decides
_HOLDERS: list = []  # callers' one-element caches of a kernel module (see held)
#: every file of lcpbench with numba kernels, relative to the package
#: (tests/model/test_kernel_cache.py checks that no file with ``@njit`` is missing)
KERNEL_FILES = ("model/chain_kernel.py", "model/compiled_kernel.py", "model/compiled_dual.py",
                "solvers/dual_kernel.py", "model/judge_kernel.py",
                "model/judge_bound.py", "model/judge_checks.py",
                "model/driver_kernel.py", "model/large_kernel.py", "model/judge_exact_kernel.py",
                "model/judge_pivot.py",
                "linalg/givens_kernel.py",
                "linalg/face_kernel.py", "linalg/twisted_kernel.py",
                "linalg/ldl_kernel.py", "linalg/wide_face_kernel.py", "model/batch_kernel.py", "model/batch_verdict.py",
                "model/wall_free_kernel.py", "model/predictor_kernel.py",
                "model/sensitivity_kernel.py", "model/sensitivity_profile_kernel.py",
                "model/angle_kernel.py", "model/path_kernel.py",
                "linalg/band_lu_kernel.py", "problems/table_kernel.py",
                "linalg/twisted_walk_kernel.py", "linalg/walk_key.py", "linalg/walk_picks.py",
                "model/stability_kernel.py",
                "model/wall_kernel.py", "model/profile_kernel.py", "model/profile_line.py",
                "model/friction_step.py", "model/friction_outer.py",
                "model/friction_primal.py", "model/friction_polish.py",
                "model/judge_friction.py",
                "solvers/pgs_sm_kernel.py", "solvers/lemke_kernel.py",
                "solvers/pivoting_kernel.py")
#: files without kernels whose numbers the kernels freeze in (hashed with KERNEL_FILES)
CONSTANT_FILES = ("thresholds.py",)
#: the name of the ahead-of-time extension module (one per cache directory and machine)
AOT_NAME = "lcpbench_aot"
MANIFEST = "manifest.json"


def kernel_cache_dir(files, base: str | None = None) -> str:
    """``<base>/lcpbench-numba/<sha>``: the cache of a kernel made of ``files``,
    named by the SHA-256 of their sources (in order)."""
    sha = hashlib.sha256()
    for f in files:
        sha.update(Path(f).read_bytes())
    if not base:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "lcpbench-numba", sha.hexdigest()[:20])


def kernels_dir() -> str:
    """The cache directory of this process's kernels: :func:`kernel_cache_dir` of
    :data:`KERNEL_FILES` and :data:`CONSTANT_FILES` under ``NUMBA_CACHE_DIR`` (numba's own setting; read from
    the environment, so that finding the AOT module needs no numba)."""
    if not _DIR:
        here = Path(__file__).parent
        _DIR.append(kernel_cache_dir([here / f for f in KERNEL_FILES + CONSTANT_FILES],
                                     os.environ.get("NUMBA_CACHE_DIR")))
    return _DIR[0]


def machine_tag() -> str:
    """12 hex digits naming this machine's CPU (architecture, model, ISA flags) and
    Python's ABI: the AOT module is built for the host CPU, and must not be run on
    another one that shares the cache directory."""
    import platform

    sha = hashlib.sha256(f"{platform.machine()} {sys.implementation.cache_tag}".encode())
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:  # the first processor's block (x86: vendor, model, flags; Arm)
                if not line.strip():
                    break
                key = line.split(":", 1)[0].strip()
                if key in ("vendor_id", "model name", "flags", "Features", "CPU part"):
                    sha.update(line.encode())
    except OSError:  # not Linux: the platform's word for the processor
        sha.update(platform.processor().encode())
    return sha.hexdigest()[:12]


def aot_dir(cache_dir: str | None = None) -> str:
    """``<cache dir>/aot-<machine_tag>``: where the AOT module of the kernels lives
    (``LCPBENCH_AOT_DIR`` where set and no ``cache_dir`` is given)."""
    if cache_dir is None and os.environ.get("LCPBENCH_AOT_DIR"):
        return os.environ["LCPBENCH_AOT_DIR"]
    return os.path.join(cache_dir or kernels_dir(), f"aot-{machine_tag()}")


def kernel_module(name: str, entry: str | None = None):
    """The compiled kernels of module ``name``, once per process: the ahead-of-time
    module's functions (:class:`AotKernels`) where it exists for the current kernels
    and machine and exports some of ``name``'s functions, else :func:`jit_module`."""
    found = _LOADED.get(name)
    if found is None:
        if entry is not None:
            _ENTRIES.setdefault(name, set()).add(entry)
        found = aot_kernels(name) or jit_module(name)
        _LOADED[name] = found
    return found


def jit_module(name: str):
    """The numba module ``name`` (imports numba; loads or compiles it) under the
    kernels' cache directory (:func:`kernels_dir`), every dispatcher it defines (each
    a Python caller may call) hooked to :func:`light_cache_load`, once per process."""
    module = _JIT.get(name)
    if module is None:
        from numba.core import config  # numba's locator reads it at each @njit

        saved = config.CACHE_DIR
        config.CACHE_DIR = kernels_dir()
        try:
            module = importlib.import_module(name)
        finally:
            config.CACHE_DIR = saved
        for fn in vars(module).values():  # every kernel of it a Python caller may call
            if getattr(getattr(fn, "py_func", None), "__module__", None) == name:
                light_cache_load(fn)
        _JIT[name] = module
    return module


def aot_enabled() -> bool:
    """Whether :func:`kernel_module` serves the AOT module where there is one: as
    :func:`use_aot` says, else unless ``LCPBENCH_AOT=0`` or
    ``LCPBENCH_NUMBA_FULL_LOAD`` is set."""
    if _USE_AOT[0] is not None:
        return _USE_AOT[0]
    return os.environ.get("LCPBENCH_AOT", "1") != "0" and not os.environ.get(
        "LCPBENCH_NUMBA_FULL_LOAD")


def use_aot(enabled: bool | None) -> None:
    """From now on in this process, serve the AOT kernels (True), the JIT (False) or
    as the environment says (None); the next :func:`kernel_module` call chooses again.
    For the builder (which needs the JIT dispatchers) and for benchmarks."""
    _USE_AOT[0] = enabled
    _LOADED.clear()
    _AOT.clear()
    for holder in _HOLDERS:  # the callers that keep the module look it up again
        holder.clear()


def kept(holder: list, name: str, entry: str):
    """:func:`kernel_module` ``(name, entry)``, loaded once into ``holder``: a caller's
    one-item list, registered with :func:`held` (so :func:`use_aot` empties it and the
    next call loads again)."""
    if not holder:
        held(holder).append(kernel_module(name, entry))
    return holder[0]


def held(holder: list) -> list:
    """Register ``holder``, a caller's cache of what :func:`kernel_module` returned,
    to be emptied by :func:`use_aot` (else a caller would keep the kernels it got
    first, whatever the switch says); returns it."""
    if not any(h is holder for h in _HOLDERS):
        _HOLDERS.append(holder)
    return holder


def aot_kernels(name: str) -> AotKernels | None:
    """The AOT module's functions of kernel module ``name``, or None (no module for
    these kernels on this machine, turned off, or it does not import: then one
    warning, and the JIT serves)."""
    if not aot_enabled():
        return None
    if not _AOT:
        _AOT.append(load_aot(aot_dir()))
    lib = _AOT[0]
    if lib is None or name not in lib[1]["modules"]:
        return None
    found = _AOT_KERNELS.get(name)
    if found is None or found._module is not lib[0]:
        found = _AOT_KERNELS[name] = AotKernels(name, lib[0], lib[1]["modules"][name])
    return found


def load_aot(where: str):
    """``(extension module, manifest)`` of the AOT module in directory ``where``, or
    None where there is none or it does not fit this process (another machine, Python
    or numpy) or does not import (a warning says so)."""
    manifest = os.path.join(where, MANIFEST)
    if not os.path.exists(manifest):
        return None
    try:
        import json

        with open(manifest, encoding="utf-8") as f:
            info = json.load(f)
        if not _fits(info):
            return None
        from importlib import machinery, util

        path = os.path.join(where, info["file"])
        spec = util.spec_from_file_location(
            AOT_NAME, path, loader=machinery.ExtensionFileLoader(AOT_NAME, path))
        module = util.module_from_spec(spec)  # type: ignore[arg-type]
        spec.loader.exec_module(module)  # type: ignore[union-attr]
        for mod in info["modules"].values():
            for fn in mod["functions"].values():
                getattr(module, fn["symbol"])
    except Exception as exc:  # a broken module: the JIT serves, one line says why
        import warnings

        warnings.warn(f"lcpbench: the ahead-of-time kernels in {where} do not load "
                      f"({type(exc).__name__}: {exc}); numba's JIT serves instead "
                      f"(`lcpbench compile` rebuilds them)", RuntimeWarning, stacklevel=3)
        return None
    return module, info


def _fits(info: dict) -> bool:
    """Built from these kernel files, for this machine, Python and numpy (major)."""
    import numpy as np

    return (info.get("format") == 1 and info.get("machine") == machine_tag()
            and info.get("python") == sys.implementation.cache_tag
            and info.get("kernels") == os.path.basename(kernels_dir())
            and str(info.get("numpy", "")).split(".")[0] == np.__version__.split(".")[0])


class AotKernels:
    """A kernel module's ahead-of-time functions and constants, module-like.

    Each exported function checks its arguments against the signature it was
    compiled for (the types numba's dispatcher would see: Python or numpy scalars
    of the same kind, C-contiguous writable arrays of the same dtype and rank);
    a call that does not fit runs the JIT module's function, as numba would compile
    a new specialisation. Any name the AOT module lacks comes from the JIT module
    (:func:`jit_module`, which imports numba)."""

    def __init__(self, name: str, module, spec: dict):
        self.__name__ = name
        self._module = module
        self.__dict__.update({k: tuple(v) if isinstance(v, list) else v
                              for k, v in spec["constants"].items()})
        for fn_name, fn in spec["functions"].items():
            setattr(self, fn_name, _checked(getattr(module, fn["symbol"]), fn, name,
                                            fn_name))

    def __getattr__(self, attr: str):  # only for names not set above
        if attr.startswith("__"):
            raise AttributeError(attr)
        return getattr(jit_module(self.__name__), attr)


def _checked(aot, fn: dict, name: str, fn_name: str):
    """``aot`` behind a check of its arguments' types (see :class:`AotKernels`).

    The check is one generated expression (as :mod:`dataclasses` generates its
    methods), with the entry's own parameter names and defaults: per array its
    class, dtype (by identity), rank and ``flags.carray`` (C-contiguous, aligned,
    writable), per scalar its class; a few microseconds for the solve kernel's 23
    arguments. What fails it goes to :func:`_slow`."""
    import numpy as np

    kinds, names, defaults = fn["args"], fn["names"], fn["defaults"]
    env = {"aot": aot, "_nd": np.ndarray, "_f8": np.float64, "_i8": np.int64, "_b1": np.bool_,
           "slow": _slow(aot, fn, name, fn_name)}
    conds = []
    for i, (x, kind) in enumerate(zip(names, kinds, strict=True)):
        if kind == "f8":
            conds.append(f"(type({x}) is float or type({x}) is _f8)")
        elif kind == "i8":
            conds.append(f"(type({x}) is int or type({x}) is _i8)")
        elif kind == "b1":
            conds.append(f"({x} is True or {x} is False or type({x}) is _b1)")
        else:
            env[f"_D{i}"] = np.dtype(kind.split(":")[1])
            conds.append(f"type({x}) is _nd and {x}.dtype is _D{i} and {x}.ndim == "
                         f"{int(kind.split(':')[2])} and {x}.flags.carray")
    first = len(names) - len(defaults)
    params = ", ".join(names[:first] + [f"{x}={v!r}" for x, v in zip(names[first:], defaults,
                                                                      strict=True)])
    args = ", ".join(names)
    src = (f"def {fn_name}({params}):\n    if {' and '.join(conds)}:\n"
           f"        return aot({args})\n    return slow({args})\n")
    exec(compile(src, f"<lcpbench.numba_cache AOT {name}.{fn_name}>", "exec"), env)
    call = env[fn_name]
    call.__doc__ = f"{name}.{fn_name}, compiled ahead of time (numba.pycc)"
    return call


def _slow(aot, fn: dict, name: str, fn_name: str):
    """The check of :func:`_checked` by equality (a dtype equal but not identical):
    ``aot`` where the arguments fit, else the JIT module's function."""
    import numpy as np

    scalar = {"f8": (float, np.float64), "i8": (int, np.int64), "b1": (bool, np.bool_)}
    kinds = fn["args"]

    def fits(args) -> bool:
        for a, k in zip(args, kinds, strict=True):
            if k in scalar:
                if type(a) not in scalar[k]:
                    return False
            elif not (type(a) is np.ndarray and a.dtype == np.dtype(k.split(":")[1])
                      and a.ndim == int(k.split(":")[2]) and a.flags.carray):
                return False
        return True

    def slow(*args):
        if fits(args):
            return aot(*args)
        return getattr(jit_module(name), fn_name)(*args)

    return slow


_ON_COMPILE: list = []  # what to call once, at the first kernel this process compiles


def on_compile(notice) -> None:
    """Call ``notice()`` once, when this process first finds a kernel missing from the
    cache (numba then compiles it: seconds to a minute; the command line prints a line).
    ``None`` removes it."""
    _ON_COMPILE[:] = [] if notice is None else [notice]


def compiling() -> None:
    """A kernel is about to be compiled: the :func:`on_compile` notice, once."""
    if _ON_COMPILE:
        _ON_COMPILE.pop()()


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
        if found is None:
            found = full(sig, target_context)
            if found is None:  # not in the cache: numba compiles it now
                compiling()
        return found

    light._lcpbench_light = True  # type: ignore[attr-defined]
    cache.load_overload = light
    return True


# -- building the AOT module (lcpbench.aot runs the solves that give the signatures) ----------
class AotBuildError(RuntimeError):
    """The AOT module could not be built (no C compiler, no setuptools, a kernel
    numba.pycc does not take); the JIT path is unchanged."""


def _kind(t) -> str | None:
    """The argument kind of numba type ``t`` that :class:`AotKernels` checks, or None
    where it checks none (the entry then stays with the JIT)."""
    from numba.core import types

    if isinstance(t, types.Array):
        if t.layout != "C" or not t.mutable or not t.aligned or not isinstance(
                t.dtype, (types.Float, types.Integer, types.Boolean)):
            return None
        return f"A:{t.dtype}:{t.ndim}"
    return {types.float64: "f8", types.int64: "i8", types.boolean: "b1"}.get(t)


def _constants(module) -> dict:
    plain = (int, float, str, bool)
    return {k: v for k, v in vars(module).items() if not k.startswith("__") and (
        type(v) in plain or (type(v) is tuple and all(type(x) in plain for x in v)))}


def aot_exports(modules: dict | None = None) -> tuple[dict, dict, list]:
    """What :func:`build_aot` exports, from the dispatchers of the JIT modules loaded
    in this process (``modules``: name -> module, default the ones loaded): every
    entry given to :func:`kernel_module` and every public function of the module,
    called with exactly one signature of argument kinds :class:`AotKernels` checks.

    Returns ``(manifest modules, {symbol: (dispatcher, numba signature)}, skipped)``."""
    from numba.core.registry import CPUDispatcher
    from numba.core.types import Literal

    modules = dict(_JIT) if modules is None else modules
    spec, exports, skipped = {}, {}, []
    for name, module in sorted(modules.items()):
        functions = {}
        wanted = _ENTRIES.get(name, set()) | {k for k in vars(module) if not k.startswith("_")}
        for fn_name in sorted(wanted):
            d = getattr(module, fn_name, None)
            if not isinstance(d, CPUDispatcher) or d.py_func.__module__ != name:
                continue
            # a constant passed from another kernel types the callee with a literal
            # (Literal[bool](False)): an overload that only compiled code calls, made
            # while the caller compiles (not when the caller loads from the cache)
            sigs = [s for s in d.signatures if not any(isinstance(t, Literal) for t in s)]
            if len(sigs) != 1:
                if sigs or fn_name in _ENTRIES.get(name, ()):
                    skipped.append(f"{name}.{fn_name}: {len(sigs)} signatures")
                continue
            kinds = [_kind(t) for t in sigs[0]]
            if None in kinds:
                skipped.append(f"{name}.{fn_name}: argument types {sigs[0]}")
                continue
            defaults = d.py_func.__defaults__ or ()
            code = d.py_func.__code__
            if not all(type(v) in (int, float, bool) for v in defaults) or (
                    code.co_flags & 0x0C or code.co_kwonlyargcount):  # *args, **kw, kw-only
                skipped.append(f"{name}.{fn_name}: parameters {code.co_varnames} "
                               f"(defaults {defaults})")
                continue
            symbol = f"{name.rsplit('.', 1)[-1]}__{fn_name}"
            names = list(code.co_varnames[:code.co_argcount])
            functions[fn_name] = {"symbol": symbol, "args": kinds, "names": names,
                                  "defaults": list(defaults)}
            exports[symbol] = (d, d.overloads[sigs[0]].signature)
        if functions:
            spec[name] = {"functions": functions, "constants": _constants(module)}
    return spec, exports, skipped


def build_aot(out_dir: str | None = None, modules: dict | None = None) -> dict:
    """Compile the kernels' entries ahead of time into ``out_dir`` (default
    :func:`aot_dir`) with ``numba.pycc``, for this CPU (its model and ISA features,
    as numba's JIT compiles), and write the manifest that :func:`load_aot` checks.

    Call it after the kernels have run (:func:`lcpbench.aot.build` runs the solves):
    the signatures are their dispatchers' (:func:`aot_exports`). Returns the
    manifest; raises :class:`AotBuildError` with the reason where it cannot build."""
    import json
    import shutil
    import tempfile
    import time

    t0 = time.perf_counter()
    spec, exports, skipped = aot_exports(modules)
    if not exports:
        raise AotBuildError("no kernel entry has run in this process, nothing to export")
    where = out_dir or aot_dir()
    os.makedirs(where, exist_ok=True)
    build = tempfile.mkdtemp(prefix=".build-", dir=where)
    try:
        try:
            import warnings

            from numba.core import codegen
            with warnings.catch_warnings():  # pycc is "pending deprecation" since numba 0.57
                warnings.simplefilter("ignore")
                from numba.pycc import CC
            cc = CC(AOT_NAME, source_module=__name__)  # finds the C compiler, or raises
        except Exception as exc:  # numba.pycc needs setuptools and a C compiler
            raise AotBuildError(f"numba.pycc cannot build here: {_first_line(exc)}") from exc
        cc.output_dir, cc.target_cpu = build, "host"
        for symbol, (d, sig) in sorted(exports.items()):
            cc.export(symbol, sig)(d.py_func)
        from numba.core import pythonapi

        plain = codegen.AOTCPUCodegen._customize_tm_features, pythonapi.PythonAPI.unserialize
        # the JIT's ISA features (the host's), not only those the CPU model's name implies
        codegen.AOTCPUCodegen._customize_tm_features = (  # type: ignore[method-assign]
            codegen.CPUCodegen._get_host_cpu_features)
        pythonapi.PythonAPI.unserialize = _unserialize_once(plain[1])  # type: ignore
        try:
            cc.compile()
        except Exception as exc:
            raise AotBuildError(f"numba.pycc failed: {_first_line(exc)}") from exc
        finally:
            codegen.AOTCPUCodegen._customize_tm_features = plain[0]  # type: ignore
            pythonapi.PythonAPI.unserialize = plain[1]  # type: ignore[method-assign]
        import numba
        import numpy as np
        from llvmlite import binding

        info = {"format": 1, "file": cc.output_file, "kernels": os.path.basename(kernels_dir()),
                "machine": machine_tag(), "python": sys.implementation.cache_tag,
                "numpy": np.__version__, "numba": numba.__version__,
                "cpu": binding.get_host_cpu_name(), "modules": spec, "skipped": skipped,
                "build_seconds": round(time.perf_counter() - t0, 1)}
        os.replace(os.path.join(build, cc.output_file), os.path.join(where, cc.output_file))
        with open(os.path.join(build, MANIFEST), "w", encoding="utf-8") as f:
            json.dump(info, f, indent=1)
        os.replace(os.path.join(build, MANIFEST), os.path.join(where, MANIFEST))
    finally:
        shutil.rmtree(build, ignore_errors=True)
    _AOT.clear()  # this process looks again
    _LOADED.clear()
    return info


def _unserialize_once(unserialize):
    """numba's ``PythonAPI.unserialize`` for the AOT build: a constant (a pickled
    object in a global of the module) is unpickled once per process, then a new
    reference to the same object. numba's JIT does the same (``numba.core.serialize``
    keeps what it unpickled by address); pycc's copy of ``numba_unpickle`` has no such
    cache, so each returned array paid a ``pickle.loads`` of ``numpy.ndarray`` (its
    Python type), ~1 µs a call per array. A pointer known only at run time (an
    exception's info) is unpickled as before."""
    from llvmlite import ir

    def once(self, structptr):
        if not isinstance(structptr, ir.GlobalVariable):
            return unserialize(self, structptr)
        b, module = self.builder, self.builder.module
        memo = ir.GlobalVariable(module, self.pyobj, module.get_unique_name(
            f"lcpbench.unpickled{structptr.name}"))
        memo.linkage, memo.initializer = "internal", ir.Constant(self.pyobj, None)
        with b.if_then(b.icmp_unsigned("==", b.load(memo), ir.Constant(self.pyobj, None)),
                       likely=False):
            b.store(unserialize(self, structptr), memo)  # NULL (an error) tries again
        obj = b.load(memo)
        self.incref(obj)  # Py_IncRef takes NULL
        return obj

    return once

def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    line = text[0].split(" If using conda")[0] if text else ""  # pycc's advice: conda only
    return f"{type(exc).__name__}: {line}"
