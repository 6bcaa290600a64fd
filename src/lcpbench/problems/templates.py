"""Arrays of a scene's chain that depend on a few numbers only, made from templates.

A chain of N equal links has many arrays that are one number repeated (EI/a,
the link load μ, the walls ±h). numpy's ``np.full`` costs about five times a copy,
so each such array is copied from a read-only template kept per (size, value).
The chain gets its own writable copy (the kernels' argument types, and a user
writing into one chain's array changes no other); the templates are never
handed out. Tests compare each array with its definition, bit for bit.
"""

from __future__ import annotations

import functools
import math

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
      numpy sum);
    - ``_loaded``: whether a link carries a load (``lcpbench.model.wall_free``).
    """
    return {"_nodal_load": filled(n - 1, (0.0 + 0.5 * load) + 0.5 * load).copy(),
            "_total_load": _total(n, load, math.copysign(1.0, load)),
            "_loaded": load != 0.0}


@functools.lru_cache(maxsize=64)
def _total(n: int, load: float, sign: float) -> float:
    return float(np.sum(np.abs(filled(n, load))))
