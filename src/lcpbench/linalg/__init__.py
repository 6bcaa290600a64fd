"""Banded storage and its arithmetic, shared by the model and the back-ends.

The lowest numerical layer: it knows matrices, not actuators or solvers.
"""

from .banded import banded_matvec, cholesky_banded, dense_to_bands, solveh_banded, sparse, sub_bands

__all__ = ["banded_matvec", "cholesky_banded", "dense_to_bands", "solveh_banded", "sparse",
           "sub_bands"]
