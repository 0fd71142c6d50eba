"""Trace extraction gives the answers of its straightforward formulation bit for bit.

``trace_points`` computes the residual in one pass, the noise's medians from a histogram, the
sub-pixel centroids from the band's pixels only and runs OpenCV single-threaded; each of these
is exact, so every field of its result equals, byte for byte, that of the plain formulation written
out here (float32 residual by subtraction, ``np.median``, ``cv2.threshold``, box filters over the
whole image), on synthetic frames that take every branch: colour and grey, a region of interest,
faint light continuing the line (hysteresis), no sub-pixel, no light.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage

from labkit.synth import LaserSpec, render_laser
from labkit.vision.laser import trace
from labkit.vision.laser.trace import (
    TracePoints,
    background,
    brightness,
    contrast_to_noise,
    integer_noise,
    residual,
    robust_noise,
    trace_points,
)
from labkit.vision.laser.window_centroids import BandLight, dense_window_centroids, window_centroids
from labkit.vision.shared.curves import Pattern
from labkit.vision.shared.opencv_threads import one_opencv_thread, precise_distance_transform


def plain_trace_points(image, offset=(0, 0), subpixel=True, snr=8.0, relative_floor=0.12, frame_px=None):
    """The trace as first written: every step in its plain form."""
    gray = brightness(image)
    res = gray.astype(np.float32) - background(gray, frame_px)
    noise = robust_noise(res)
    smooth = cv2.GaussianBlur(res, (0, 0), 1.0)
    peak = float(smooth.max())
    empty = TracePoints(np.zeros((0, 2)), np.zeros(0), peak, noise)
    floor = max(snr * noise, relative_floor * peak)
    if peak <= snr * noise:
        return empty
    h, w = gray.shape
    r = max(5, int(round(0.01 * (frame_px or max(h, w)))))
    weak_floor = floor if floor <= relative_floor * peak else max(snr * robust_noise(smooth, 10000),
                                                                    relative_floor * peak)
    _, bright = cv2.threshold(smooth, min(floor, weak_floor), 255, cv2.THRESH_BINARY)
    bx, by, bw, bh = cv2.boundingRect(bright.astype(np.uint8))
    if bw == 0 or bh == 0:
        return empty
    x0, y0 = max(0, bx - r - 2), max(0, by - r - 2)
    x1, y1 = min(w, bx + bw + r + 2), min(h, by + bh + r + 2)
    smooth, res = smooth[y0:y1, x0:x1], res[y0:y1, x0:x1]
    local = cv2.dilate(smooth, np.ones((2 * r + 1, 2 * r + 1), np.uint8))
    band = (smooth >= 0.5 * local) & (smooth > 0)
    mask = band & (local >= floor)
    if weak_floor < floor:
        mask = trace._continued(mask, band & (local >= weak_floor), local)
    return plain_centreline(mask, res, (offset[0] + x0, offset[1] + y0), subpixel, peak, noise)


def plain_centreline(mask, res, offset, subpixel, peak, noise):
    bx, by, bw, bh = cv2.boundingRect(mask.astype(np.uint8))
    if bw == 0 or bh == 0:
        return TracePoints(np.zeros((0, 2)), np.zeros(0), peak, noise)
    pad = 14
    x0, y0 = max(0, bx - pad), max(0, by - pad)
    x1, y1 = min(mask.shape[1], bx + bw + pad), min(mask.shape[0], by + bh + pad)
    mask, res = mask[y0:y1, x0:x1], res[y0:y1, x0:x1]
    offset = (offset[0] + x0, offset[1] + y0)
    dist = precise_distance_transform(mask.astype(np.uint8))
    ridge = (dist >= cv2.dilate(dist, np.ones((3, 3), np.uint8)) - 0.35) & (dist > 0)
    ys, xs = np.nonzero(ridge)
    if len(xs) == 0:
        return TracePoints(np.zeros((0, 2)), np.zeros(0), peak, noise)
    x, y = xs.astype(float), ys.astype(float)
    weights = np.ones(len(xs))
    half_width = float(np.median(dist[ys, xs]))
    if subpixel:
        half = int(np.clip(half_width, 1, 12))
        x, y = plain_window_centroids(np.where(mask, res, 0).astype(np.float32), xs, ys, half)
        weights = np.clip(res[ys, xs], 1e-3, None).astype(float)
    pts = np.column_stack([x + offset[0], y + offset[1]])
    bys, bxs = np.nonzero(mask)
    band = np.column_stack([bxs + offset[0], bys + offset[1]]).astype(float)
    band_w = np.clip(res[bys, bxs], 1e-3, None).astype(float) if subpixel else np.ones(len(bxs))
    return TracePoints(pts, weights, peak, noise, band, band_w, 2.0 * half_width)


def plain_window_centroids(weights, xs, ys, half):
    k = 2 * half + 1
    columns = np.arange(weights.shape[1], dtype=np.float32)[None, :]
    row_sum = cv2.boxFilter(weights, -1, (k, 1), normalize=False, borderType=cv2.BORDER_CONSTANT)
    row_moment = cv2.boxFilter(weights * columns, -1, (k, 1), normalize=False, borderType=cv2.BORDER_CONSTANT)
    rows = ys[:, None] + np.arange(-half, half + 1)[None, :]
    inside = (rows >= 0) & (rows < weights.shape[0])
    rows_in, cols = np.clip(rows, 0, weights.shape[0] - 1), xs[:, None]
    r0 = np.where(inside, row_sum[rows_in, cols], 0.0)
    s0 = r0.sum(axis=1)
    sx = np.where(inside, row_moment[rows_in, cols], 0.0).sum(axis=1)
    sy = (r0 * rows).sum(axis=1)
    ok = s0 > 0
    x, y = xs.astype(float), ys.astype(float)
    x[ok], y[ok] = sx[ok] / s0[ok], sy[ok] / s0[ok]
    return x, y


def assert_same_bits(got: TracePoints, want: TracePoints) -> None:
    for name in ("points", "weights", "peak", "noise", "band", "band_weights", "line_width_px"):
        a, b = getattr(got, name), getattr(want, name)
        if a is None or b is None:
            assert a is None and b is None, name
            continue
        a, b = np.asarray(a), np.asarray(b)
        assert (a.dtype, a.shape) == (b.dtype, b.shape), name
        assert a.tobytes() == b.tobytes(), f"{name} differs"


def _frame(size, pattern, seed, **kw):
    spec = LaserSpec(pattern=pattern, size=size, frames=1, exposure_s=1.0, cycle_hz=2.0, seed=seed, **kw)
    return next(render_laser(spec))


def _faint_half_ring():
    """320x240 grey: a ring whose left half is too faint for the noise floor but continues the
    bright right half (the hysteresis branch)."""
    light = np.zeros((240, 320), np.float32)
    cv2.ellipse(light, (160, 120), (70, 70), 0, -90, 90, 80.0, 8, cv2.LINE_AA)
    cv2.ellipse(light, (160, 120), (70, 70), 0, 90, 270, 45.0, 8, cv2.LINE_AA)
    light = cv2.GaussianBlur(light, (0, 0), 1.0)
    noise = np.random.default_rng(2).normal(0.0, 7.0, light.shape)
    return np.clip(60.0 + light + noise, 0, 255).astype(np.uint8)


CIRCLE = Pattern("circle", (160.4, 120.3), 0.0, (70.0, 70.0))
CASES = {
    "colour circle, gradient, hole, halo": lambda: (_frame(
        (320, 240), CIRCLE, 4, gradient=60.0, hole_radius_px=8.0, noise_sigma=3.0, halo_sigma_px=5.0,
        halo_strength=0.3), {}),
    "region of interest": lambda: (
        _frame((320, 240), CIRCLE, 4, gradient=60.0, noise_sigma=3.0)[40:220, 60:260],
        {"offset": (60, 40), "frame_px": 320}),
    "saturated epitrochoid, 640x480": lambda: (_frame(
        (640, 480), Pattern("epitrochoid", (330.0, 236.0), 0.4, scale=120.0, b=0.35, loops=4), 5,
        brightness=3.0, spot_sigma_px=3.0, noise_sigma=4.0, lamp=30.0), {}),
    "grey ellipse, no sub-pixel": lambda: (brightness(_frame(
        (400, 300), Pattern("ellipse", (210.0, 140.0), 0.3, (120.0, 70.0)), 6, noise_sigma=2.0)),
        {"subpixel": False}),
    "faint half continuing the line": lambda: (_faint_half_ring(), {}),
    "no light": lambda: (
        np.clip(np.random.default_rng(0).normal(60, 4, (120, 160, 3)), 0, 255).astype(np.uint8), {}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_trace_points_equal_the_plain_formulation_bit_for_bit(case):
    image, kw = CASES[case]()
    got = trace_points(image, **kw)
    assert_same_bits(got, plain_trace_points(image, **kw))
    if case != "no light":
        assert len(got.points) > 100


def test_the_faint_case_takes_the_hysteresis_branch():
    """The case above is only a check of that branch if the noise, not the peak, sets the floor
    and the smoothed image's noise lets fainter light in."""
    gray = _faint_half_ring()
    res = residual(gray)
    noise = integer_noise(res)
    smooth = cv2.GaussianBlur(res, (0, 0), 1.0)
    peak = float(smooth.max())
    assert 8.0 * noise > 0.12 * peak
    assert max(8.0 * robust_noise(smooth, 10000), 0.12 * peak) < 8.0 * noise


