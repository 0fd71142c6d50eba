"""Find the laser light in an image (a frame or an accumulation of frames) and turn it into trace
points: pure functions on arrays.

Robust against background light and gradients (a large-scale median background is subtracted),
the fuzzy halo and saturation (a pixel belongs to the trace when it is at least half as bright as
the brightest pixel within a few pixels, so the kept band is symmetric about the line's centre),
sensor noise and compression artefacts (a robust noise estimate sets the floor; fainter light that
continues a detected line at its width and half its brightness is kept, hysteresis) and the dark
hole (negative residuals are ignored). Sub-pixel accuracy comes from intensity weights.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from labkit.vision.laser.disc_opening import open_by_disc
from labkit.vision.laser.window_centroids import BandLight, window_centroids
from labkit.vision.shared.opencv_threads import one_opencv_thread, precise_distance_transform


@dataclass
class TracePoints:
    """Trace pixels of one image: positions (N, 2) in full-frame px, weights, and levels."""

    points: np.ndarray
    weights: np.ndarray
    peak: float  # brightest residual above background (grey levels)
    noise: float  # robust noise of the residual (grey levels)
    band: np.ndarray | None = None  # every trace pixel (M, 2), not thinned
    band_weights: np.ndarray | None = None
    line_width_px: float = float("nan")  # full width of the band: twice its median half-width


def brightness(image: np.ndarray) -> np.ndarray:
    """Per-pixel brightest channel (any laser colour) as uint8."""
    if image.ndim == 2:
        return image
    b, g, r = cv2.split(image)
    return cv2.max(cv2.max(b, g), r)


def background(gray: np.ndarray, frame_px: int | None = None) -> np.ndarray:
    """Smooth background (screen light, gradients, lamps) as float32: a grey-scale opening with a
    disc of ~1/10 of the image size on a 4x reduced copy removes every bright structure narrower
    than that (trace lines, their halo, small loops) and keeps broad light and the dark hole."""
    return _background_levels(gray, frame_px).astype(np.float32)


def _background_levels(gray: np.ndarray, frame_px: int | None) -> np.ndarray:
    """:func:`background` in grey levels (uint8, a view of the full-size estimate)."""
    h, w = gray.shape
    # OpenCV reduces by exactly 4 several times faster than by 4.006: pad to a multiple of 4
    pad_h, pad_w = -h % 4, -w % 4
    if pad_h or pad_w:
        gray = cv2.copyMakeBorder(gray, 0, pad_h, 0, pad_w, cv2.BORDER_REPLICATE)
    sw, sh = gray.shape[1] // 4, gray.shape[0] // 4
    small = cv2.resize(gray, (sw, sh), interpolation=cv2.INTER_AREA)
    k = max(3, int(0.1 * (frame_px or max(h, w)) / 4) | 1)
    k = min(k, max(3, (min(sw, sh) - 1) | 1))
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))
    opened = open_by_disc(small, disc)
    opened = cv2.blur(opened, (max(1, k // 2), max(1, k // 2)))
    return cv2.resize(opened, (4 * sw, 4 * sh), interpolation=cv2.INTER_LINEAR)[:h, :w]


def residual(gray: np.ndarray, frame_px: int | None = None) -> np.ndarray:
    """``gray`` minus its :func:`background` as float32, in one pass: every value is an integer
    (a difference of two grey levels), exactly ``gray.astype(np.float32) - background(gray)``."""
    return cv2.subtract(gray, _background_levels(gray, frame_px), dtype=cv2.CV_32F)


def robust_noise(residual: np.ndarray, samples: int = 50000) -> float:
    """Noise level from the median absolute deviation of a sample of about ``samples`` pixels
    (1.4826 MAD)."""
    sample = residual.ravel()[:: max(1, residual.size // samples)]
    med = float(np.median(sample))
    return max(0.5, 1.4826 * float(np.median(np.abs(sample - med))))


def integer_noise(residual: np.ndarray, samples: int = 50000) -> float:
    """:func:`robust_noise` of a residual whose values are integers in [-255, 255] (a
    :func:`residual`), the same float, from a histogram of the sample instead of two sorts: both
    medians (an order statistic or the mean of two) are exact in float32 either way."""
    sample = residual.ravel()[:: max(1, residual.size // samples)]
    counts = np.bincount(sample.astype(np.intp) + 255, minlength=511)
    n = len(sample)
    med = _histogram_median(counts, n) - 255  # in grey levels; a half level when n is even
    # twice each deviation |v - med| is an integer: 2 |v - med| = |2 v - 2 med|
    doubled = np.abs(2 * np.arange(-255, 256) - round(2 * med))
    mad = _histogram_median(np.bincount(doubled, weights=counts, minlength=1022), n) / 2
    return max(0.5, 1.4826 * mad)


def _histogram_median(counts: np.ndarray, n: int) -> float:
    """``np.median`` of ``n`` integers given as ``counts[v]`` = how many equal ``v``."""
    cumulative = np.cumsum(counts)
    upper = int(np.searchsorted(cumulative, n // 2, side="right"))
    if n % 2:
        return float(upper)
    lower = int(np.searchsorted(cumulative, n // 2 - 1, side="right"))
    return (lower + upper) / 2


def contrast_to_noise(gray: np.ndarray, frame_px: int | None = None) -> float:
    """How far the brightest light stands above the background, in units of the noise: the
    smoothed peak residual over the robust noise, exactly as :func:`trace_points` scores light
    (its detection threshold is ``snr`` = 8 on this scale). ``gray``: one channel (H, W)."""
    with one_opencv_thread():
        res = residual(gray, frame_px)
        return float(cv2.GaussianBlur(res, (0, 0), 1.0).max()) / integer_noise(res)


def trace_points(image: np.ndarray, offset: tuple[int, int] = (0, 0), subpixel: bool = True,
                 snr: float = 8.0, relative_floor: float = 0.12, frame_px: int | None = None) -> TracePoints:
    """Centre-line points of the light trace in ``image`` (BGR or grey), plus every trace pixel.

    A pixel belongs to the trace when its smoothed residual above background is >= half of the
    local maximum within ``r`` px (r ~ 1 % of the frame size) and that local maximum exceeds
    ``snr`` times the noise and ``relative_floor`` times the global peak. Light whose local maximum
    is below that noise floor but above ``snr`` times the noise of the smoothed residual (the image
    the test is made on) is kept where it continues the detected light (:func:`_continued`):
    inside a dense pattern of fat saturated lines the background estimate is raised by the
    pattern's own glow, and the inner loops stand less than ``snr`` raw noise sigmas above it
    (the suite's 320x240 6-loop epitrochoid with a 12 px line: only the outer rim was found, and
    it read as an ellipse). The band is thinned to its centre line (:func:`_centreline`).
    Weights are residuals (sub-pixel) or 1. ``frame_px`` is the long side of the full frame when
    ``image`` is a region of interest (window sizes scale with it).
    """
    with one_opencv_thread():  # small images: the pool's splitting costs more CPU than it saves
        return _trace_points(brightness(image), offset, subpixel, snr, relative_floor, frame_px)


def _trace_points(gray: np.ndarray, offset: tuple[int, int], subpixel: bool, snr: float,
                  relative_floor: float, frame_px: int | None) -> TracePoints:
    res = residual(gray, frame_px)
    noise = integer_noise(res)
    smooth = cv2.GaussianBlur(res, (0, 0), 1.0)
    peak = float(smooth.max())
    empty = TracePoints(np.zeros((0, 2)), np.zeros(0), peak, noise)
    floor = max(snr * noise, relative_floor * peak)
    if peak <= snr * noise:
        return empty
    h, w = gray.shape
    r = max(5, int(round(0.01 * (frame_px or max(h, w)))))
    # light the noise floor misses may continue the trace: tested against the noise of the
    # smoothed image (only when the noise, not the peak, sets the floor)
    weak_floor = floor if floor <= relative_floor * peak else max(snr * robust_noise(smooth, 10000),
                                                                    relative_floor * peak)
    # the pixels cv2.threshold(smooth, t, 255, THRESH_BINARY) sets: above t rounded to float32
    bx, by, bw, bh = cv2.boundingRect((smooth > np.float32(min(floor, weak_floor))).view(np.uint8))
    if bw == 0 or bh == 0:
        return empty
    # only the bounding box of the light that may be trace matters (plus the window)
    x0, y0 = max(0, bx - r - 2), max(0, by - r - 2)
    x1, y1 = min(w, bx + bw + r + 2), min(h, by + bh + r + 2)
    smooth, res = smooth[y0:y1, x0:x1], res[y0:y1, x0:x1]
    local = cv2.dilate(smooth, np.ones((2 * r + 1, 2 * r + 1), np.uint8))  # square: separable, fast
    band = smooth >= local * 0.5
    band &= smooth > 0
    mask = band & (local >= floor)
    if weak_floor < floor:
        mask = _continued(mask, band & (local >= weak_floor), local)
    return _centreline(mask, res, (offset[0] + x0, offset[1] + y0), subpixel, peak, noise)


def _continued(strong: np.ndarray, weak: np.ndarray, local: np.ndarray) -> np.ndarray:
    """``strong`` light and the ``weak`` light that continues it (hysteresis). A continuation
    of a line looks like the line: weak light connected (8-neighbours) to strong light and at
    least half as bright (``local``: the local maximum) as the brightest strong light it is
    connected to, the half-maximum rule of the band itself (the faint skirt of a bright line's
    glow is not its continuation), and as wide: opened by a disc half as wide as the strong band
    (thinner strokes, such as a timestamp's characters, fall away)."""
    extra = np.flatnonzero(weak & ~strong)
    if len(extra) == 0:
        return strong
    count, labels = cv2.connectedComponents(weak.view(np.uint8), connectivity=8)
    brightest = np.full(count, np.inf, np.float32)  # inf: a component without strong light
    np.minimum.at(brightest, labels[strong], -np.inf)
    np.maximum.at(brightest, labels[strong], local[strong])
    extra = extra[local.ravel()[extra] >= 0.5 * brightest[labels.ravel()[extra]]]
    if len(extra) == 0:
        return strong
    fainter = np.zeros_like(strong)
    fainter.ravel()[extra] = True
    wide = cv2.morphologyEx((strong | fainter).view(np.uint8), cv2.MORPH_OPEN,
                            _disc(0.5 * _band_width(strong)))
    count, labels = cv2.connectedComponents(wide | strong.view(np.uint8), connectivity=8)
    seeded = np.zeros(count, bool)
    seeded[np.unique(labels[strong])] = True
    seeded[0] = False
    return seeded[labels]


def _band_width(mask: np.ndarray) -> float:
    """Full width (px) of a band: twice the median of its distance-transform ridge."""
    dist = cv2.distanceTransform(mask.view(np.uint8), cv2.DIST_L2, 3)
    ridge = (dist >= cv2.dilate(dist, np.ones((3, 3), np.uint8)) - 0.35) & (dist > 0)
    return 2.0 * float(np.median(dist[ridge])) if ridge.any() else 1.0


def _disc(diameter: float) -> np.ndarray:
    """A disc of about ``diameter`` px, odd-sized (an even kernel would shift an opening)."""
    d = max(1, int(round(diameter))) | 1
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (d, d))


