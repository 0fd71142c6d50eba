"""Sub-pixel refinement of the trace's centre line: the intensity centroid of a square window
around each ridge pixel, on the light of the trace band (zero off the band).

The band is a thin curve in its bounding box (about 4 % of it at 720p), so the windows' row sums
are read from the band's pixels alone: prefix sums along the band in row-major order, each window
row a range of them, found from the integral image of the band's mask. Every sum of integer light
is exact that way, as it is in the two horizontal box filters over the whole box that
:func:`dense_window_centroids` runs, so both give the same centroids bit for bit
(``tests/vision/test_trace_exact.py``); light that is not integer goes the dense way.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class BandLight:
    """Light on a band of pixels and none elsewhere: ``mask`` (bool image) marks the band,
    ``rows``, ``cols`` list its pixels in row-major order (``np.nonzero(mask)``) and ``values``
    (float32) their light."""

    mask: np.ndarray
    rows: np.ndarray
    cols: np.ndarray
    values: np.ndarray

    def dense(self) -> np.ndarray:
        """The whole image (float32)."""
        image = np.zeros(self.mask.shape, np.float32)
        image[self.rows, self.cols] = self.values
        return image


def window_centroids(light: BandLight, xs: np.ndarray, ys: np.ndarray,
                     half: int) -> tuple[np.ndarray, np.ndarray]:
    """Intensity centroid of the ``(2 half + 1)^2`` window of ``light`` around each pixel
    ``(xs, ys)``; light outside the image counts as none, and a pixel whose window holds no light
    keeps its own position. Only the asked-for windows add their rows up."""
    if not np.array_equal(light.values, np.round(light.values)):
        return dense_window_centroids(light.dense(), xs, ys, half)
    height, width = light.mask.shape
    rows = ys[:, None] + np.arange(-half, half + 1)[None, :]
    inside = (rows >= 0) & (rows < height)
    rows_in = np.clip(rows, 0, height - 1)
    # band pixels of window row (r, a..b): from row r's first one, skip those of row r left of a
    # (counts in row r: differences of the integral image's rows r and r + 1), up to b
    counts = cv2.integral(light.mask.view(np.uint8)).ravel()
    row_first = np.searchsorted(light.rows, np.arange(height))[rows_in]
    top = rows_in * (width + 1)
    left = np.maximum(xs - half, 0)[:, None]
    right = np.minimum(xs + half, width - 1)[:, None] + 1
    start = row_first + counts[top + width + 1 + left] - counts[top + left]
    stop = row_first + counts[top + width + 1 + right] - counts[top + right]
    # float32 light times float32 column, as the dense image's product; sums of integers: exact
    moments = light.values * light.cols.astype(np.float32)
    row_sum = _window_sums(light.values, start, stop)
    row_moment = _window_sums(moments, start, stop)
    return _centroids(row_sum, row_moment, rows, inside, xs, ys)


def _window_sums(values: np.ndarray, start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Sums of ``values[start:stop]`` (float32 of the exact float64 sum, as a box filter's)."""
    prefix = np.concatenate([[0.0], np.cumsum(values, dtype=np.float64)])
    return (prefix[stop] - prefix[start]).astype(np.float32)


def dense_window_centroids(weights: np.ndarray, xs: np.ndarray, ys: np.ndarray,
                           half: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`window_centroids` of a whole image ``weights`` (float32): row sums of every window
    from two horizontal box filters, read at the asked-for windows."""
    k = 2 * half + 1
    columns = np.arange(weights.shape[1], dtype=np.float32)[None, :]
    row_sum = cv2.boxFilter(weights, -1, (k, 1), normalize=False, borderType=cv2.BORDER_CONSTANT)
    row_moment = cv2.boxFilter(weights * columns, -1, (k, 1), normalize=False, borderType=cv2.BORDER_CONSTANT)
    rows = ys[:, None] + np.arange(-half, half + 1)[None, :]
    inside = (rows >= 0) & (rows < weights.shape[0])
    rows_in, cols = np.clip(rows, 0, weights.shape[0] - 1), xs[:, None]
    return _centroids(row_sum[rows_in, cols], row_moment[rows_in, cols], rows, inside, xs, ys)


def _centroids(row_sum: np.ndarray, row_moment: np.ndarray, rows: np.ndarray, inside: np.ndarray,
               xs: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centroids from each window's row sums and first moments in x (N, 2 half + 1; float32)."""
    r0 = np.where(inside, row_sum, 0.0)
    s0 = r0.sum(axis=1)
    sx = np.where(inside, row_moment, 0.0).sum(axis=1)
    sy = (r0 * rows).sum(axis=1)
    ok = s0 > 0
    x, y = xs.astype(float), ys.astype(float)
    x[ok], y[ok] = sx[ok] / s0[ok], sy[ok] / s0[ok]
    return x, y