def test_residual_is_the_float_difference():
    gray = brightness(_frame((320, 240), CIRCLE, 4, gradient=60.0, noise_sigma=3.0))[3:237, 5:311]
    got = residual(gray, 320)
    want = gray.astype(np.float32) - background(gray, 320)
    assert got.dtype == np.float32 and got.tobytes() == want.tobytes()


integer_images = st.tuples(st.integers(1, 120), st.integers(1, 120), st.integers(0, 2**31 - 1),
                           st.sampled_from(["uniform", "narrow", "tailed"]))


@settings(max_examples=150, deadline=None)
@given(integer_images, st.integers(1, 60000))
def test_integer_noise_equals_robust_noise(shape_seed_kind, samples):
    h, w, seed, kind = shape_seed_kind
    rng = np.random.default_rng(seed)
    if kind == "uniform":
        values = rng.integers(-255, 256, (h, w))
    elif kind == "narrow":
        values = rng.integers(-2, 3, (h, w))
    else:
        values = np.clip(np.round(rng.standard_cauchy((h, w)) * 4), -255, 255)
    res = values.astype(np.float32)
    assert integer_noise(res, samples) == robust_noise(res, samples)


band_images = st.tuples(st.integers(3, 90), st.integers(3, 140), st.integers(0, 2**31 - 1),
                        st.floats(0.02, 0.9), st.integers(1, 12))


