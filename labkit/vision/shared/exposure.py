"""Refusing footage that shows nothing: all-black or all-white (saturated) frames, judged from
histograms of the accumulated chunks (:mod:`labkit.vision.laser.analyse`). Pure functions."""

from __future__ import annotations

import math

import numpy as np

from labkit.errors import VideoError


def grey_histogram(image: np.ndarray) -> np.ndarray:
    """256-bin histogram of about 200 000 evenly spaced samples of an accumulated chunk."""
    return np.bincount(image.ravel()[:: max(1, image.size // 200000)], minlength=256)


def check_exposure(counts: np.ndarray, name: str, black_white: tuple[float, float] = (0.0, 255.0)) -> None:
    """Refuse all-black or all-white footage from the chunks' summed :func:`grey_histogram`;
    ``black_white``: the frames' black and white levels (16, 235 for a studio-range luma plane),
    mapped to 0-255 first."""
    black, white = black_white

    def level(grey: float) -> float:
        return (grey - black) * (255.0 / (white - black))

    brightest = level(float(np.flatnonzero(counts)[-1]))
    if brightest < 16:
        raise VideoError(name, f"all frames are black (brightest grey level {int(brightest)})")
    if level(_percentile_of_histogram(counts, 5.0)) > 245:
        raise VideoError(name, "all frames are white (saturated); reduce exposure or gain")


def _percentile_of_histogram(counts: np.ndarray, q: float) -> float:
    """``np.percentile(values, q)`` (linear interpolation) of the integer values whose histogram
    is ``counts``, without sorting them: the sorted values at the two neighbouring ranks are read
    off the cumulative counts (a level map is affine, so it commutes with the interpolation)."""
    cumulative = np.cumsum(counts)
    rank = q / 100.0 * (int(cumulative[-1]) - 1)
    lo = math.floor(rank)
    v_lo, v_hi = np.searchsorted(cumulative, [lo, min(lo + 1, int(cumulative[-1]) - 1)], side="right")
    return float(v_lo + (rank - lo) * (v_hi - v_lo))
