"""The frictional options of a scene (issue 39): Coulomb walls, end conditions, a pull.

Checked here, in the user's units, so that :class:`~lcpbench.problems.scenes.ActuatorScene`
only stores them. What they mean is in docs/friction.md:

* ``friction`` — the Coulomb coefficient μ of the walls: one number for every wall,
  or one per wall (upper, then lower in a channel); 0 is the paper's frictionless
  wall.
* ``left_end``, ``right_end`` — ``"pinned"`` (held in y and x; both ends pinned is
  the paper's support, the right pin on a roller), ``"slider"`` (held in y, free
  along x) or ``"free"``.
* ``pull`` — an axial force P (N, along +x) on the right end, which must be a
  slider or free.
"""

from __future__ import annotations

import copy

from ..errors import ProblemError
from .checks import check_choice, check_number, describe

#: the end conditions of a chain, in docs/friction.md's order
END_CONDITIONS = ("pinned", "slider", "free")
#: allowed μ (Coulomb coefficient; 0 = frictionless)
FRICTION_RANGE = (0.0, 1e3)
#: allowed |P| (N)
PULL_LIMIT = 1e6


def check_friction(value, walls: int) -> float | tuple[float, ...]:
    """μ as a float (one number for every wall) or a tuple of ``walls`` floats, each
    in [0, 1e3]; ProblemError naming ``friction`` otherwise."""
    if isinstance(value, (list, tuple)):
        if len(value) != walls:
            raise ProblemError(f"friction must be one number or one per wall ({walls} "
                               f"here: upper{', lower' if walls == 2 else ''}), got "
                               f"{len(value)} values")
        return tuple(_mu(v) for v in value)
    return _mu(value)


def _mu(value) -> float:
    return check_number("friction", value, low=FRICTION_RANGE[0], high=FRICTION_RANGE[1],
                        unit="(Coulomb coefficient μ, one per wall or one for all)")


def wall_friction(friction, walls: int) -> tuple[float, float]:
    """(μ of the upper wall, μ of the lower wall); 0 for a wall that is not there."""
    if isinstance(friction, tuple):
        return (friction[0], friction[1] if walls == 2 else 0.0)
    return (friction, friction if walls == 2 else 0.0)


def check_end(name: str, value) -> str:
    """An end condition: one of :data:`END_CONDITIONS`."""
    return check_choice(name, value, END_CONDITIONS)


def check_pull(value) -> float:
    """P (N): a finite number in [−1e6, 1e6]."""
    return check_number("pull", value, low=-PULL_LIMIT, high=PULL_LIMIT, unit="N")


def check_support(left: str, right: str, pull: float, mu: tuple[float, float],
                  channel: bool = True) -> None:
    """ProblemError when the chain is not held: a pull on a pinned end, both ends free,
    a free end without a channel (one wall above and the weight both push a free end
    away: it swings about the other end), or nothing that holds x (no pinned end and
    frictionless walls)."""
    if pull != 0.0 and right == "pinned":
        raise ProblemError(f"pull acts on the right end, which must be 'slider' or 'free' "
                           f"(right_end='pinned' holds x); got pull={describe(pull)} "
                           f"with right_end='pinned'")
    if left == "free" and right == "free":
        raise ProblemError("left_end and right_end cannot both be 'free': nothing holds "
                           "the chain (pin an end or make it a slider)")
    if "free" in (left, right) and not channel:
        raise ProblemError("a free end needs channel=True: with one wall above, the wall and "
                           "the weight both push the free end away and nothing holds the "
                           "chain (it swings about the other end)")
    if "pinned" not in (left, right) and not any(m > 0 for m in mu):
        raise ProblemError(f"nothing holds the chain along x: left_end={left!r} and "
                           f"right_end={right!r} with frictionless walls; pin an end "
                           f"('pinned') or give friction > 0")


class FrictionOptions:
    """The frictional options of a scene (``friction``, ``left_end``, ``right_end``,
    ``pull``: fields of the frozen dataclass that takes this in), checked once for
    every scene kind that has them (:class:`~lcpbench.problems.scenes.ActuatorScene`,
    :class:`~lcpbench.problems.sections.SectionedScene`)."""

    def _check_friction_options(self) -> None:
        walls = 2 if self.channel else 1
        put = object.__setattr__
        put(self, "friction", check_friction(self.friction, walls))
        put(self, "left_end", check_end("left_end", self.left_end))
        put(self, "right_end", check_end("right_end", self.right_end))
        put(self, "pull", check_pull(self.pull))
        check_support(self.left_end, self.right_end, self.pull, self.wall_friction,
                      self.channel)

    def with_pull(self, pull: float):
        """This scene with another axial pull (N): a copy whose frictional options are
        checked again (the pull: a number, on an end that is not pinned), not its other
        fields, which a pull does not change (``dataclasses.replace`` would check them all
        again, a wall profile sampled over its reach among them). What the scene keeps
        for pickling (:meth:`__getstate__`) is kept; its chain is not."""
        new = copy.copy(self)
        object.__setattr__(new, "pull", pull)
        new._check_friction_options()
        return new

    @property
    def wall_friction(self) -> tuple[float, float]:
        """(μ of the upper wall, μ of the lower wall); 0 where there is no wall."""
        return wall_friction(self.friction, 2 if self.channel else 1)

    @property
    def frictional(self) -> bool:
        """Whether the scene leaves the paper's model (friction, an end other than
        pinned, a pull): solved along a path, :func:`lcpbench.solve_path`."""
        return is_frictional(self.friction, self.left_end, self.right_end, self.pull)


def is_frictional(friction, left: str, right: str, pull: float) -> bool:
    """Whether the options leave the paper's model: μ > 0 on a wall, an end other than
    pinned, or a pull."""
    mus = friction if isinstance(friction, tuple) else (friction,)
    return (any(m > 0 for m in mus) or left != "pinned" or right != "pinned"
            or pull != 0.0)