def _centreline(mask: np.ndarray, res: np.ndarray, offset: tuple[int, int], subpixel: bool,
                peak: float, noise: float) -> TracePoints:
    """Thin the trace band to its centre line: ridge of the distance transform (the medial axis,
    insensitive to a saturated flat top), then optionally move each ridge pixel to the intensity
    centroid of a window as wide as the band (sub-pixel refinement)."""
    bx, by, bw, bh = cv2.boundingRect(mask.view(np.uint8))
    if bw == 0 or bh == 0:
        return TracePoints(np.zeros((0, 2)), np.zeros(0), peak, noise)
    # work inside the trace's bounding box (plus a margin for the windows)
    pad = 14
    x0, y0 = max(0, bx - pad), max(0, by - pad)
    x1, y1 = min(mask.shape[1], bx + bw + pad), min(mask.shape[0], by + bh + pad)
    mask, res = mask[y0:y1, x0:x1], res[y0:y1, x0:x1]
    offset = (offset[0] + x0, offset[1] + y0)
    dist = precise_distance_transform(mask.view(np.uint8))
    nearby = cv2.dilate(dist, np.ones((3, 3), np.uint8))
    np.subtract(nearby, 0.35, out=nearby)
    ridge = dist >= nearby
    ridge &= mask  # dist > 0
    ys, xs = _nonzero(ridge)
    if len(xs) == 0:
        return TracePoints(np.zeros((0, 2)), np.zeros(0), peak, noise)
    x, y = xs.astype(float), ys.astype(float)
    weights = np.ones(len(xs))
    half_width = float(np.median(dist[ys, xs]))
    bys, bxs = _nonzero(mask)
    light = res[bys, bxs]
    if subpixel:
        half = int(np.clip(half_width, 1, 12))
        x, y = window_centroids(BandLight(mask, bys, bxs, light), xs, ys, half)
        weights = np.clip(res[ys, xs], 1e-3, None).astype(float)
    pts = np.column_stack([x + offset[0], y + offset[1]])
    band = np.column_stack([bxs + offset[0], bys + offset[1]]).astype(float)
    band_w = np.clip(light, 1e-3, None).astype(float) if subpixel else np.ones(len(bxs))
    return TracePoints(pts, weights, peak, noise, band, band_w, 2.0 * half_width)


