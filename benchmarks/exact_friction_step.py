"""The frictional step as sparse exact equations, from the doubles it was built from:
the data half of :mod:`exact_friction` (its module note says why the primal form; not
library code: the tests and the friction benchmarks use it through exact_friction)."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

#: a link whose |tan α| is at most this is level (both its nodes at a wall to round-off):
#: its tan α is taken as 0, so that T per node along a run at a wall is exactly
#: indeterminate, as it is in fact, not decided by the round-off of the nodes' heights
LEVEL = 1e-12


def to_fraction(x) -> Fraction:
    """A double, exactly."""
    return Fraction(float(x))


@dataclass
class PrimalStep:
    """A frictional step as sparse exact equations. Unknowns 0..n−1; ``mechanics``: the
    equalities every index set shares [(coefficients by unknown, right-hand side)];
    ``normal[r]``/``gap[r]``: wall row r's N unknown and its gap (constant,
    coefficients), ``tangential[c]``/``slip[c]`` the same for pair c; ``mu``, ``pair``
    per row; ``moves``: the unknowns that move the chain; ``force``/``length``: the
    scales of N and of g, s (the LCP's units); ``link``: the link length (the move's
    scale); ``names``: the unknowns by kind and node (:func:`chain_step`)."""

    n: int
    mechanics: list
    normal: list
    gap: list
    tangential: list
    slip: list
    mu: list
    pair: list
    moves: list
    force: float = 1.0
    length: float = 1.0
    link: float = 1.0
    names: dict = field(default_factory=dict)


def chain_step(fs) -> PrimalStep:
    """The :class:`PrimalStep` of a ``FrictionStep`` (see the module's note)."""
    P = fs.parts
    bands, f, t = P["bands"], P["f"], P["tan"]
    first, right_datum = int(P["first"]), bool(P["right_datum"])
    nh, links = bands.shape[1], t.size
    rot = P["rot"]
    nxy, txy = fs.normal_xy, fs.tangent_xy
    rows_at = {}
    for r, j in enumerate(fs.normal_node):
        rows_at.setdefault(first + int(j), []).append(r)
    pairs_at = {}
    for c, node in enumerate(fs.friction_node):
        pairs_at.setdefault(int(node), []).append(c)
    count = [0]

    def new():
        count[0] += 1
        return count[0] - 1

    tau = new() if fs.has_tau else None
    Y, X, L = {}, {}, {}
    Nv, Tv = [None] * fs.normal_node.size, [None] * fs.friction_node.size
    for i in range(links + 1):  # node by node: a narrow band
        if first <= i < first + nh:
            Y[i] = new()
        X[i] = new()
        if i < links:
            L[i] = new()
        for r in rows_at.get(i, []):
            Nv[r] = new()
        for c in pairs_at.get(i, []):
            Tv[c] = new()
    rho = new() if rot.size else None
    T = [Fraction(0) if abs(v) <= LEVEL else to_fraction(v) for v in t]

    def Fx(i):  # the force along x at node i
        d = {Nv[r]: to_fraction(nxy[r, 0]) for r in rows_at.get(i, []) if nxy[r, 0] != 0.0}
        d.update({Tv[c]: to_fraction(txy[c, 0]) for c in pairs_at.get(i, []) if txy[c, 0] != 0.0})
        return d

    def add(d, k, v):
        if v != 0:
            d[k] = d.get(k, 0) + v

    eqs = []
    for j in range(nh):  # the heights' equilibrium (H symmetric, lower band storage)
        J, row = first + j, {}
        for jj in range(max(0, j - 2), min(nh, j + 3)):
            add(row, Y[first + jj], to_fraction(bands[abs(j - jj), min(j, jj)]))
        if rho is not None:
            add(row, rho, to_fraction(P["rot_k"]) * to_fraction(rot[j]))
        for r in rows_at.get(J, []):
            add(row, Nv[r], -to_fraction(nxy[r, 1]))
        for c in pairs_at.get(J, []):
            add(row, Tv[c], -to_fraction(txy[c, 1]))
        if J >= 1:
            add(row, L[J - 1], T[J - 1])
        if J < links:
            add(row, L[J], -T[J])
        eqs.append((row, to_fraction(f[j])))
    if tau is not None:  # k_τ τ = f_τ + Σ F^x (= L_0 + F^x_0, the left datum)
        row = {tau: to_fraction(P["k_tau"]), L[0]: Fraction(-1)}
        for k, v in Fx(0).items():
            add(row, k, -v)
        eqs.append((row, to_fraction(f[nh])))
    if rho is not None:
        row = {rho: Fraction(1)}
        for j in range(nh):
            add(row, Y[first + j], -to_fraction(rot[j]))
        eqs.append((row, Fraction(0)))
    for i in range(1, links + 1):  # δx_i − δx_{i−1} = −tan α_{i−1} (δy_i − δy_{i−1})
        row = {X[i]: Fraction(1), X[i - 1]: Fraction(-1)}
        if i in Y:
            add(row, Y[i], T[i - 1])
        if i - 1 in Y:
            add(row, Y[i - 1], -T[i - 1])
        eqs.append((row, Fraction(0)))
    if right_datum:
        eqs.append(({X[links]: Fraction(1)}, Fraction(0)))
    elif tau is not None:
        eqs.append(({X[0]: Fraction(1), tau: Fraction(-1)}, Fraction(0)))
    else:
        eqs.append(({X[0]: Fraction(1)}, Fraction(0)))
    for k in range(links):  # the links' horizontal forces: Dᵀ F^x = Σ_k e_k L_k
        row = {L[k]: Fraction(1)}
        if right_datum:  # L_k = −Σ_{i<=k} F^x_i
            if k >= 1:
                row[L[k - 1]] = Fraction(-1)
            for key, v in Fx(k).items():
                add(row, key, v)
        else:  # L_k = Σ_{i>k} F^x_i
            if k + 1 < links:
                row[L[k + 1]] = Fraction(-1)
            for key, v in Fx(k + 1).items():
                add(row, key, -v)
        eqs.append((row, Fraction(0)))
    gap, slip = [], []
    for r, j in enumerate(fs.normal_node):
        J, d = first + int(j), {}
        add(d, X[J], to_fraction(nxy[r, 0]))
        add(d, Y[J], to_fraction(nxy[r, 1]))
        add(d, Nv[r], to_fraction(P["compliance"][r]))
        gap.append((to_fraction(P["gap"][r]), d))
    for c, node in enumerate(fs.friction_node):
        node, d = int(node), {}
        add(d, X[node], to_fraction(txy[c, 0]))
        if node in Y:
            add(d, Y[node], to_fraction(txy[c, 1]))
        slip.append((to_fraction(P["slip"][c]), d))
    moves = list(Y.values()) + list(X.values()) + ([tau] if tau is not None else [])
    return PrimalStep(count[0], eqs, Nv, gap, Tv, slip, [to_fraction(m) for m in fs.mu],
                      [int(p) for p in fs.pair], moves, fs.force, fs.length,
                      fs.length / links, dict(Y=Y, X=X, L=L, tau=tau, rho=rho))


def answer_values(fs, step: PrimalStep, z: np.ndarray) -> np.ndarray:
    """Every unknown of ``step`` (a :func:`chain_step`) from the LCP answer z, in floats."""
    N, T, dy, tau = fs.forces(z)
    nm = step.names
    v = np.zeros(step.n)
    first = int(fs.parts["first"])
    t = fs.parts["tan"]
    links = t.size
    Yd = np.zeros(links + 1)
    for i, k in nm["Y"].items():
        Yd[i] = dy[i - first]
        v[k] = dy[i - first]
    if nm["tau"] is not None:
        v[nm["tau"]] = tau
    if nm["rho"] is not None:
        v[nm["rho"]] = float(fs.parts["rot"] @ dy)
    x = np.zeros(links + 1)
    x[0] = tau
    for i in range(1, links + 1):
        x[i] = x[i - 1] - t[i - 1] * (Yd[i] - Yd[i - 1])
    if fs.parts["right_datum"]:
        x -= x[links]
    Fx = np.zeros(links + 1)
    first_node = first + np.asarray(fs.normal_node)
    np.add.at(Fx, first_node, fs.normal_xy[:, 0] * N)
    np.add.at(Fx, np.asarray(fs.friction_node), fs.tangent_xy[:, 0] * T)
    Lk = -np.cumsum(Fx)[:links] if fs.parts["right_datum"] else np.cumsum(Fx[::-1])[::-1][1:]
    for i, k in nm["X"].items():
        v[k] = x[i]
    for i, k in nm["L"].items():
        v[k] = Lk[i]
    v[step.normal] = N
    v[step.tangential] = T
    return v
