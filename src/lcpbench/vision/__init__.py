"""From photographs to the model: the paper's static-image pipeline (Sec. IV-D).

An extra: ``pip install 'lcpbench[vision]'`` (OpenCV, scikit-image). Nothing here
is imported by ``import lcpbench``, and importing this package imports no OpenCV
either: the names below load their module on first use.

Stages (each callable and tested alone):

- :func:`load_calibration`, :func:`undistort` — lens rectification (IV-D-1)
- :func:`detect_marker` — mm per pixel from the ArUco marker (IV-D-2)
- :func:`find_bearings`, :func:`to_mm` — pins, level, origin (IV-D-1, 2)
- :func:`segment` — HSV segmentation (IV-D-3)
- :func:`centerline` — sub-pixel centerline (IV-D-4)
- :func:`inflection_indices`, :func:`fit_circle`, :func:`bend_angle` (eq. 38),
  :func:`arc_length` (eq. 39) — IV-D-5 to 7
- :func:`fit_chain` — one least-squares fit of the chain of k arcs between the
  pins, with standard errors and warnings (the measurement)
- :func:`measure` — all of the above on one photograph
- :func:`fit_theta_pressure` — θ against pressure (eqs. 40-42)
- :func:`compare`, :func:`icp` — model against photograph (IV-D-8, Fig. 23)
- :func:`render_unconstrained`, :func:`render_constrained` — test images with truth
"""

from __future__ import annotations

import importlib

from .errors import VisionError

_WHERE = {
    "load_image": "stages", "load_calibration": "stages", "undistort": "stages",
    "detect_marker": "stages", "find_bearings": "stages", "to_mm": "stages",
    "to_px": "stages", "segment": "stages", "centerline": "stages",
    "refine_centerline": "stages",
    "fit_circle": "geometry", "bend_angle": "geometry", "bend_angle_printed": "geometry",
    "arc_length": "geometry", "inflection_indices": "geometry", "icp": "geometry",
    "rigid_fit": "geometry", "offset_curve": "geometry",
    "measure": "measure", "Measurement": "measure", "analyse_centerline": "measure",
    "analyse": "measure", "fit_chain": "jointfit", "JointFit": "jointfit",
    "Confidence": "jointfit", "chain": "jointfit",
    "fit_theta_pressure": "calibrate", "PressureFit": "calibrate",
    "compare": "compare", "model_centerline": "compare",
    "render": "render", "render_unconstrained": "render", "render_constrained": "render",
    "arc_sections": "render", "Nuisances": "render", "default_calibration": "render",
    "tube_colour": "render",
}

__all__ = ["VisionError", *_WHERE]


def __getattr__(name: str):
    if name in _WHERE:
        return getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