@settings(max_examples=120, deadline=None)
@given(band_images)
def test_window_centroids_from_the_band_equal_the_box_filters(image):
    """Integer light on a random band (negative too, as residuals are): the band's prefix sums and
    the dense box filters give the same centroids bit for bit; both are the windows' centroids."""
    h, w, seed, density, half = image
    rng = np.random.default_rng(seed)
    band = rng.random((h, w)) < density
    light = np.where(band, rng.integers(-40, 256, (h, w)), 0).astype(np.float32)
    rows, cols = np.nonzero(band)
    if len(rows) == 0:
        return
    pick = rng.choice(len(rows), size=min(len(rows), 25), replace=False)
    ys, xs = rows[pick].astype(np.intp), cols[pick].astype(np.intp)
    sparse = window_centroids(BandLight(band, rows, cols, light[rows, cols]), xs, ys, half)
    dense = dense_window_centroids(light, xs, ys, half)
    plain = plain_window_centroids(light, xs, ys, half)
    for a, b, c in zip(sparse, dense, plain, strict=True):
        assert a.tobytes() == b.tobytes() == c.tobytes()
    padded = np.pad(light.astype(np.float64), half)
    for i, (x, y) in enumerate(zip(xs, ys, strict=True)):
        window = padded[y:y + 2 * half + 1, x:x + 2 * half + 1]
        total = window.sum()
        if total > 0:
            wy, wx = np.mgrid[y - half:y + half + 1, x - half:x + half + 1]
            assert abs(sparse[0][i] - (window * wx).sum() / total) < 1e-6 * (1 + abs(x))
            assert abs(sparse[1][i] - (window * wy).sum() / total) < 1e-6 * (1 + abs(y))


