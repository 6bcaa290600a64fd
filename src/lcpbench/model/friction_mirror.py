"""A free left end, solved as the mirror image of a free right end (issue 39,
docs/friction.md, free ends).

The frictional step frees the right end: its tip's height is an unknown and the
rotation about the left end is held by a proximal spring. A chain whose left end is
free is that chain seen from behind (x → −x): node i is the mirror's node N − i, link
k its link N − 1 − k with α'_{N−1−k} = −α_k, and the x of every node, the slips and
the tangential forces change sign; heights and normal forces do not. A row of
sections mirrors into its sections in reverse order (each keeps its θ: a curve
bending clockwise, mirrored and walked the other way, still bends clockwise). The
pull P on the (slider) right end becomes a force −P along x on the mirror's left end
(its datum: it loads the translation τ only, ``left_pull`` of
:func:`~lcpbench.model.friction_driver.solve_state`). So one free end is built once.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..problems.sections import SectionedScene
from .friction_driver import FrictionState
from .friction_result import FrictionResult


def mirrored_scene(scene):
    """(the mirror of a scene whose left end is free, the force along x on its left
    end): its left end is the scene's right end and its right end is free."""
    kw: dict = dict(left_end=scene.right_end, right_end="free", pull=0.0)
    if isinstance(scene, SectionedScene):
        kw["sections"] = scene.sections[::-1]
    return replace(scene, **kw), -float(scene.pull)


def mirror_x(x: np.ndarray) -> np.ndarray:
    """Node x (mm, nodes 1..N+1) in the other frame: x'_i = −x_{N−i}."""
    return -np.asarray(x)[::-1]


def mirror_state(state: FrictionState, link_length: float) -> FrictionState:
    """A path's state in the other frame (α' = −α reversed; x' of the new node 1 is
    −x of the old node N+1)."""
    right = state.x0 + float(np.sum(link_length * np.cos(state.alpha)))
    return FrictionState(-state.alpha[::-1].copy(), -right)


def mirror_result(res: FrictionResult, scene, state: dict) -> FrictionResult:
    """The mirror's judged result in the scene's frame: per node arrays reversed, x,
    slips and tangential forces negated; the scene's own pull."""
    lower = None if res.forces_lower is None else res.forces_lower[::-1].copy()
    return replace(
        res, scene=scene, state=state, x=mirror_x(res.x), y=res.y[::-1].copy(),
        alpha=-res.alpha[::-1], forces=res.forces[::-1].copy(), forces_lower=lower,
        tangential_forces=-res.tangential_forces[::-1], slip=-res.slip[::-1],
        stick=res.stick[::-1].copy(), pull=float(scene.pull))
