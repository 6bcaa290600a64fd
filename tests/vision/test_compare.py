"""Model against photograph: a photograph drawn from the model's own constrained
shape must register onto it (the issue: mean ICP distance < 0.05 mm)."""

import numpy as np
import pytest

from lcpbench.vision.compare import compare, model_centerline
from lcpbench.vision.measure import measure
from lcpbench.vision.render import Nuisances, render_constrained


@pytest.fixture(scope="module")
def constrained():
    theta, height = 150.0, 5.0
    pts, res = model_centerline(theta, height)
    img, truth = render_constrained(pts[:, 0], pts[:, 1], wall_height=height,
                                    px_per_mm=12.0, nuisances=Nuisances.all_on(5))
    return theta, height, img, truth, res


def test_compare_on_the_models_own_shape(constrained):
    theta, height, img, truth, res = constrained
    m = measure(img, calibration=truth["calibration"])
    cmp = compare(m, theta, height)
    assert cmp.distances_mm.mean() < 0.05
    assert cmp.percent.mean() == pytest.approx(100 * cmp.distances_mm.mean() / cmp.span_mm)
    assert cmp.force_n == pytest.approx(res.total_force, rel=1e-9) and cmp.force_n > 0
    # the tube touches the walls: its centerline reaches height - r
    assert np.max(cmp.model_mm[:, 1]) == pytest.approx(height - 1.5, abs=1e-6)


def test_compare_notices_the_wrong_height(constrained):
    theta, height, img, truth, _ = constrained
    m = measure(img, calibration=truth["calibration"])
    # a model 1 mm lower does not fit the photograph: ten times the distance
    assert compare(m, theta, height - 1.0).distances_mm.mean() > 0.2