def test_window_centroids_of_light_that_is_not_integer_go_the_dense_way():
    rng = np.random.default_rng(3)
    light = np.where(rng.random((40, 50)) < 0.3, rng.normal(50, 20, (40, 50)), 0).astype(np.float32)
    rows, cols = np.nonzero(light)
    xs, ys = cols[::7].astype(np.intp), rows[::7].astype(np.intp)
    got = window_centroids(BandLight(light != 0, rows, cols, light[rows, cols]), xs, ys, 4)
    want = dense_window_centroids(light, xs, ys, 4)
    assert all(a.tobytes() == b.tobytes() for a, b in zip(got, want, strict=True))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(-300, 300, width=32), st.integers(-3, 3))
def test_the_bright_pixels_are_those_cv2_threshold_sets(seed, level, ulps):
    """``smooth > np.float32(t)`` (trace_points) marks what ``cv2.threshold(smooth, t, ...)``
    sets, for thresholds at, beside and between float32 values."""
    rng = np.random.default_rng(seed)
    smooth = rng.normal(level, 5, (37, 41)).astype(np.float32)
    smooth[::3, ::5] = np.float32(level)
    t = np.float32(level)
    if ulps:
        t = np.nextafter(t, np.float32(np.inf * np.sign(ulps)), dtype=np.float32)
    t = float(t) + ulps * 1e-9  # between float32 values too
    _, bright = cv2.threshold(smooth, t, 255, cv2.THRESH_BINARY)
    assert np.array_equal(smooth > np.float32(t), bright > 0)


def _exact_distances(mask: np.ndarray) -> np.ndarray:
    return ndimage.distance_transform_edt(mask).astype(np.float32)  # float64 sqrt: rounds as sqrtf


@pytest.mark.parametrize("threads", [1, 2])
def test_the_precise_distance_transform_is_exact_on_any_pool(threads):
    """With OpenCV's pool at one thread, cv2's precise transform goes to IPP's algorithm, which
    misses the correctly rounded float32 at some pixels (sqrt(37): opencv/opencv#24082);
    precise_distance_transform gives the exact distances either way, in a single-thread section too."""
    rng = np.random.default_rng(11)
    mask = np.ones((150, 160), np.uint8)
    mask[rng.random(mask.shape) < 0.004] = 0
    mask[20, 20], mask[26, 21] = 0, 1  # some pixels 6 and 1 px from their nearest zero: sqrt(37)
    before = cv2.getNumThreads()
    cv2.setNumThreads(threads)
    try:
        got = precise_distance_transform(mask)
        with one_opencv_thread():
            inside = precise_distance_transform(mask)
            assert cv2.getNumThreads() == 1
        assert cv2.getNumThreads() == threads
    finally:
        cv2.setNumThreads(before)
    want = _exact_distances(mask)
    assert got.tobytes() == want.tobytes() and inside.tobytes() == want.tobytes()


def test_contrast_to_noise_is_the_plain_ratio():
    gray = brightness(_frame((320, 240), CIRCLE, 4, gradient=60.0, noise_sigma=3.0))
    res = gray.astype(np.float32) - background(gray, 320)
    want = float(cv2.GaussianBlur(res, (0, 0), 1.0).max()) / robust_noise(res)
    assert contrast_to_noise(gray, 320) == want
