"""Trace extraction and spot detection on images with known answers; renderer determinism."""

import math

import numpy as np
import pytest

from labkit.synth import LaserSpec, render_laser
from labkit.vision.laser.trace import detect_spot, trace_points
from labkit.vision.shared.curves import Pattern


def gaussian_spot(x, y, sigma=2.0, size=(200, 150), peak=200.0, background=30.0):
    yy, xx = np.mgrid[0:size[1], 0:size[0]].astype(float)
    img = background + peak * np.exp(-((xx - x) ** 2 + (yy - y) ** 2) / (2 * sigma ** 2))
    return np.repeat(np.clip(img, 0, 255).astype(np.uint8)[:, :, None], 3, axis=2)


def test_detect_spot_sub_pixel():
    spot = detect_spot(gaussian_spot(73.3, 41.7))
    assert spot is not None
    assert math.hypot(spot.x - 73.3, spot.y - 41.7) < 0.1


def test_detect_spot_none_on_a_flat_frame():
    assert detect_spot(np.full((100, 100, 3), 50, np.uint8)) is None


def test_trace_points_lie_on_a_drawn_circle_with_gradient_and_hole():
    spec = LaserSpec(pattern=Pattern("circle", (160.4, 120.3), 0.0, (70.0, 70.0)), size=(320, 240), frames=1,
                     exposure_s=1.0, cycle_hz=2.0, gradient=60.0, hole_radius_px=8.0, noise_sigma=3.0,
                     halo_sigma_px=5.0, halo_strength=0.3, seed=4)
    frame = next(render_laser(spec))
    tp = trace_points(frame)
    r = np.hypot(tp.points[:, 0] - 160.4, tp.points[:, 1] - 120.3)
    assert len(tp.points) > 300
    assert np.median(np.abs(r - 70.0)) < 0.5
    # the same image as a region of interest gives the same points in frame coordinates
    roi = frame[40:220, 60:260]
    tq = trace_points(roi, offset=(60, 40), frame_px=320)
    rq = np.hypot(tq.points[:, 0] - 160.4, tq.points[:, 1] - 120.3)
    assert np.median(np.abs(rq - 70.0)) < 0.5


def test_renderer_is_seeded():
    spec = LaserSpec(frames=3, size=(160, 120), noise_sigma=5.0, jitter_px=0.5, seed=7)
    a, b = list(render_laser(spec)), list(render_laser(spec))
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    spec.seed = 8
    c = list(render_laser(spec))
    assert not np.array_equal(a[0], c[0])


def test_no_trace_on_pure_noise():
    rng = np.random.default_rng(0)
    img = np.clip(rng.normal(60, 4, (120, 160, 3)), 0, 255).astype(np.uint8)
    assert len(trace_points(img).points) == 0


@pytest.mark.parametrize("level", [0, 255])
def test_no_trace_on_flat_images(level):
    assert len(trace_points(np.full((50, 60, 3), level, np.uint8)).points) == 0


def _ring_with_a_faint_half(noise_sigma: float = 7.0, seed: int = 2):
    """A 320x240 frame: a ring of radius 70 px and about 8 px line, its right half 80 grey levels
    above the screen and its left half 45 (over half the bright half, under 8 raw noise sigmas,
    56, but far above the noise of the smoothed image); beside it a faint disc and a faint 1 px
    stroke leaving the bright half, both as faint as the faint half."""
    import cv2

    light = np.zeros((240, 320), np.float32)
    cv2.ellipse(light, (160, 120), (70, 70), 0, -90, 90, 80.0, 8, cv2.LINE_AA)
    cv2.ellipse(light, (160, 120), (70, 70), 0, 90, 270, 45.0, 8, cv2.LINE_AA)
    cv2.circle(light, (35, 40), 6, 45.0, -1, cv2.LINE_AA)
    cv2.line(light, (235, 150), (300, 215), 45.0, 1, cv2.LINE_AA)
    light = cv2.GaussianBlur(light, (0, 0), 1.0)
    rng = np.random.default_rng(seed)
    frame = np.clip(60.0 + light + rng.normal(0.0, noise_sigma, light.shape), 0, 255).astype(np.uint8)
    return frame


def test_faint_light_is_kept_where_it_continues_the_line_and_only_there():
    """Hysteresis (docs/explanation/laser-analysis.md, trace): the faint half of the ring continues the
    bright half and is found; a faint disc apart from it and a stroke much thinner than the line are not."""
    tp = trace_points(_ring_with_a_faint_half())
    x, y = tp.points[:, 0], tp.points[:, 1]
    r = np.hypot(x - 160, y - 120)
    on_ring = np.abs(r - 70) < 4
    left = on_ring & (x < 150)
    # the faint half is traced along most of its length (angles from 100 to 260 degrees)
    angles = np.degrees(np.arctan2(y[left] - 120, x[left] - 160)) % 360
    assert np.histogram(angles, bins=16, range=(100, 260))[0].min() > 0
    assert np.median(np.abs(r[left] - 70)) < 0.7
    assert not np.any(np.hypot(x - 35, y - 40) < 10), "a faint blob apart from the line is not trace"
    stroke = (np.abs((x - 235) - (y - 150)) < 3) & (x > 245) & (x < 300)
    assert not np.any(stroke), "a faint stroke thinner than the line is not its continuation"
