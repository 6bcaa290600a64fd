"""The formulations of one contact step, for any back-end (docs/formulations.md).

One contact step (:class:`~lcpbench.model.step.ContactStep`) is one convex problem;
it can be handed to a back-end in five exactly equivalent forms:

=====  ===========  ========================================================  =========
name   label        unknowns and constraints                                  cond
=====  ===========  ========================================================  =========
F1     gaps         the condensed LCP in the gaps g, R = K g + z (eq. 30)     ~N⁴
F2     heights      the box QP in the free node heights u, Hessian H = K      ~N⁴
F3     lifted       heights and joint angles (δu, φ̂), φ̂ = φ̂₀ + J δu:          ~N²
                    Hessian diag(k), the banded kinematic equality
F4     reactions    the dual in the reactions R on the wall rows: the         ~N⁴ at most
                    compliance W = G H⁻¹ Gᵀ, an SPD LCP (a QP in R >= 0)      (rows only)
F5     angles       the link-angle increments Δα (the paper's variables),     ~N²
                    gaps linearised: δu = S Δα, S = [a cos αₖ]ₖ<ᵢ
=====  ===========  ========================================================  =========

Each has an equilibrated variant (name + ``"+ruiz"``, :mod:`lcpbench.solvers.equilibrate`).
Every form is nondimensionalised (lengths by ℓ, forces by EI/ℓ², as
:func:`step_scales`), and every answer is mapped back to the heights u and the
reactions R, which lcpbench's one judge then checks (:mod:`.step_solver`). In every
form the reactions are the multipliers of the wall constraints.

F1 and F2 are the forms the back-ends always had (:func:`step_lcp`, :func:`step_qp`,
the step's compiled ones, :meth:`lcpbench.model.step.ContactStep.lcp_form`); this module
also builds F3-F5 (:func:`lifted_qp`, :func:`reaction_lcp`, :func:`angle_qp`), maps their
answers back and runs any of the five on a back-end
(:func:`run_formulation`). Which back-end accepts which form follows from its
registry data (:func:`accepts`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..errors import ProblemError
from ..linalg import solveh_banded
from ..linalg import sparse as sp
from ..solvers.base import BoxQP, LinearQP, Settings, Status, StepSolution
from ..solvers.equilibrate import equilibrate_lcp, equilibrate_qp, scale_qp, unscale_qp
from ..solvers.runner import run_lcp
from .elastic import compliances

#: name -> (label, kind): "lcp" (a symmetric LCP, or the QP in z >= 0), "box" (a box
#: QP), "rows" (a QP with linear rows: equalities and general inequalities)
FORMS = {"gaps": ("F1", "lcp"), "heights": ("F2", "box"), "lifted": ("F3", "rows"),
         "reactions": ("F4", "lcp"), "angles": ("F5", "rows")}
RUIZ = "+ruiz"
NAMES = tuple(name + v for name in FORMS for v in ("", RUIZ))


@dataclass(frozen=True)
class Formulation:
    """One formulation of the contact step: ``name`` (a key of :data:`FORMS`), and
    whether it is Ruiz-equilibrated; ``eps``, where the ``best`` recipe gives one
    (:func:`best_eps`), is the tolerance ε the back-end is handed in it in place of the
    profile's (lcpbench's judge keeps the profile's); None: the profile's."""

    name: str
    equilibrated: bool = False
    eps: float | None = None

    @property
    def label(self) -> str:
        return FORMS[self.name][0] + ("r" if self.equilibrated else "")

    @property
    def kind(self) -> str:
        return FORMS[self.name][1]

    def __str__(self) -> str:
        form = self.name + (RUIZ if self.equilibrated else "")
        return form if self.eps is None else f"{form}{AT}{self.eps!r}"


#: ``NAME@E``: the form NAME with the back-end handed the tolerance E (a recipe's ε)
AT = "@"


def parse_formulation(value: str | Formulation | None) -> Formulation | None:
    """A :class:`Formulation` from its name (``"lifted"``, ``"lifted+ruiz"``) or label
    (``"F3"``, ``"F3r"``), with ``"@E"`` the ε handed to the back-end
    (``"angles+ruiz@1e-06"``, what ``str`` writes for a recipe with an ε); None for
    None; one ProblemError naming the choices."""
    if value is None or isinstance(value, Formulation):
        return value
    if isinstance(value, str):
        v, at, e = value.strip().partition(AT)
        eps = None
        if at:
            try:
                eps = float(e)
            except ValueError:
                eps = float("nan")
            if not 0.0 < eps < 1.0:
                raise ProblemError(f"formulation: the tolerance after '@' must be a number "
                                   f"in (0, 1), got {value!r}")
        for name, (label, _) in FORMS.items():
            if v.lower() in (name, label.lower()):
                return Formulation(name, False, eps)
            if v.lower() in (name + RUIZ, label.lower() + "r"):
                return Formulation(name, True, eps)
    raise ProblemError(f"formulation must be one of {', '.join(NAMES)} (or F1..F5, F1r..F5r)"
                       f", each with an optional @EPS, or 'best', got {value!r}")


#: the committed evidence behind ``formulation="best"`` (package data, written by
#: benchmarks/formulation_success.py from results/formulations/)
BEST_FILE = "best_formulations.json"


def best_formulations(settings: str = "high") -> dict[str, str]:
    """Back-end name -> its best formulation on the paper grid at ``settings`` (the
    committed table, per profile: at ``default`` a solver's own tolerance means
    something else in an equilibrated form, so the forms best at ``high`` are not
    best there). A back-end or a profile not in it keeps its own form."""
    return dict(_best_table().get("best", {}).get(settings, {}))


def best_eps(settings: str = "default") -> dict[str, float]:
    """Back-end name -> the tolerance ε its ``best`` recipe hands it at ``settings``
    (the committed table's ``eps``, with its reason beside it): the loosest ε measured
    to meet issue 37's target there. A back-end or a profile not in it is handed the
    profile's own (at ``default``: none, the back-end's own tolerance)."""
    table = _best_table().get("eps", {})
    return {k: float(v) for k, v in table.get(settings, {}).items()}


def _best_table() -> dict:
    """The committed table :data:`BEST_FILE` (package data), {} where it is missing."""
    import json
    from importlib.resources import files

    path = files("lcpbench.model").joinpath(BEST_FILE)
    return json.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}


def handed(settings: Settings, form: Formulation | None) -> Settings:
    """The settings the back-end is handed in ``form``: ``settings`` with the recipe's
    ε where ``form`` carries one (:attr:`Formulation.eps`), else ``settings`` itself."""
    if form is None or form.eps is None:
        return settings
    from dataclasses import replace

    return replace(settings, eps=form.eps)


def native(backend) -> Formulation:
    """The form a back-end always had: F2 for a QP back-end, F1 for an LCP one."""
    return Formulation("heights" if backend.form == "qp" else "gaps")


def resolve_formulation(backend, value, settings="high") -> Formulation | None:
    """The formulation ``backend`` is handed for ``value`` (a name, "best" or None) at
    ``settings`` (a profile's name or Settings: "best" is per profile); None where that
    is its own form (today's path, unchanged). "best" is the measured recipe: the form,
    its equilibration and, where the table gives one for a profile that hands no ε
    (``default``), the ε the back-end is handed (:attr:`Formulation.eps`; then not
    None even in the back-end's own form). A form the back-end does not take is one
    ProblemError naming those it takes."""
    if value is None:
        return None
    if isinstance(value, str) and value.strip().lower() == "best":
        from ..solvers.registry import get_settings

        profile = getattr(settings, "name", settings)
        best = best_formulations(profile).get(backend.name)
        form = native(backend) if best is None else parse_formulation(best)
        eps = best_eps(profile).get(backend.name)
        if eps is not None and get_settings(settings).eps is None:
            return _accepted(backend, Formulation(form.name, form.equilibrated, eps))
    else:
        form = parse_formulation(value)
    if form.eps is not None and backend.storage == "banded":
        raise ProblemError(f"formulation: {backend.name} takes no tolerance ε (it solves "
                           f"each contact step exactly), got {value!r}")
    if form == native(backend):
        return None
    return _accepted(backend, form)


def _accepted(backend, form: Formulation) -> Formulation:
    if not accepts(backend, form):
        takes = [str(Formulation(n, e)) for n in FORMS for e in (False, True)
                 if accepts(backend, Formulation(n, e))]
        raise ProblemError(f"formulation: {backend.name} does not take {form} "
                           f"({form.label}); it takes {', '.join(takes)}")
    return form


def accepts(backend, formulation: Formulation) -> bool:
    """Whether ``backend`` (a registry record) takes ``formulation``, from its data:
    an LCP back-end takes the LCPs (F1, F4); a QP back-end those too (as QPs in z >= 0)
    and the box QP (F2), and the forms with rows (F3, F5) where ``linear_rows``; a
    back-end that runs the contact step itself (the banded active set) only F2."""
    kind = formulation.kind
    if backend.storage == "banded":  # it reads the step's bands: the height QP itself
        return kind == "box" and not formulation.equilibrated
    if backend.form == "lcp":
        return kind == "lcp"
    return kind != "rows" or backend.linear_rows


def step_scales(step, scaled: bool) -> tuple[float, float]:
    """(length, force) units of the form handed to the back-end: ℓ and EI/ℓ², or 1."""
    if not scaled:
        return 1.0, 1.0
    return float(step.length_scale), float(step.force_scale)


def step_qp(step, scaled: bool = True) -> BoxQP:
    """The step as a bound-constrained QP, in the units of ``step_scales``.

    A step with elastic walls has its own forms (:mod:`lcpbench.model.elastic`):
    handing its rigid QP over would drop the walls' springs, so it is refused.
    """
    _rigid_only(step, "step_qp")
    n = step.size
    data, indices, indptr, c, lo, hi, b = step.qp_form(*step_scales(step, scaled))
    return BoxQP(sp.csc_matrix((data, indices, indptr), shape=(n, n)), c, lo, hi, bands=b)


def step_lcp(step, scaled: bool = True):
    """The step as an LCP (the condensed contact form) and its unit vectors.

    Returns ``(form, M̃, q̃, dz, dw)`` with ``z = dz ⊙ z̃`` and ``w = dw ⊙ w̃``:
    gaps in units of ℓ and reactions in units of EI/ℓ² (the channel's second
    block swaps the two).
    """
    _rigid_only(step, "step_lcp")
    return step.lcp_form(*step_scales(step, scaled))


def _rigid_only(step, what: str) -> None:
    if getattr(step, "elastic", False):
        raise ProblemError(f"{what}: this step has elastic walls; its forms are "
                           "lcpbench.model.elastic.elastic_qp / reaction_lcp")


def _free_shift(step) -> int:
    return int(step.free_nodes[0]) + 1


def kinematic_matrix(step) -> object:
    """J, the joint angles' rows on the free nodes (φ̂ = φ̂(u₀) + J (u − u₀), eq. 21):
    a sparse ``joints x n`` matrix of three diagonals (1/mm)."""
    n, nj = step.size, step.base.size
    cols = step.base[:, None] + np.arange(3)[None, :] - _free_shift(step)
    rows = np.repeat(np.arange(nj), 3).reshape(nj, 3)
    keep = (cols >= 0) & (cols < n)
    return sp.csr_matrix((step.coef[keep], (rows[keep], cols[keep])), shape=(nj, n))


def lifted_qp(step, scaled: bool = True) -> LinearQP:
    """F3: unknowns x = [δũ; φ̂] (the height increments δu = u − u₀ over ℓ, the joint
    angles φ̂), minimise ½ Σ k̃ (φ̂ − φ*)² − f̃ᵀ δũ subject to φ̂ − J̃ δũ = φ̂(u₀)
    (J̃ = Jℓ) and the walls on δũ. The Hessian is diag(0, k̃) (plus the Newton term
    T on δũ), the equality tridiagonal: K is never formed."""
    _rigid(step)
    L, F = step_scales(step, scaled)
    n, nj = step.size, step.base.size
    kt = step.stiffness / (F * L)
    Puu = sp.csr_matrix((n, n))
    if step.geometric is not None:
        b = step.geometric * (L / F)
        Puu = sp.diags([b[1, : n - 1], b[0], b[1, : n - 1]], [-1, 0, 1], shape=(n, n))
    P = sp.block_diag([Puu, sp.diags(kt)], format="csc")
    c = np.r_[-step.nodal_load / F, -kt * step.rest_joint]
    Jt = kinematic_matrix(step) * L
    A = sp.hstack([-Jt, sp.identity(nj)], format="csr")
    inf = np.full(nj, np.inf)
    return LinearQP(P, c, np.r_[(step.lower - step.origin) / L, -inf],
                    np.r_[(step.upper - step.origin) / L, inf], A=A,
                    row_lower=step.phi_origin.copy(), row_upper=step.phi_origin.copy())


def wall_rows(step) -> tuple[np.ndarray, np.ndarray]:
    """(free-node indices of the upper wall rows, of the lower wall rows)."""
    return np.flatnonzero(np.isfinite(step.upper)), np.flatnonzero(np.isfinite(step.lower))


def _signs(step) -> tuple[np.ndarray, np.ndarray]:
    """G's rows: the node of each wall row and its sign (+1 upper, −1 lower)."""
    iu, il = wall_rows(step)
    return np.r_[iu, il], np.r_[np.ones(iu.size), -np.ones(il.size)]


def _scaled_bands(step, L: float, F: float) -> np.ndarray:
    return step.bands * (L / F)


@dataclass
class ReactionLCP:
    """F4: ``w = W λ + q``, ``0 <= λ ⟂ w >= 0``: λ the reactions R/(EI/ℓ²) on the wall
    rows G (upper then lower), w the gaps over ℓ, W = G H̃⁻¹ Gᵀ the compliance."""

    M: np.ndarray
    q: np.ndarray
    nodes: np.ndarray  # the free node of each row
    signs: np.ndarray  # +1 an upper wall row, −1 a lower one


def reaction_lcp(step, scaled: bool = True) -> ReactionLCP:
    """F4 from the banded factor of H: W = G H̃⁻¹ Gᵀ, q = h̃ − G ũ_free with ũ_free
    = −H̃⁻¹ c̃ the unconstrained minimiser (O(N m) for m wall rows). With elastic
    walls the compliances 1/k of the rows join W's diagonal: w is the compliant gap
    g + R/k (:mod:`lcpbench.model.elastic`), and M is positive definite where every
    wall yields. Rigid walls: the height step only (in increments the step has its own
    face solves); elastic walls on any step, the banded factor of its H (the elastic
    walls' hand-off to an LCP back-end, :mod:`lcpbench.model.elastic_step`)."""
    if not getattr(step, "elastic", False):
        _in_heights(step)
    L, F = step_scales(step, scaled)
    nodes, sign = _signs(step)
    n, m = step.size, nodes.size
    Gt = np.zeros((n, m))
    Gt[nodes, np.arange(m)] = sign
    b = _scaled_bands(step, L, F)
    Y = solveh_banded(b, np.column_stack([Gt, -step.linear / F]), lower=True,
                      check_finite=False)
    W = Gt.T @ Y[:, :m]
    M = 0.5 * (W + W.T)
    if getattr(step, "elastic", False):
        cu, cl = compliances(step)
        M[np.diag_indices_from(M)] += np.where(sign > 0, cu[nodes], cl[nodes]) * (F / L)
    h = np.where(sign > 0, step.upper[nodes], -step.lower[nodes]) / L
    return ReactionLCP(M, h - sign * Y[nodes, m], nodes, sign)


def heights_from_reactions(step, lcp: ReactionLCP, lam: np.ndarray,
                           scaled: bool = True) -> np.ndarray:
    """u = −H⁻¹ (c + Gᵀ R): the heights at reactions λ (one banded solve)."""
    L, F = step_scales(step, scaled)
    rhs = -step.linear / F
    np.add.at(rhs, lcp.nodes, -lcp.signs * lam)
    return L * solveh_banded(_scaled_bands(step, L, F), rhs, lower=True, check_finite=False)


def link_heights(step) -> np.ndarray:
    """S: δy_i = Σ_{k<i} a cos α_k Δα_k (eq. 21 summed), a dense (N+1) x N matrix (mm)."""
    N = step.links
    S = np.tril(np.ones((N + 1, N)), -1)
    return S / step.inv_a_cos[None, :]


def angle_qp(step, scaled: bool = True) -> LinearQP:
    """F5: unknowns the link-angle increments Δα (rad); φ̂ = φ̂(u₀) + D Δα (D the joint
    differences), δu = S Δα; minimise ½ Σ k̃ (φ̂ − φ*)² − f̃ᵀ S Δα / ℓ subject to the
    linearised gaps on the wall rows and δy = 0 at the fixed nodes."""
    _rigid(step)
    if step.geometric is not None:
        raise ProblemError("formulation 'angles' takes the paper's Gauss-Newton step "
                           "(method 'globalised' or 'undamped'), not the Newton step")
    L, F = step_scales(step, scaled)
    N, nj = step.links, step.base.size
    left, right = step.base - 1, step.base  # joint j joins links base−1 and base
    keep = left >= 0
    D = sp.csr_matrix((np.r_[np.ones(nj), -np.ones(int(keep.sum()))],
                       (np.r_[np.arange(nj), np.flatnonzero(keep)],
                        np.r_[right, left[keep]])), shape=(nj, N))
    kt = step.stiffness / (F * L)
    P = (D.T @ sp.diags(kt) @ D).tocsc()
    S = link_heights(step) / L
    free = step.free_nodes
    fixed = np.setdiff1d(np.arange(1, N + 1), free)
    c = D.T @ (kt * (step.phi_origin - step.rest_joint)) - S[free].T @ (step.nodal_load / F)
    iu, il = wall_rows(step)
    walls = np.union1d(iu, il)
    A = sp.csr_matrix(np.vstack([S[free[walls]], S[fixed]]))
    lo = np.r_[(step.lower[walls] - step.origin[walls]) / L, np.zeros(fixed.size)]
    hi = np.r_[(step.upper[walls] - step.origin[walls]) / L, np.zeros(fixed.size)]
    inf = np.full(N, np.inf)
    return LinearQP(P, c, -inf, inf, A=A, row_lower=lo, row_upper=hi)


def _rigid(step) -> None:
    if getattr(step, "elastic", False):
        raise ProblemError("a step with elastic walls has its own forms "
                           "(lcpbench.model.elastic)")
    _in_heights(step)


def _in_heights(step) -> None:
    if getattr(step, "factor", None) is not None:
        raise ProblemError("a step in increments (large N) has its own face solves; "
                           "the formulations take the height step")


# -- running a formulation on a back-end ---------------------------------------------
def _failed(n: int, message: str, status: Status = Status.FAILED, **kw) -> StepSolution:
    return StepSolution(np.full(n, np.nan), np.zeros(n), np.zeros(n), status,
                        message=message, **kw)


def _split(step, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Net signed reaction R (upper pushes: R > 0) -> (upper, lower) reactions."""
    return np.maximum(R, 0.0), np.maximum(-R, 0.0)


def _solve_qp(mod, backend, qp, s: Settings, equilibrated: bool):
    """(x, y, y_rows, QPResult) of a QP back-end on ``qp``, Ruiz-scaled if asked."""
    scaling = None
    if equilibrated:
        scaling = equilibrate_qp(qp.P, qp.c, getattr(qp, "A", None))
        qp = scale_qp(qp, scaling)
    res = mod.solve_qp(qp, s, None, **backend.options)
    x, y, yr = res.x, res.y, res.y_rows
    if scaling is not None:
        x, y, yr = unscale_qp(scaling, x, y, yr)
    return x, y, yr, res


def _solve_lcp(backend, M: np.ndarray, q: np.ndarray, s: Settings, equilibrated: bool):
    """(z, w, LCPSolution) of any back-end on the LCP, Ruiz-scaled if asked."""
    D = None
    if equilibrated:
        M, q, D = equilibrate_lcp(M, q)
    res = run_lcp(backend, M, q, s, None)
    z, w = res.z, res.w
    if D is not None:
        z, w = D * z, w / D
    return z, w, res


def gaps_answer(step, form, z: np.ndarray, w: np.ndarray):
    """Heights and reactions (u, R_upper, R_lower) of an answer (z, w) of the step's LCP
    in gaps (F1, ``form``: ``step.lcp_form``'s): the upper rows' reactions are w, a
    channel's lower rows' are z past the gap rows."""
    n, m = step.size, form.n_gap
    r_up, r_lo = np.zeros(n), np.zeros(n)
    r_up[form.rows] = w[:m]
    if z.size > m:
        r_lo[form.rows] = z[m:]
    return step.from_lcp(form, z), r_up, r_lo


def run_formulation(backend, step, s: Settings, formulation: Formulation,
                    scaled: bool) -> StepSolution:
    """``backend``'s answer to ``step`` in ``formulation``, mapped back to heights and
    reactions (not yet judged: :func:`lcpbench.model.step_solver.solve_step` does)."""
    n = step.size
    if not accepts(backend, formulation):
        return _failed(n, f"{backend.name} does not take formulation {formulation} "
                          f"({formulation.label}, {formulation.kind})")
    mod = backend.load()
    L, F = step_scales(step, scaled)
    t0 = time.perf_counter()
    try:
        if formulation.name == "gaps":
            form, M, q, dz, dw = step_lcp(step, scaled)
            build = time.perf_counter() - t0
            z, w, res = _solve_lcp(backend, M, q, s, formulation.equilibrated)
            if not np.all(np.isfinite(z)):
                return _failed(n, res.message, _not_solved(res.status), build_time=build)
            u, r_up, r_lo = gaps_answer(step, form, z * dz, w * dw)
        elif formulation.name == "reactions":
            lcp = reaction_lcp(step, scaled)
            build = time.perf_counter() - t0
            lam, _, res = _solve_lcp(backend, lcp.M, lcp.q, s, formulation.equilibrated)
            if not np.all(np.isfinite(lam)):
                return _failed(n, res.message, _not_solved(res.status), build_time=build)
            u = heights_from_reactions(step, lcp, lam, scaled)
            r_up, r_lo = np.zeros(n), np.zeros(n)
            up = lcp.signs > 0
            r_up[lcp.nodes[up]] = lam[up] * F
            r_lo[lcp.nodes[~up]] = lam[~up] * F
        else:
            qp = step_qp(step, scaled) if formulation.name == "heights" \
                else _problem(step, formulation.name, scaled)
            build = time.perf_counter() - t0
            x, y, yr, res = _solve_qp(mod, backend, qp, s, formulation.equilibrated)
            if not np.all(np.isfinite(x)):
                return _failed(n, res.message, _not_solved(res.status), build_time=build)
            u, R = _back_from_qp(step, formulation.name, qp, x, y, yr, L, F)
            r_up, r_lo = _split(step, R)
    except ProblemError as exc:
        return _failed(n, f"formulation {formulation}: {exc}")
    return StepSolution(u, r_up, r_lo, res.status, res.iterations, res.solve_time,
                        res.setup_time, res.message,
                        time_source=getattr(res, "time_source", None)
                        or res.extra.get("time_source", "solver"), build_time=build)


def _not_solved(status: Status) -> Status:
    return status if status is not Status.SOLVED else Status.FAILED


def _problem(step, name: str, scaled: bool) -> LinearQP:
    return lifted_qp(step, scaled) if name == "lifted" else angle_qp(step, scaled)


def _back_from_qp(step, name: str, qp, x, y, yr, L: float, F: float):
    """(u, net R) from a QP form's answer: R is the multiplier of the walls."""
    n = step.size
    if name == "heights":
        return x * L, y * F
    if name == "lifted":
        return step.origin + L * x[:n], y[:n] * F
    # angles: δu = S Δα; R on the wall rows from their multipliers
    S = link_heights(step)
    u = step.origin + S[step.free_nodes] @ x
    R = np.zeros(n)
    walls = np.union1d(*wall_rows(step))
    R[walls] = yr[: walls.size] * F
    return u, R


# -- a bare LCP (an LCP file): the forms it has -----------------------------------------
def lcp_formulation(backend, value, settings="default") -> Formulation | None:
    """The form a bare LCP ``w = M z + q`` (``lcpbench lcp FILE``) is handed to ``backend``
    in, for ``value`` (a name, "best" or None); None: as given (F1). A bare LCP has F1
    and F4 (each ±ruiz) only: F2, F3 and F5 need the contact step's chain (one
    ProblemError). "best": the back-end's best form at ``settings`` where it is one of
    these, else the LCP as given."""
    if value is None:
        return None
    if isinstance(value, str) and value.strip().lower() == "best":
        best = best_formulations(getattr(settings, "name", settings)).get(backend.name)
        form = None if best is None else parse_formulation(best)
        if form is None or form.kind != "lcp":
            return None
    else:
        form = parse_formulation(value)
    if form.kind != "lcp":
        raise ProblemError(f"formulation: an LCP file has the forms gaps, gaps+ruiz, "
                           f"reactions and reactions+ruiz only ({form} needs the contact "
                           "step's chain)")
    return None if form == Formulation("gaps") else form


def solve_lcp_in(M, q, solver: str, settings="default",
                 formulation: str | Formulation | None = None):
    """:func:`lcpbench.solvers.runner.solve_lcp` with the LCP handed in ``formulation``
    (:func:`lcp_formulation`): ``gaps+ruiz`` the Ruiz-scaled D M D; ``reactions`` the
    dual in w, 0 <= w ⟂ M⁻¹ w − M⁻¹ q >= 0 (z its slack: M symmetric positive definite,
    else one ProblemError; with ``best``, the LCP as given). The answer's z is mapped back
    and judged on (M, q) itself;
    ``sol.extra["formulation"]`` says which form ran."""
    import scipy.linalg as sla

    from ..solvers.registry import get_backend, get_settings
    from ..solvers.runner import check_lcp, is_symmetric, judge_lcp, solve_lcp

    s = get_settings(settings)
    form = lcp_formulation(get_backend(solver), formulation, s)
    if form is None:
        return solve_lcp(M, q, solver, s)
    M, q = check_lcp(M, q)
    Mt, qt, cho = M, q, None
    if form.name == "reactions":
        try:
            if not is_symmetric(M):
                raise np.linalg.LinAlgError
            cho = sla.cho_factor(0.5 * (M + M.T))
        except (np.linalg.LinAlgError, ValueError):
            if formulation == "best":  # the best form is for the contact step's M: else
                return solve_lcp(M, q, solver, s)  # the LCP as given
            raise ProblemError("formulation reactions (the dual in w) needs M symmetric "
                               "positive definite") from None
        Mt = sla.cho_solve(cho, np.eye(q.size))
        Mt, qt = 0.5 * (Mt + Mt.T), -sla.cho_solve(cho, q)
    D = None
    if form.equilibrated:
        Mt, qt, D = equilibrate_lcp(Mt, qt)
    sol = solve_lcp(Mt, qt, solver, handed(s, form))  # the form's ε, where it has one
    zt = sol.z if D is None else D * sol.z
    # in F4 the unknown is w and z is its slack: z = M⁻¹ (w − q)
    z = sla.cho_solve(cho, zt - q, check_finite=False) if form.name == "reactions" else zt
    sol.z, sol.w = z, M @ z + q
    sol.extra["formulation"] = str(form)
    return judge_lcp(M, q, sol, s)
