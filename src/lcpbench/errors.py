"""The exception tree of lcpbench: one base class, specific subclasses.

Foreign errors (numpy, scipy, solver libraries) are re-raised ``from`` the
original so the cause stays visible.
"""

from __future__ import annotations


class LcpbenchError(Exception):
    """Base class of every error lcpbench raises on purpose."""


class ProblemError(LcpbenchError, ValueError):
    """A scene or problem was given a parameter outside its allowed range."""


class SolverNotFound(LcpbenchError, LookupError):
    """An unknown back-end name, or one whose library is not installed."""


class StoreError(LcpbenchError):
    """A results store that cannot be opened, read or written (never overwritten silently)."""
