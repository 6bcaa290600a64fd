"""Elastic (tissue-like) walls: the contact step with compliance (issue 17, item 2).

A Winkler wall of stiffness k (N/mm per mm of wall) acts on free node i as a
one-sided spring of stiffness k_i = k · share_i (N/mm), share_i the node's
share of wall length (:func:`lcpbench.problems.scenes.wall_share`). The wall's
reaction R_i (eq. 30's R, N) and the node's gap g_i = h − u_i (< 0: the node
indents the wall) satisfy the LCP with compliance

    R ≥ 0,   g + R/k ≥ 0,   R · (g + R/k) = 0,

and the step is the QP with the matching penalty, min Q(u) + Σ ½ k_i (u_i − h_i)₊²
(Q the step's quadratic, :mod:`lcpbench.model.step`).

QP back-ends (and the banded active set) get a box QP. The penalty is not
quadratic, so each node with an elastic wall gets one more unknown per wall
(:func:`elastic_qp`):

* the **spring form** (the one handed over): x = (u_i, v⁺_i, v⁻_i), minimise
  Q(u) + Σ ½ k (u − v)² with v⁺ <= h, v⁻ >= lower: v is the point of the wall's
  surface the node's spring holds; for fixed u the minimum over v is the
  penalty. R = k (u − v) is the multiplier of v's bound.
* the **split form**: u_i = v_i + δ⁺_i − δ⁻_i with v_i in the walls and δ ≥ 0,
  minimise Q(u) + Σ ½ k_i δ_i². The same u, but a node off the wall has v and δ
  both free with u = v + δ, so a solver's round-off in δ moves u, which the
  chain's stiffness turns into force far from the wall (measured: 1.6e-7 of
  EI/ℓ² after the active set clipped δ = −3e-13 to its bound). In the spring
  form that round-off sits in v and costs only k times itself. Kept for
  comparison (tests), not handed over.

Both Hessians are positive definite (xᵀPx = uᵀHu + Σ k (u − v)², or + Σ k δ²).
The unknowns are interleaved node by node, so P stays banded: a pentadiagonal
H gives a half-bandwidth of at most 8 (5 with one wall), and every solve is
O(N).

LCP back-ends get the LCP in the reactions (F4 with the compliances,
:func:`lcpbench.model.formulations.reaction_lcp`): z = R, w the
compliant gaps g + R/k, M = W + diag(1/k) with W = H⁻¹ on the wall rows
(signed for the lower wall). It is dense, as every LCP back-end's input is,
built by banded solves, and symmetric positive definite where the walls are
elastic: no pair is degenerate off the walls, and Gauss–Seidel applies. The
banded LCP of the split form (z = (g, δ)) was tried first: every node off the
walls is a degenerate pair there (δ = 0 and k δ − R = 0), and Lemke stopped on
it with a natural residual of 0.7 on the channel at N = 140.

A rigid wall (k = inf) adds no unknown to the QP and a zero to M's diagonal,
so a rigid step's forms are those of rigid walls (tests check this).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..problems.templates import wall_share

if TYPE_CHECKING:
    import scipy.sparse as sp


def compliances(obj) -> tuple[np.ndarray, np.ndarray]:
    """1/k of the upper and lower wall per free node (mm/N; 0 for a rigid wall).

    ``obj`` is a Chain or a ContactStep (anything with ``upper``,
    ``upper_stiffness``, ``lower_stiffness``).
    """
    n = np.asarray(obj.upper).size
    return compliance(obj.upper_stiffness, n), compliance(obj.lower_stiffness, n)


def compliance(k, n: int) -> np.ndarray:
    """1/k of one wall (mm/N; 0 where rigid): ``k`` its stiffness per free node, or the
    rows of several chains' stacked (element by element the same numbers); None: a
    rigid wall, ``n`` zeros."""
    if k is None:
        return np.zeros(n)
    with np.errstate(divide="ignore"):
        return np.where(np.isfinite(k), 1.0 / np.asarray(k, float), 0.0)


def wall_springs(obj) -> tuple[np.ndarray, np.ndarray]:
    """Finite stiffness k_i (N/mm) of the upper / lower wall per free node (0 where rigid
    or no wall) of a Chain or a ContactStep."""
    n = np.asarray(obj.upper).size
    out = []
    for k, wall in ((obj.upper_stiffness, obj.upper), (obj.lower_stiffness, obj.lower)):
        if k is None:
            out.append(np.zeros(n))
        else:
            k = np.asarray(k, float)
            out.append(np.where(np.isfinite(k) & np.isfinite(wall), k, 0.0))
    return out[0], out[1]


def indentation(obj, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Depth (mm, >= 0) by which each free node at height ``u`` indents the upper
    and the lower wall: (u − h)₊ and (lower − u)₊; 0 where the wall is absent."""
    with np.errstate(invalid="ignore"):
        up = np.where(np.isfinite(obj.upper), np.maximum(u - obj.upper, 0.0), 0.0)
        lo = np.where(np.isfinite(obj.lower), np.maximum(obj.lower - u, 0.0), 0.0)
    return up, lo


