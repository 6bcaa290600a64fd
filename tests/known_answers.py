"""Small problems with known answers, in one place, each with where its answer
comes from: a hand derivation (written beside it), the theory the paper
quotes, the paper's own scenes, or the Siconos collection's expectations.

Tests import what they need (``from known_answers import ...``; pytest puts
``tests/`` on the path, see ``pythonpath`` in pyproject.toml). Nothing here
is computed by lcpbench: an answer that lcpbench produced is not a known
answer.

LCP: find z >= 0 with w = M z + q >= 0 and z'w = 0 (z and w are the LCP's
own letters; in the contact step z = g, the gaps, and w = R, the reactions
of eq. 30).

Box QP: minimise ½ x'Px + c'x subject to lower <= x <= upper, with the
signed bound multiplier y from P x + c + y = 0 (y > 0 where the upper bound
pushes, y < 0 where the lower one does).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

INF = np.inf
HERE = Path(__file__).resolve().parent


# -- LCPs with hand-derived answers ---------------------------------------------------
@dataclass(frozen=True)
class KnownLCP:
    """An LCP (M, q) with its solution z (and w = M z + q); ``source`` says why."""

    M: tuple
    q: tuple
    z: tuple
    w: tuple
    source: str

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """Fresh float copies of (M, q)."""
        return np.array(self.M, dtype=float), np.array(self.q, dtype=float)


#: M = [[2, 1], [1, 2]], q = [-5, -6]: both z > 0, so M z = -q gives z = [4/3, 7/3], w = 0.
BOTH_ACTIVE = KnownLCP(((2.0, 1.0), (1.0, 2.0)), (-5.0, -6.0), (4 / 3, 7 / 3), (0.0, 0.0),
                       "hand: both z > 0, so M z = -q")
#: M = [[2, 1], [1, 2]], q = [1, -4]: z = [0, 2], w = [3, 0] (z_0 = 0 since w_0 = 1 > 0;
#: then 2 z_1 - 4 = 0).
SECOND_ACTIVE = KnownLCP(((2.0, 1.0), (1.0, 2.0)), (1.0, -4.0), (0.0, 2.0), (3.0, 0.0),
                         "hand: z_0 = 0, 2 z_1 - 4 = 0, w_0 = z_1 + 1 = 3")
#: M = I: w = z + q, so z = max(-q, 0) and w = max(q, 0).
IDENTITY = KnownLCP(((1.0, 0.0), (0.0, 1.0)), (-1.0, 2.0), (1.0, 0.0), (0.0, 2.0),
                    "hand: M = I, z = max(-q, 0), w = max(q, 0)")

#: name -> (M, q, z*), every back-end's known-answer LCPs (hand-derived).
LCP_KNOWN = {
    # 2x2 SPD, first constraint active: 2 z1 - 1 = 0, w2 = z1 + 1 = 1.5
    "one-active": ([[2.0, 1.0], [1.0, 2.0]], [-1.0, 1.0], [0.5, 0.0]),
    # diagonal: z_i = max(0, -q_i / M_ii)
    "diagonal": ([[1.0, 0, 0], [0, 2.0, 0], [0, 0, 4.0]], [-1.0, 2.0, -8.0], [1.0, 0.0, 2.0]),
    # degenerate: at z = (1, 0), w = (0, 0): both of the second pair vanish
    "degenerate": ([[2.0, 1.0], [1.0, 2.0]], [-2.0, -1.0], [1.0, 0.0]),
    # no contact: q >= 0 gives z = 0
    "no-contact": ([[2.0, -1.0, 0], [-1.0, 2.0, -1.0], [0, -1.0, 2.0]], [1.0, 0.5, 3.0],
                   [0.0, 0.0, 0.0]),
}

#: (M, q): degenerate non-symmetric LCPs on which Lemke with a naive tie-break
#: (first / last tied row) cycles until the pivot budget runs out. Found by a
#: random search over degenerate LCPs with a planted solution; each has a
#: solution (checked by enumeration in tests/solvers/test_lemke.py).
CYCLING_PRONE = [
    ([[1, 1, -2, -1, 2], [-2, 0, 2, 2, -2], [2, -2, 2, -2, -2], [-1, 2, 0, 2, -2],
      [2, 1, 1, -1, -1]],
     [-4, 4, 1, -2, -4]),
    ([[-1, -1, 1, -1, -2, -1], [1, -1, 1, 0, 2, 0], [1, 0, -1, 1, -2, -1],
      [1, 1, 1, -2, 2, -2], [1, 0, 1, 0, -1, 2], [2, 2, -1, 2, -1, 0]],
     [2, -3, -2, 0, -3, -6]),
    ([[0, -1, -1, 2, 0, -1], [-2, -1, -1, 0, 1, -2], [2, 2, 2, 1, 1, 1],
      [1, -2, 0, 1, 1, -1], [-2, 0, 1, 1, -2, 2], [0, 1, 2, 2, 2, -1]],
     [0, 0, -2, -2, 6, -2]),
]


# -- box QPs with hand-derived answers ------------------------------------------------
#: name -> (P, c, lower, upper, x*, y*), y* from P x* + c + y* = 0 by hand.
BOX_QP_KNOWN = {
    # ½·2x² - 4x, x <= 1: unconstrained 2 -> x = 1, y = -(2 - 4) = 2 > 0 (upper pushes)
    "1d-upper": ([[2.0]], [-4.0], [-INF], [1.0], [1.0], [2.0]),
    # ½·2x² + 4x, x >= -1: x = -1, y = -(-2 + 4) = -2 < 0 (lower pushes)
    "1d-lower": ([[2.0]], [4.0], [-1.0], [INF], [-1.0], [-2.0]),
    # interior of a two-sided box: x = 0.5, y = 0
    "1d-inside": ([[2.0]], [-1.0], [-1.0], [1.0], [0.5], [0.0]),
    # no bound at all: x = -c/P = -0.5, y = 0
    "1d-free": ([[4.0]], [2.0], [-INF], [INF], [-0.5], [0.0]),
    # coupled, x0 <= 0.5 active, x1 free: 2 x1 + 0.5 + 3 = 0 -> x1 = -1.75;
    # y0 = -(2·0.5 - 1.75 - 3) = 3.75
    "2d-upper-free": ([[2.0, 1.0], [1.0, 2.0]], [-3.0, 3.0], [-INF, -INF], [0.5, INF],
                      [0.5, -1.75], [3.75, 0.0]),
    # coupled, upper active on x0 and lower on x1: grad at (1, -1) is (-3, 3)
    "2d-upper-lower": ([[2.0, 1.0], [1.0, 2.0]], [-4.0, 4.0], [-INF, -1.0], [1.0, INF],
                       [1.0, -1.0], [3.0, -3.0]),
    # 3 rows: upper active, lower active, a row without bound
    "3d-mixed": (np.diag([1.0, 1.0, 2.0]), [-1.0, 1.0, 1.0], [-INF, -0.5, -INF],
                 [0.5, INF, INF], [0.5, -0.5, -0.5], [0.5, -0.5, 0.0]),
    # positive SEMIdefinite P, both bounds active: y = -(P x + c) = (0.5, -1)
    "psd": (np.diag([1.0, 0.0]), [-1.0, 1.0], [-INF, -1.0], [0.5, INF],
            [0.5, -1.0], [0.5, -1.0]),
}

#: name -> (H, c, lower, upper, u*, R_upper*, R_lower*): a contact step's box QP
#: in node heights u, with the reactions of the upper and lower walls (>= 0).
CONTACT_QP_KNOWN = {
    # 1-D: minimiser 2 beyond the wall at 1; reaction = -(2·1 - 4) = 2
    "one-node": ([[2.0]], [-4.0], [-INF], [1.0], [1.0], [2.0], [0.0]),
    # 2x2: u* = (5/3, -5/6) crosses the upper wall 1 of node 0 only; with u0 = 1,
    # 2 u1 + 1 = 0 gives u1 = -0.5 and the reaction -(2·1 + 1·(-0.5) - 2.5) = 1
    "two-nodes": ([[2.0, 1.0], [1.0, 2.0]], [-2.5, 0.0], [-INF, -INF], [1.0, INF],
                  [1.0, -0.5], [1.0, 0.0], [0.0, 0.0]),
    # a channel: node 0 pushed up to 1, node 2 pushed down to -1, node 1 free
    "channel": ([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]], [-10.0, 0.0, 10.0],
                [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0], [1.0, 0.0, -1.0], [8.0, 0.0, 0.0],
                [0.0, 0.0, 8.0]),
    # no wall reachable: the unconstrained minimiser, no face solve
    "no-contact": ([[4.0, 1.0], [1.0, 3.0]], [1.0, 2.0], [-INF, -INF], [10.0, 10.0],
                   list(np.linalg.solve([[4.0, 1.0], [1.0, 3.0]], [-1.0, -2.0])), [0.0, 0.0],
                   [0.0, 0.0]),
    # degenerate: the unconstrained minimiser sits exactly on the wall (zero reaction)
    "degenerate": ([[2.0, 0.0], [0.0, 2.0]], [-2.0, -4.0], [-INF, -INF], [1.0, 1.0],
                   [1.0, 1.0], [0.0, 2.0], [0.0, 0.0]),
}


# -- the paper ------------------------------------------------------------------------
#: The paper's default actuator scene at θ = 150°, h = 3 mm (Figs. 5-7; ℓ = 30 mm,
#: EI = 32.01 N·mm², w = 2.45e-4 N/mm, N = 140 are ActuatorScene's defaults).
PAPER_SCENE = {"theta": 150, "height": 3.0, "links": 140}

#: Tip reaction of the cantilever of Sec. III-G by Euler–Bernoulli theory,
#: eqs. (34)-(37), at the paper's load (1 mm tip deflection over 30 mm): 7.69 mN
#: (the paper prints 7.7 mN).
CANTILEVER_THEORY_FORCE = 7.69e-3


def stenosis():
    """A Gaussian narrowing of 0.8 mm at x = 14 mm, 3 mm wide, of the 3 mm wall (the
    stenosis of benchmarks/scene_kinds.py)."""
    from lcpbench.problems.walls import WallProfile

    def h(x):
        return 3.0 - 0.8 * np.exp(-((x - 14.0) / 3.0) ** 2)

    def dh(x):
        return 0.8 * 2 * (x - 14.0) / 9.0 * np.exp(-((x - 14.0) / 3.0) ** 2)

    return WallProfile.from_function(h, dh, name="stenosis")


# -- the Siconos collection -----------------------------------------------------------
#: Siconos's LCP test problems (a copy of its numerics data files).
SICONOS_LCP_DIR = HERE / "data" / "siconos-lcp"
#: What each back-end is expected to do on each of them (solved or not), as data.
SICONOS_EXPECTED = HERE / "solvers" / "data" / "siconos_expected.json"
