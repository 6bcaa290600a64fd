"""Each image stage alone, against the renderer's ground truth."""

import json
import math

import cv2
import numpy as np
import pytest

from lcpbench.vision.errors import VisionError
from lcpbench.vision.geometry import resample
from lcpbench.vision.render import TUBE_BGR, Nuisances, arc_sections, distort, render
from lcpbench.vision.stages import (
    centerline,
    detect_marker,
    find_bearings,
    load_calibration,
    load_image,
    segment,
    to_mm,
    to_px,
    undistort,
)


@pytest.mark.parametrize("ppm, rotation", [(10.0, 0.0), (12.0, -8.5), (25.0, 9.7)])
def test_marker_scale(rendered, ppm, rotation):
    img, truth = rendered(90, ppm, nuisances=False, rotation=rotation)
    m = detect_marker(img, 25.0)
    assert m.px_per_mm == pytest.approx(ppm, rel=5e-4)
    # the marker's side in mm is a setting: a 50 mm marker halves px/mm
    assert detect_marker(img, 50.0).px_per_mm == pytest.approx(ppm / 2, rel=5e-4)


@pytest.mark.parametrize("rotation", [-10.0, -3.3, 0.0, 6.1, 10.0])
def test_levelling_on_a_known_rotation(rendered, rotation):
    img, truth = rendered(60, 12.0, nuisances=False, rotation=rotation)
    b = find_bearings(img, 12.0, detect_marker(img))
    assert b.level_deg == pytest.approx(rotation, abs=0.02)
    np.testing.assert_allclose([b.left, b.right], truth["pins_px"], atol=0.1)


def test_pixel_mm_transform_round_trip(rendered):
    img, truth = rendered(60, 12.0, nuisances=False, rotation=7.0)
    b = find_bearings(img, 12.0, detect_marker(img))
    pts = np.array([[0.0, 0.0], [10.0, 5.0], [-3.0, -7.0]])
    np.testing.assert_allclose(to_mm(to_px(pts, b, 12.0), b, 12.0), pts, atol=1e-12)
    # the right pin lands on the x axis at the pin span
    span = np.hypot(*np.subtract(*truth["pins_px"])) / 12.0
    np.testing.assert_allclose(to_mm(b.right, b, 12.0), [span, 0.0], atol=0.01)


def test_undistort_round_trip(rendered):
    ideal, truth = rendered(120, 12.0, nuisances=False, rotation=4.0)
    h, w = ideal.shape[:2]
    cal = {"camera_matrix": [[1.1 * w, 0, w / 2], [0, 1.1 * w, h / 2], [0, 0, 1]],
           "dist_coeffs": [-0.15, 0.05, 0.0, 0.0, 0.0]}
    warped = np.clip(np.round(distort(ideal.astype(float), cal)), 0, 255).astype(np.uint8)
    # the distortion is real: the bearings move by more than a pixel
    bw = find_bearings(warped, 12.0)
    assert np.max(np.abs(np.array([bw.left, bw.right]) - truth["pins_px"])) > 1.0
    back = undistort(warped, cal)
    b = find_bearings(back, 12.0)
    np.testing.assert_allclose([b.left, b.right], truth["pins_px"], atol=0.1)


def test_segmentation_auto_range_finds_the_tube_colour(rendered):
    img, _ = rendered(90, 12.0, nuisances=True)
    seg = segment(img)
    hue = cv2.cvtColor(np.uint8([[TUBE_BGR]]), cv2.COLOR_BGR2HSV)[0, 0, 0]
    assert seg.lower[0] <= hue <= seg.upper[0]
    # the mask's area is the tube's: length 90 mm x 3 mm, less the parts under the discs
    area_mm2 = seg.mask.sum() / 12.0 ** 2
    assert 0.85 * 90 * 3 < area_mm2 < 1.02 * 90 * 3


def test_segmentation_with_a_user_range_that_misses_is_an_error(rendered):
    img, _ = rendered(90, 12.0, nuisances=False)
    with pytest.raises(VisionError, match="segmentation is empty"):
        segment(img, (100, 200, 200), (110, 255, 255))  # blue: nothing of the kind


@pytest.mark.parametrize("theta", [30, 180])
def test_centerline_is_sub_pixel(theta):
    # a clean image: the detected centerline lies on the drawn one to a tenth of a pixel
    c, _ = arc_sections(theta, 30.0, 3)
    img, truth = render(c, px_per_mm=12.0, nuisances=Nuisances(rotation_deg=5.0))
    m = detect_marker(img)
    b = find_bearings(img, m.px_per_mm, m)
    pts, width = centerline(segment(img), b, m.px_per_mm)
    exact = to_px(resample(c, step=0.002), b, m.px_per_mm)
    from scipy.spatial import cKDTree

    d, _ = cKDTree(exact).query(pts)
    assert np.sqrt(np.mean(d ** 2)) < 0.05 and np.percentile(d, 95) < 0.1 and d.max() < 0.2
    assert np.median(width) == pytest.approx(3 * 12.0, rel=0.03)


def test_no_marker_is_an_error(rendered):
    img, truth = rendered(60, 12.0, nuisances=False)
    blank = img.copy()
    q = np.array(truth["marker_corners_px"])
    cv2.fillConvexPoly(blank, np.round(q.mean(0) + 1.2 * (q - q.mean(0))).astype(np.int32),
                       (225, 225, 225))
    with pytest.raises(VisionError, match="no ArUco marker"):
        detect_marker(blank)


def test_load_errors(tmp_path):
    bad = tmp_path / "notes.png"
    bad.write_text("not an image")
    with pytest.raises(VisionError, match="not an image"):
        load_image(bad)
    with pytest.raises(VisionError, match="no such file"):
        load_image(tmp_path / "missing.png")
    cal = tmp_path / "cal.json"
    cal.write_text(json.dumps({"camera_matrix": [[1, 0], [0, 1]], "dist_coeffs": [0] * 5}))
    with pytest.raises(VisionError, match="camera_matrix must be 3x3"):
        load_calibration(cal)
    cal.write_text(json.dumps({"camera_matrix": np.eye(3).tolist(), "dist_coeffs": [0, 1]}))
    with pytest.raises(VisionError, match="dist_coeffs"):
        load_calibration(cal)
    good = load_calibration({"camera_matrix": np.eye(3).tolist(), "dist_coeffs": [0.1] * 5})
    assert len(good["dist_coeffs"]) == 5 and math.isclose(good["camera_matrix"][0][0], 1.0)
