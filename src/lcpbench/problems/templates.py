"""Arrays of a scene's chain that depend on a few numbers only, made from templates.

A chain of N equal links has many arrays that are one number repeated (EI/a,
the link load μ, the walls ±h). numpy's ``np.full`` costs about five times a copy,
so each such array is copied from a read-only template kept per (size, value).
The chain gets its own writable copy (the kernels' argument types, and a user
writing into one chain's array changes no other); the functions below return the
read-only templates, which only the chain builders read, to copy them. Tests compare
each array with its definition, bit for bit.

What the chains pinned at both ends with one N and ℓ share whatever θ and h (the link
centres, the joints, the interior nodes, their reach and their share of wall length) is
kept per (N, ℓ) too (:func:`pinned_frame`), and the flat walls per (N, ℓ, h, channel)
(:func:`flat_walls`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np


def filled(size: int, value: float) -> np.ndarray:
    """``np.full(size, value)``, read only: a template that chains copy (a copy costs a
    fifth of np.full)."""
    return _template(size, value, math.copysign(1.0, value))


@functools.lru_cache(maxsize=64)
def _template(size: int, value: float, sign: float) -> np.ndarray:
    """:func:`filled`; ``sign``, that of ``value``, keeps −0.0 and 0.0 (equal as keys)
    apart."""
    arr = np.full(size, value)
    arr.setflags(write=False)
    return arr


def full(size: int, value: float) -> np.ndarray:
    """``np.full(size, value)``, without its Python wrapper."""
    arr = np.empty(size)
    arr.fill(value)
    return arr


def uniform_load(n: int, load: float) -> dict:
    """What the model derives from a chain whose N links each carry ``load`` (N), with
    pins at both ends, computed from the number: kept with the chain
    (:meth:`Chain.derived`; tests check each against its definition):

    - ``_nodal_load``: :attr:`Chain.nodal_load` (half of each link's load to each end:
      an interior node gets ½μ + ½μ, summed as the property sums them);
    - ``_total_load``: Σ|μ_i| (:func:`lcpbench.model.angle_step.total_load`, the same
      numpy sum).
    """
    return {"_nodal_load": filled(n - 1, (0.0 + 0.5 * load) + 0.5 * load).copy(),
            "_total_load": _total(n, load, math.copysign(1.0, load))}


@functools.lru_cache(maxsize=64)
def _total(n: int, load: float, sign: float) -> float:
    return float(np.sum(np.abs(filled(n, load))))


def wall_share(links: int, link_length: float, free_nodes: np.ndarray) -> np.ndarray:
    """Each free node's share of wall length (mm): half of each link it ends.

    A node between two links stands for a, a free tip for a/2: the lengths
    over which a Winkler wall's pressure p (N/mm) adds up to the node's
    reaction R_i = p_i · share_i.
    """
    f = np.asarray(free_nodes)
    ends = (f > 0).astype(float) + (f < links).astype(float)
    return 0.5 * link_length * ends


@dataclass(frozen=True)
class Frame:
    """What the chains pinned at both ends with one N and ℓ share (an actuator scene's,
    a row of sections'), whatever θ and h (read only: a Chain gets copies)."""

    a: float
    half_index: np.ndarray  # k + 1/2, k = 0..N−1 (the link centres, in links)
    joints: np.ndarray
    interior: np.ndarray
    reach: np.ndarray  # min(s, ℓ − s) of the interior nodes (scenes.reachable)
    share: np.ndarray  # the interior nodes' share of wall length (:func:`wall_share`)


def within_reach(reach: np.ndarray, height: float) -> np.ndarray:
    """Which nodes of maximal height ``reach`` (mm: their arc length to the nearer pin)
    can touch a wall at ``height`` (to round-off): the nodes that get a contact row."""
    return reach >= height * (1.0 - 1e-12)


@functools.lru_cache(maxsize=64)
def flat_walls(n: int, length: float, height: float, channel: bool):
    """(upper, lower) wall heights of the free nodes of a chain pinned at both ends, read
    only (chains copy them): ±h on the rows of the nodes that can reach the walls
    (:func:`lcpbench.problems.scenes.reachable`, "pinned-pinned", its reach
    min(s, ℓ − s) kept per frame), ±inf elsewhere; −inf below when not a channel."""
    can = within_reach(pinned_frame(n, length).reach, height)
    upper = np.where(can, height, np.inf)
    lower = np.where(can, -height, -np.inf) if channel else np.full(n - 1, -np.inf)
    for arr in (upper, lower):
        arr.setflags(write=False)
    return upper, lower


@functools.lru_cache(maxsize=32)
def pinned_frame(n: int, length: float) -> Frame:
    """The :class:`Frame` of N links over ℓ (a = ℓ/N), kept per (N, ℓ)."""
    a = length / n
    interior = np.arange(1, n)
    s = interior * a
    frame = Frame(a, np.arange(n) + 0.5,
                   np.column_stack([np.arange(n - 1), np.arange(1, n)]), interior,
                   np.minimum(s, length - s), wall_share(n, a, interior))
    for arr in (frame.half_index, frame.joints, frame.interior, frame.reach, frame.share):
        arr.setflags(write=False)
    return frame
