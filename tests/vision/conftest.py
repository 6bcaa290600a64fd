"""Shared rendered images (drawn once per session) for the vision tests.

The expected values come from the renderer's ground truth (the shape it was
given), never from the pipeline's own output.
"""

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import pytest  # noqa: E402

pytest.importorskip("cv2")
pytest.importorskip("skimage")

import cv2  # noqa: E402

cv2.setNumThreads(1)


@pytest.fixture(scope="session")
def rendered():
    """``rendered(theta, px_per_mm, seed, all_nuisances)`` → (image, truth), cached."""
    from lcpbench.vision.render import Nuisances, render_unconstrained

    cache = {}

    def get(theta, px_per_mm=12.0, seed=0, nuisances=True, rotation=None):
        key = (theta, px_per_mm, seed, nuisances, rotation)
        if key not in cache:
            nz = Nuisances.all_on(seed) if nuisances else Nuisances(seed=seed)
            if rotation is not None:
                nz.rotation_deg = rotation
            cache[key] = render_unconstrained(theta, px_per_mm=px_per_mm, nuisances=nz)
        return cache[key]

    return get
