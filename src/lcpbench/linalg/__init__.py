"""Banded storage and its arithmetic, shared by the model and the back-ends.

The lowest numerical layer: it knows matrices, not actuators or solvers.
"""

from .banded import banded_matvec, dense_to_bands, sub_bands

__all__ = ["banded_matvec", "dense_to_bands", "sub_bands"]
