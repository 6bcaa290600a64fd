"""The pipeline on photographs drawn by the second, independent renderer
(tests/vision/agg_photos.py: matplotlib's Agg, closed-form arcs). The expected
values are the shapes the renderer was given, never the pipeline's output."""

import math

import numpy as np
import pytest
from agg_photos import Scene, arcs, draw

from lcpbench.vision.measure import measure

#: issue 41's per-image bound (the target's max) on the middle section's θ and ℓ
MAX_ERROR = 0.008


@pytest.mark.parametrize("theta", [10.0, 34.0, 175.0])
def test_closed_form_arcs_are_a_tangent_chain_of_the_given_theta_and_length(theta):
    chain = arcs(theta, 25.0, 3)
    r = 25.0 / math.radians(theta)
    for a in chain:
        assert a["radius"] * abs(a["a1"] - a["a0"]) == pytest.approx(25.0, rel=1e-12)
        for ang, pin in ((a["a0"], a["pins"][0]), (a["a1"], a["pins"][1])):
            np.testing.assert_allclose(a["centre"] + r * np.array([math.cos(ang), math.sin(ang)]),
                                       pin, atol=1e-12)
    # tangent continuity at the inflection points: consecutive centres are collinear
    # with the shared pin, on opposite sides of it
    for a, b in zip(chain, chain[1:]):
        u, v = a["centre"] - a["pins"][1], b["centre"] - b["pins"][0]
        assert abs(u[0] * v[1] - u[1] * v[0]) < 1e-9 and u @ v < 0
    # the middle section bulges up by its sagitta
    mid = chain[1]
    assert mid["centre"][1] + r == pytest.approx(r * (1 - math.cos(math.radians(theta) / 2)))


def test_pixel_convention_bearing_centres_are_the_pins():
    """With no nuisance, the dark bearing pixels' centroid is the pin (OpenCV's pixel
    centres), to the anti-aliasing's accuracy."""
    scene = Scene(theta_deg=50.0, px_per_mm=12.0, rotation_deg=7.0, texture=0, shadow=False,
                  distortion=False, blur_px=0, noise=0, jpeg=None)
    img, truth = draw(scene)
    v = img.max(axis=2).astype(float)
    for p in truth["pins_px"]:
        r = int(scene.bearing_mm * scene.px_per_mm)
        x0, y0 = int(p[0]) - r, int(p[1]) - r
        win = v[y0:y0 + 2 * r + 1, x0:x0 + 2 * r + 1]
        w = np.clip(120 - win, 0, None)     # the dark ring only (hub, tube, paper are light)
        yy, xx = np.mgrid[0:win.shape[0], 0:win.shape[1]]
        c = np.array([(w * xx).sum(), (w * yy).sum()]) / w.sum() + [x0, y0]
        np.testing.assert_allclose(c, p, atol=0.02)


CASES = [  # θ, ℓ, hue, marker side, px/mm, rotation: low θ, the hard case, high θ
    (10.0, 30.0, 200.0, "left", 12.0, -6.0),
    (34.0, 25.15, 120.0, "above", 11.0, 4.0),
    (175.0, 22.0, 300.0, "right", 10.0, 9.0),
]


@pytest.mark.parametrize("theta,length,hue,side,ppm,rot", CASES)
def test_measured_middle_section_matches_the_second_renderers_truth(theta, length, hue, side,
                                                                    ppm, rot):
    scene = Scene(theta_deg=theta, length_mm=length, hue_deg=hue, marker_side=side,
                  px_per_mm=ppm, rotation_deg=rot, seed=int(theta))
    img, truth = draw(scene)
    m = measure(img, calibration=truth["calibration"])       # automatic segmentation
    mid = m.sections[m.middle]
    assert m.px_per_mm == pytest.approx(ppm, rel=1e-3)
    np.testing.assert_allclose([m.bearings.left, m.bearings.right], truth["pins_px"], atol=0.15)
    assert mid.theta_deg == pytest.approx(theta, rel=MAX_ERROR)
    assert mid.arc_length_mm == pytest.approx(length, rel=MAX_ERROR)
    assert not m.warnings, m.warnings


def test_measures_through_an_occluder_across_the_middle_section():
    """A bar hides the middle section's crest and cuts the tube in two: the pieces are
    chained and the joint fit measures the whole actuator across the gap."""
    theta, length = 60.0, 30.0
    chord = 2 * length / math.radians(theta) * math.sin(math.radians(theta) / 2)
    scene = Scene(theta_deg=theta, length_mm=length, px_per_mm=12.0, rotation_deg=3.0,
                  occluder=(1.5 * chord, 4.0), seed=5)
    img, truth = draw(scene)
    m = measure(img, calibration=truth["calibration"])
    mid = m.sections[m.middle]
    assert mid.theta_deg == pytest.approx(theta, rel=MAX_ERROR)
    assert mid.arc_length_mm == pytest.approx(length, rel=MAX_ERROR)
    # the hidden part has no centerline points
    x = m.centerline_mm[:, 0]
    inside = (x > 1.5 * chord - 1.5) & (x < 1.5 * chord + 1.5)
    assert not inside.any()
