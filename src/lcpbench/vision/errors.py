"""The error a vision stage raises on bad input (exit status 2 on the command line)."""

from __future__ import annotations

from ..errors import LcpbenchError


class VisionError(LcpbenchError, ValueError):
    """An image, calibration or setting the pipeline cannot use; the message says what
    to fix (a missing marker, no bearings, an empty segmentation, ...)."""