def _nonzero(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.nonzero`` of a boolean image (rows, columns in row-major order) through OpenCV, which
    scans a sparse mask several times faster."""
    found = cv2.findNonZero(mask.view(np.uint8))
    if found is None:
        return np.zeros(0, np.intp), np.zeros(0, np.intp)
    found = found.reshape(-1, 2)
    return found[:, 1].astype(np.intp), found[:, 0].astype(np.intp)


@dataclass
class Spot:
    """The light in one frame: intensity-weighted centroid (px) of the brightest blob."""

    x: float
    y: float
    peak: float
    area_px: int


def detect_spot(frame: np.ndarray) -> Spot | None:
    """Brightest blob in one frame, sub-pixel centroid by moments in a window around the maximum
    (per-frame detection for live overlays; the pattern fit uses accumulated trace points)."""
    gray = brightness(frame)
    _, vmax, _, (mx, my) = cv2.minMaxLoc(gray)
    h, w = gray.shape
    r = max(8, int(0.02 * max(h, w)))
    x0, y0 = max(0, mx - r), max(0, my - r)
    win = gray[y0:my + r + 1, x0:mx + r + 1].astype(np.float32)
    base = float(np.median(gray[:: max(1, h // 64), :: max(1, w // 64)]))
    if vmax - base < 20:
        return None
    wgt = np.clip(win - (base + 0.5 * (vmax - base)), 0, None)
    m = cv2.moments(wgt)
    if m["m00"] <= 0:
        return None
    return Spot(x0 + m["m10"] / m["m00"], y0 + m["m01"] / m["m00"], float(vmax), int(np.count_nonzero(wgt)))
