"""The registry of back-ends: what exists, what is installed, what it can do.

Every back-end is a :class:`Backend` record: capabilities as data, the
lcpbench module that adapts it, and the top-level Python modules it needs.
Listing the registry never imports a native library: availability is decided
with :func:`importlib.util.find_spec` (as cvxpy does), or by a cheap check
function for the Siconos bridge. The adapter module is imported only when the
back-end is first used.

Third-party back-ends plug in through the entry-point group
``lcpbench.solvers``: an entry point loads to a :class:`Backend` or a list of
them, whose ``module`` provides ``solve_lcp`` (form "lcp") or ``solve_qp``
(form "qp") with the signatures of the built-in adapters.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.util
from dataclasses import dataclass, field
from functools import lru_cache

from ..errors import ProblemError, SolverNotFound
from .base import PROFILES, Settings, dist_version

FORMS = ("lcp", "qp")
#: How a back-end takes the frictional contact step (issue 39, docs/friction.md):
#: "lcp", the Stewart–Trinkle LCP in z = (N, β⁺, β⁻, λ); "fc2d", the Delassus form
#: u = W r + q with a Coulomb cone per contact (Siconos' fc2d problem); "tresca", a
#: fixed point of Tresca box QPs in r = (N, T)
FRICTION_FORMS = ("lcp", "fc2d", "tresca")
STORAGES = ("dense", "sparse", "banded")
ENTRY_POINT_GROUP = "lcpbench.solvers"


@dataclass(frozen=True)
class Backend:
    """One back-end and its capabilities.

    Attributes
    ----------
    name : the name users pass as ``solver=``.
    form : "lcp" (works on ``w = M z + q``) or "qp" (works on the
        bound-constrained QP; an LCP file is handed over as
        ``min ½ zᵀMz + qᵀz, z >= 0``, which needs symmetric M).
    storage : "dense", "sparse" or "banded" matrices.
    warm_start : does it accept a starting point (used across outer steps).
    method : "pivoting" (exact, finite), "active-set" (exact, finite),
        "iterative" (first-order), "interior-point", "augmented-lagrangian"
        or "modelling" (a modelling layer that picks a solver).
    module : the lcpbench module with ``solve_lcp`` / ``solve_qp``.
    requires : top-level modules that must be importable.
    extra : the pip extra of lcpbench that installs it (None: built in).
    hint : how to install it where the extra alone does not (a separate package, a
        commercial licence); None: from ``extra``.
    distribution : the distribution whose version is reported.
    options : keyword arguments for the module's solve function.
    check : "module:function" returning availability, instead of ``requires``.
    fallback : the back-end run where this one cannot certify a step.
    linear_rows : a "qp" back-end that takes linear rows besides the bounds
        (equalities ``A x = b`` and ``l <= A x <= u``). Which formulation of the
        contact step a back-end accepts follows from ``form``, ``linear_rows`` and
        whether it runs the contact step itself
        (:func:`lcpbench.model.formulations.accepts`).
    friction : how it takes the frictional contact step, one of
        :data:`FRICTION_FORMS`; None: by its form (a "qp" back-end by the Tresca
        fixed point, an "lcp" one not at all). See :attr:`friction_form`.
    """

    name: str
    form: str
    storage: str
    warm_start: bool
    method: str
    module: str
    description: str = ""
    requires: tuple[str, ...] = ()
    extra: str | None = None
    distribution: str | None = None
    options: dict = field(default_factory=dict, hash=False, compare=False)
    check: str | None = None
    fallback: str | None = None  # back-end to run when this one cannot certify a step
    hint: str | None = None
    #: a "qp" back-end that also takes linear rows, equalities and general inequalities
    #: (a :class:`~lcpbench.solvers.base.LinearQP`), not only bounds
    linear_rows: bool = False
    #: how it takes the frictional step (:data:`FRICTION_FORMS`; None: by ``form``,
    #: :attr:`friction_form`); "none": not at all
    friction: str | None = None

    def __post_init__(self):
        if self.form not in FORMS:
            raise ValueError(f"Backend {self.name!r}: form must be one of {FORMS}")
        if self.storage not in STORAGES:
            raise ValueError(f"Backend {self.name!r}: storage must be one of {STORAGES}")
        if self.friction not in (None, "none") + FRICTION_FORMS:
            raise ValueError(f"Backend {self.name!r}: friction must be one of "
                             f"{FRICTION_FORMS} or 'none'")

    @property
    def friction_form(self) -> str | None:
        """The form in which it takes the frictional contact step (one of
        :data:`FRICTION_FORMS`), or None: a "qp" back-end takes the Tresca fixed point
        unless its record says otherwise."""
        if self.friction is not None:
            return None if self.friction == "none" else self.friction
        return "tresca" if self.form == "qp" else None

    @property
    def exact(self) -> bool:
        """Finite methods that end on an exact basis (pivoting, active set)."""
        return self.method in ("pivoting", "active-set")

    def available(self) -> bool:
        """Installed? Decided without importing any native library."""
        if self.check:
            return bool(_call(self.check))
        return all(_has_module(m) for m in self.requires)

    def version(self) -> str | None:
        if self.check and not self.available():
            return None
        dist = self.distribution
        if dist is None:
            return None
        if dist.startswith("call:"):
            return _call(dist[5:])
        return dist_version(dist)

    def install_hint(self) -> str:
        if self.hint is not None:
            return self.hint
        if self.extra is None:
            return "built in"
        if self.extra.startswith("apt:"):
            return f"apt-get install {self.extra[4:]}"
        return f"pip install 'lcpbench[{self.extra}]'"

    def load(self):
        """The adapter module (imports the native library lazily, at solve time)."""
        return importlib.import_module(self.module)

    def capabilities(self) -> dict:
        """Capabilities and installation state as plain data (for ``lcpbench solvers``)."""
        ok = self.available()
        return {
            "name": self.name, "available": ok, "version": self.version() if ok else None,
            "form": self.form, "storage": self.storage, "warm_start": self.warm_start,
            "method": self.method, "exact": self.exact, "linear_rows": self.linear_rows,
            "friction": self.friction_form,
            "install": self.install_hint(),
            "description": self.description,
        }


def _has_module(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        return False


def _call(target: str):
    """Call ``"module:function"``; a check that cannot run means "not available"."""
    mod, _, fn = target.partition(":")
    try:
        return getattr(importlib.import_module(mod), fn)()
    except Exception:
        return None


def _own(name, form, storage, warm, method, module, description, **kw) -> Backend:
    return Backend(name, form, storage, warm, method, module, description,
                   distribution="lcpbench", **kw)


#: the Siconos back-ends' frictional form: their fc2d solvers where Siconos has one
#: (lemke, enum; its projected Gauss–Seidel is fc2d's NSGS), else the LCP
SICONOS_FRICTION = {"lemke": "fc2d", "enum": "fc2d", "pgs": "fc2d", "newton-min": "lcp",
                    "newton-fb": "lcp", "murty": "lcp", "bard": "lcp", "pathsearch": "lcp"}


def _builtin() -> list[Backend]:
    out = [
        _own("active-set", "qp", "banded", True, "active-set", "lcpbench.solvers.banded",
             "primal active set on the banded Cholesky factor, O(N) per change; "
             "falls back to Lemke when it cannot certify (a solve's steps: up to 1000 nodes); "
             "on a frictional step, the active set on the stick/slide/separate states",
             fallback="lemke", friction="fc2d"),
        _own("lemke", "lcp", "dense", False, "pivoting", "lcpbench.solvers.lemke",
             "Lemke's complementary pivoting, lexicographic anti-cycling rule",
             friction="lcp"),
        _own("pgs", "lcp", "dense", True, "iterative", "lcpbench.solvers.pgs",
             "projected Gauss-Seidel"),
        _own("psor", "lcp", "dense", True, "iterative", "lcpbench.solvers.pgs",
             "projected successive over-relaxation (PGS with omega = 1.5)",
             options={"omega": 1.5}),
        _own("pgs-sm", "lcp", "dense", True, "iterative", "lcpbench.solvers.pgs_sm",
             "projected Gauss-Seidel with subspace minimisation (Morales, Nocedal & "
             "Smelyanskiy 2008; symmetric M; numba)", requires=("numba",)),
        Backend("osqp", "qp", "sparse", True, "iterative", "lcpbench.solvers.qp_osqp",
                "OSQP 1.x (ADMM), native API", requires=("osqp",), extra="osqp",
                distribution="osqp", linear_rows=True),
        Backend("clarabel", "qp", "sparse", False, "interior-point",
                "lcpbench.solvers.qp_clarabel", "Clarabel interior point, native API",
                requires=("clarabel",), extra="clarabel", distribution="clarabel",
                linear_rows=True),
        Backend("proxsuite-dense", "qp", "dense", True, "augmented-lagrangian",
                "lcpbench.solvers.qp_proxsuite", "ProxQP (ProxSuite), dense back-end",
                requires=("proxsuite",), extra="proxsuite", distribution="proxsuite",
                options={"variant": "dense"}, linear_rows=True),
        Backend("proxsuite-sparse", "qp", "sparse", True, "augmented-lagrangian",
                "lcpbench.solvers.qp_proxsuite", "ProxQP (ProxSuite), sparse back-end",
                requires=("proxsuite",), extra="proxsuite", distribution="proxsuite",
                options={"variant": "sparse"}, linear_rows=True),
        Backend("cvxpy", "qp", "sparse", False, "modelling", "lcpbench.solvers.qp_cvxpy",
                "the QP stated in cvxpy, solved by the solver cvxpy picks",
                requires=("cvxpy",), extra="cvxpy", distribution="cvxpy", linear_rows=True),
    ]
    out.append(Backend(
        "quantecon-lemke", "lcp", "dense", False, "pivoting", "lcpbench.solvers.peer_quantecon",
        "QuantEcon's Lemke (numba, lexicographic rule): quantecon.optimize.lcp_lemke",
        requires=("quantecon",), extra="peer", distribution="quantecon", friction="lcp"))
    out += _qpsolvers_backends()
    for method, label in (("lemke", "Lemke"), ("pgs", "projected Gauss-Seidel"),
                          ("newton-min", "Newton on the min function"),
                          ("newton-fb", "Newton on Fischer-Burmeister, line search"),
                          ("enum", "enumeration of complementary bases (n <= 20)"),
                          ("murty", "Murty's least-index pivoting"),
                          ("bard", "Bard's pivoting"),
                          ("pathsearch", "path search (pivoting along a homotopy)")):
        exact = method in ("lemke", "enum", "murty", "bard", "pathsearch")
        out.append(Backend(
            f"siconos-{method}", "lcp", "dense", method in ("pgs", "newton-min", "newton-fb"),
            "pivoting" if exact else "iterative",
            "lcpbench.solvers.siconos_bridge", f"Siconos numerics (C): {label}, via a "
            "subprocess bridge to the system Python", extra="apt:python3-siconos",
            distribution="call:lcpbench.solvers.siconos_bridge:version",
            check="lcpbench.solvers.siconos_bridge:available", options={"method": method},
            friction=SICONOS_FRICTION.get(method)))
    return out


#: qpsolvers back-ends that have a native lcpbench adapter (not duplicated).
_NATIVE = {"osqp", "clarabel", "proxqp"}
#: How each qpsolvers solver is classified (method, storage).
_QPSOLVERS_KIND = {
    "daqp": ("active-set", "dense"), "quadprog": ("active-set", "dense"),
    "qpoases": ("active-set", "dense"), "highs": ("active-set", "sparse"),
    "piqp": ("interior-point", "sparse"), "cvxopt": ("interior-point", "dense"),
    "ecos": ("interior-point", "sparse"), "mosek": ("interior-point", "sparse"),
    "gurobi": ("interior-point", "sparse"), "hpipm": ("interior-point", "dense"),
    "qpswift": ("interior-point", "sparse"), "kvxopt": ("interior-point", "dense"),
    "scs": ("iterative", "sparse"), "qpalm": ("augmented-lagrangian", "sparse"),
    "sip": ("interior-point", "sparse"), "jaxopt_osqp": ("iterative", "dense"),
}


def _qpsolvers_backends() -> list[Backend]:
    try:
        from .qp_qpsolvers import KNOWN_SOLVERS, install_hint  # pure Python: no native imports
    except ImportError:  # pragma: no cover - the adapter ships with lcpbench
        return []

    out = []
    for solver, module in sorted(KNOWN_SOLVERS.items()):
        if solver in _NATIVE:
            continue
        method, storage = _QPSOLVERS_KIND.get(solver, ("iterative", "sparse"))
        out.append(Backend(
            f"qpsolvers-{solver}", "qp", storage, True, method, "lcpbench.solvers.qp_qpsolvers",
            f"{solver} through qpsolvers", requires=("qpsolvers", module.split(".")[0]),
            extra="qpsolvers", distribution="qpsolvers", options={"solver": solver},
            hint=install_hint(solver), linear_rows=True))
    return out


@lru_cache(maxsize=1)
def _plugins() -> tuple[tuple[Backend, ...], tuple[str, ...]]:
    """Back-ends from the ``lcpbench.solvers`` entry points (and load errors)."""
    found: list[Backend] = []
    errors: list[str] = []
    for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        try:
            obj = ep.load()
            obj = obj() if callable(obj) and not isinstance(obj, Backend) else obj
            items = [obj] if isinstance(obj, Backend) else list(obj)
            if not all(isinstance(b, Backend) for b in items):
                raise TypeError("the entry point must give a Backend or a list of them")
            found.extend(items)
        except Exception as exc:  # a broken plugin must not break the registry
            errors.append(f"{ep.name}: {type(exc).__name__}: {exc}")
    return tuple(found), tuple(errors)


@lru_cache(maxsize=1)
def _builtin_table() -> dict[str, Backend]:
    return {b.name: b for b in _builtin()}


@lru_cache(maxsize=1)
def _all() -> dict[str, Backend]:
    table = dict(_builtin_table())
    for b in _plugins()[0]:
        table.setdefault(b.name, b)  # a plugin cannot shadow a built-in name
    return table


def backends() -> dict[str, Backend]:
    """Every known back-end, installed or not, by name."""
    return dict(_all())


def plugin_errors() -> tuple[str, ...]:
    return _plugins()[1]


def available_backends() -> list[str]:
    return [name for name, b in _all().items() if b.available()]


#: What ``solver="auto"`` runs, in the registry and in ``lcpbench.solve``: the
#: dual active set on the banded step. It is exact (its answer is the LCP's to
#: round-off, checked by lcpbench's judge) and never failed on the paper grid or
#: the hard suite (results/sweep, results/hard), so no measurement is needed.
DEFAULT = "active-set"


def get_backend(name: str) -> Backend:
    """The back-end called ``name``; "auto" is the default (active-set).

    Raises
    ------
    SolverNotFound
        For an unknown name or one that is not installed, naming the installed
        back-ends and how to install the missing one.
    """
    if name == "auto":
        name = DEFAULT
    # a plugin cannot shadow a built-in name: a built-in is found without scanning the
    # installed distributions' entry points (a tenth of a second at start-up)
    b = _builtin_table().get(name) or _all().get(name)
    if b is not None and b.available():
        return b
    installed = ", ".join(available_backends())
    if b is None:
        raise SolverNotFound(f"unknown solver {name!r}; installed: auto, {installed} "
                             "(`lcpbench solvers` lists all)")
    raise SolverNotFound(f"solver {name!r} is not installed ({b.install_hint()}); "
                         f"installed: {installed}")


def get_settings(settings: str | Settings) -> Settings:
    """A settings profile by name (default, low, mid, high) or a Settings object."""
    if isinstance(settings, Settings):
        return settings
    try:
        return PROFILES[settings]
    except (KeyError, TypeError):
        raise ProblemError(f"settings must be one of {', '.join(PROFILES)}, "
                           f"got {settings!r}") from None
