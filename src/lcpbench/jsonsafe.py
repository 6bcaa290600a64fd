"""JSON-ready copies of results: NaN/±inf become None, numpy becomes Python."""

from __future__ import annotations

import math

import numpy as np


def sanitise(obj):
    """A JSON-ready copy of ``obj``: NaN/±inf become None, numpy becomes Python."""
    if isinstance(obj, dict):
        return {str(k): sanitise(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [sanitise(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return sanitise(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj
