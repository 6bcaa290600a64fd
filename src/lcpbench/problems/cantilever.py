"""Sec. III-G's validation scene: a clamped–free beam under a uniform load per length,
pushed toward a wall at ``y = +h``, with the Euler–Bernoulli answers it is checked
against (eqs. 33–37)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scenes import (
    DEFAULT_EI,
    DEFAULT_LENGTH,
    DEFAULT_LINKS,
    EI_RANGE,
    HEIGHT_RANGE,
    LENGTH_RANGE,
    LOAD_RANGE,
    Chain,
    in_range,
    links_value,
    node_stiffness,
    reachable,
    wall_stiffness,
)
from .templates import wall_share


@dataclass(frozen=True)
class CantileverScene:
    """Sec. III-G: a clamped–free beam, uniform load toward a wall at distance h.

    Parameters
    ----------
    load : float
        Distributed load F (N/mm) pushing the beam toward the wall, in [0, 1e6].
    height : float
        Distance h from the undeformed beam to the wall (mm), in [1e-6, 1e6].
    links : int
        As for :class:`ActuatorScene`, but not "auto".
    length, EI, wall_stiffness :
        As for :class:`ActuatorScene`.

    Notes
    -----
    The clamp is a torsional spring of stiffness 2EI/a holding link 1 toward
    the horizontal: it stands for the half-link [0, a/2] between the clamp and
    the first link's centre, which makes the chain second-order accurate (the
    paper does not say which stiffness it used).
    """

    load: float = 0.001
    height: float = 1.0
    links: int = DEFAULT_LINKS
    length: float = DEFAULT_LENGTH
    EI: float = DEFAULT_EI
    wall_stiffness: float = math.inf

    def __post_init__(self):
        object.__setattr__(self, "wall_stiffness", wall_stiffness(self.wall_stiffness))
        object.__setattr__(self, "load", in_range("load", self.load, LOAD_RANGE, "N/mm"))
        object.__setattr__(self, "height", in_range("height", self.height, HEIGHT_RANGE, "mm"))
        object.__setattr__(self, "links", links_value(self.links, auto=False))
        object.__setattr__(self, "length", in_range("length", self.length, LENGTH_RANGE, "mm"))
        object.__setattr__(self, "EI", in_range("EI", self.EI, EI_RANGE, "N·mm²"))

    def chain(self) -> Chain:
        n = int(self.links)
        a = self.length / n
        joints = np.column_stack([np.arange(-1, n - 1), np.arange(n)])
        stiffness = np.full(n, self.EI / a)
        stiffness[0] = 2 * self.EI / a
        free = np.arange(1, n + 1)  # nodes 2..N+1 (the tip is free)
        can = reachable(free * a, self.length, self.height, "clamped-free")
        return Chain(
            links=n,
            link_length=a,
            rest_alpha=np.zeros(n),
            joint_stiffness=stiffness,
            joint_links=joints,
            rest_joint=np.zeros(n),
            link_load=np.full(n, self.load * a),
            free_nodes=free,
            upper=np.where(can, self.height, np.inf),
            lower=np.full(n, -np.inf),
            force_scale=self.EI / self.length**2,
            length=self.length,
            wall=self.height,
            upper_stiffness=node_stiffness(self.wall_stiffness, can, wall_share(n, a, free)),
            consecutive=True,
        )

    # -- Euler–Bernoulli theory, eqs. (33)–(37) ------------------------------
    def theory_force(self) -> float:
        """Tip reaction R_t from linear beam theory (N), eqs. (34)–(37); 0 if no contact."""
        F, h, ell, EI = self.load, self.height, self.length, self.EI
        f_c = 8 * EI * h / ell**4  # (34)
        f_r = F - f_c  # (35)
        if f_r <= 0:
            return 0.0
        dy_r = f_r * ell**4 / (8 * EI)  # (36)
        return 3 * EI * dy_r / ell**3  # (37)

    def theory_deflection(self, x: np.ndarray) -> np.ndarray:
        """Unconstrained deflection Δy(x) = F x²(x² − 4ℓx + 6ℓ²)/(24 EI), eq. (33)."""
        F, ell, EI = self.load, self.length, self.EI
        return F * x**2 * (x**2 - 4 * ell * x + 6 * ell**2) / (24 * EI)