def _penalty(obj, u: np.ndarray, grad: np.ndarray) -> float:
    from ..numba_cache import kernel_module  # numba: loads or compiles at first use

    cu, cl = compliances(obj)
    return float(kernel_module("lcpbench.model.chain_kernel").wall_penalty(
        np.ascontiguousarray(u, dtype=float), np.ascontiguousarray(obj.lower, dtype=float),
        np.ascontiguousarray(obj.upper, dtype=float), cu, cl, grad))


def penalty(obj, u: np.ndarray) -> float:
    """The walls' elastic energy Σ ½ k_i δ_i² (N·mm) at free-node heights ``u``
    (:func:`lcpbench.model.chain_kernel.wall_penalty`)."""
    return _penalty(obj, u, np.empty(0))


def penalty_gradient(obj, u: np.ndarray) -> np.ndarray:
    """∂/∂u of :func:`penalty` (N): k (u − h)₊ − k (lower − u)₊."""
    grad = np.zeros(np.asarray(u).size)
    _penalty(obj, u, grad)
    return grad


def wall_pressure(chain, y_free: np.ndarray, forces_upper: np.ndarray,
                  forces_lower: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """(indentation depth δ (mm), contact pressure per length p (N/mm)) per free node.

    δ_i = (y_i − h)₊ into an elastic upper wall or (−h − y_i)₊ into a lower one
    (0 at a rigid wall, which does not yield); p_i = (R_i + R_lower,i) / share_i,
    the node's reaction over its share of wall length
    (:func:`lcpbench.problems.scenes.wall_share`). At an elastic wall p = k δ; at
    a rigid one p is the reaction smeared over a link, which grows with N at the
    edges of a contact (the rigid wall's point forces).
    """
    if not chain.elastic_walls:
        depth = np.zeros(y_free.size)  # rigid walls do not yield
    else:
        ku, kl = wall_springs(chain)
        up, lo = indentation(chain, y_free)
        depth = np.maximum(np.where(ku > 0, up, 0.0), np.where(kl > 0, lo, 0.0))
    share = wall_share(chain.links, chain.link_length, chain.free_nodes)
    total = np.maximum(forces_upper, 0.0)
    if forces_lower is not None:
        total = total + np.maximum(forces_lower, 0.0)
    return depth, total / share


@dataclass
class ElasticQP:
    """An elastic step's box QP in x, and the map back to the heights u.

    ``u_rows`` (n,): the row of x whose value (``form="spring"``) or whose sum
    with the node's δ rows (``"split"``) is u_i; ``E`` (n × m, sparse): u = E x.
    ``node`` (m,): the free node of each row; ``kind`` (m,): 0 for the node's own
    row, +1 for the upper wall's, −1 for the lower wall's. ``react`` (m,): the
    rows whose bound multiplier is a wall reaction R. ``P``, ``c``, ``lower``,
    ``upper``, ``bands``: the QP in mm and N.
    """

    form: str
    E: sp.csr_matrix
    node: np.ndarray
    kind: np.ndarray
    react: np.ndarray
    P: sp.csc_matrix
    c: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    bands: np.ndarray

    @property
    def size(self) -> int:
        return self.c.size

    @property
    def u_rows(self) -> np.ndarray:
        return np.flatnonzero(self.kind == 0)

    def heights(self, x: np.ndarray) -> np.ndarray:
        """Free-node heights u = E x."""
        return self.E @ x

    def reactions(self, y: np.ndarray) -> np.ndarray:
        """Net wall reaction per node (N, + the upper wall pushes down) from the
        signed bound multipliers y (+: an upper bound's)."""
        return np.bincount(self.node[self.react], y[self.react], minlength=self.E.shape[0])

    def start(self, u: np.ndarray) -> np.ndarray:
        """x for heights ``u`` (a warm start)."""
        x = np.zeros(self.size)
        own = self.u_rows
        up, lo = self.kind > 0, self.kind < 0
        if self.form == "spring":  # u itself; each wall's v = u clipped to that wall
            x[own] = np.clip(u, self.lower[own], self.upper[own])
            x[up] = np.minimum(u[self.node[up]], self.upper[up])
            x[lo] = np.maximum(u[self.node[lo]], self.lower[lo])
            return x
        x[own] = np.clip(u, self.lower[own], self.upper[own])  # split: v, then δ
        rest = u - x[own]
        x[up] = np.maximum(rest[self.node[up]], 0.0)
        x[lo] = np.maximum(-rest[self.node[lo]], 0.0)
        return x


def _bands(P: sp.csc_matrix) -> np.ndarray:
    coo = P.tocoo()
    m = P.shape[0]
    width = int(np.max(coo.row - coo.col, initial=0))
    bands = np.zeros((width + 1, m))
    for d in range(width + 1):
        bands[d, : m - d] = P.diagonal(-d)
    return bands


def elastic_qp(step, form: str = "spring") -> ElasticQP:
    """The box QP of an elastic contact step, O(N); interleaved node by node.

    ``form="spring"`` (QP back-ends): x = (u_i, v⁺_i, v⁻_i), minimise
    Q(u) + Σ ½ k (u − v)² with v⁺ <= h, v⁻ >= lower: the wall's surface point v
    is held by a spring to the node, so a round-off in v moves R by k times it,
    never by the chain's stiffness. The multiplier of v's bound is R = k (u − v).
    ``form="split"`` (the LCP): x = (v_i, δ⁺_i, δ⁻_i), u = v + δ⁺ − δ⁻, minimise
    Q(u) + Σ ½ k δ² with v in the walls, δ >= 0 (see the module docstring).
    A rigid wall (k = inf) bounds u (spring) or v (split) itself.
    """
    if form not in ("spring", "split"):
        raise ValueError(f"form must be 'spring' or 'split', got {form!r}")
    n = step.size
    ku, kl = wall_springs(step)
    per = 1 + (ku > 0) + (kl > 0)  # rows per node
    first = np.concatenate(([0], np.cumsum(per)[:-1]))
    m = int(per.sum())
    node = np.repeat(np.arange(n), per)
    kind = np.zeros(m, int)
    iu = first[ku > 0] + 1
    il = first[kl > 0] + 1 + (ku[kl > 0] > 0)
    kind[iu], kind[il] = 1, -1
    import scipy.sparse as sp  # only for elastic walls: the default solve never loads it

    b = step.bands
    H = sp.diags([b[2, : n - 2], b[1, : n - 1], b[0], b[1, : n - 1], b[2, : n - 2]],
                 [-2, -1, 0, 1, 2], shape=(n, n), format="csr")
    spring = np.zeros(m)
    spring[iu], spring[il] = ku[ku > 0], kl[kl > 0]
    lower = np.full(m, -np.inf)
    upper = np.full(m, np.inf)
    if form == "split":
        sign = np.where(kind < 0, -1.0, 1.0)
        E = sp.csr_matrix((sign, (node, np.arange(m))), shape=(n, m))
        P = (E.T @ H @ E + sp.diags(spring)).tocsc()
        lower[first], upper[first] = step.lower, step.upper
        lower[kind != 0] = 0.0
        react = kind == 0
    else:
        E = sp.csr_matrix((np.ones(n), (np.arange(n), first)), shape=(n, m))
        # the walls' springs: ½ k (u − v)², coupling each v to its node's u row
        wall = np.flatnonzero(kind != 0)
        one = np.ones(wall.size)
        G = sp.csr_matrix((np.concatenate([one, -one]),
                           (np.concatenate([wall, wall]),
                            np.concatenate([first[node[wall]], wall]))), shape=(m, m))
        P = (E.T @ H @ E + G.T @ sp.diags(spring) @ G).tocsc()  # G x = u − v per wall row
        rigid_up = np.where(ku > 0, np.inf, step.upper)
        rigid_lo = np.where(kl > 0, -np.inf, step.lower)
        lower[first], upper[first] = rigid_lo, rigid_up
        upper[iu], lower[il] = step.upper[ku > 0], step.lower[kl > 0]
        react = np.isfinite(lower) | np.isfinite(upper)
    P.sum_duplicates()
    return ElasticQP(form, E, node, kind, react, P, E.T @ step.linear, lower, upper, _bands(P))


def scaled_qp(qp: ElasticQP, L: float, F: float):
    """(P̃, c̃, lower/L, upper/L, bands) in the units of the back-end."""
    s = L / F
    return qp.P * s, qp.c / F, qp.lower / L, qp.upper / L, qp.bands * s
