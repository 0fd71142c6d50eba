"""The floating body seen from the side: its silhouette as a pixel-coverage image.

A cylinder (``length`` along its dipole axis, ``width`` its diameter) seen side on is a rectangle.
A cuboid magnet with a square cross-section (``width`` x ``width``, ``length`` along the dipole
axis: a "cube" plate as in Fig. 6.20) spinning about its axis shows a rectangle whose width
breathes between ``width`` and ``width * sqrt(2)`` with the spin angle. Coverage is exact to the
supersampling: the outline is filled at ``SUPERSAMPLE`` times the resolution with sub-pixel
vertices and averaged back (area interpolation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

SUPERSAMPLE = 4
EDGE_INSET = 0.45  # fine pixels (see coverage)


@dataclass(frozen=True)
class Body:
    """``shape``: ``cylinder`` or ``cuboid``; ``length_px`` along the dipole axis; ``width_px``
    across it (diameter or side); ``spin_hz`` about the dipole axis (changes a cuboid's outline)."""

    shape: str = "cylinder"
    length_px: float = 60.0
    width_px: float = 30.0
    spin_hz: float = 0.0

    def apparent_width(self, t: float) -> float:
        if self.shape == "cylinder":
            return self.width_px
        s = 2 * math.pi * self.spin_hz * t
        return self.width_px * (abs(math.cos(s)) + abs(math.sin(s)))

    @property
    def radius_px(self) -> float:
        """Radius of a circle that holds the outline in any pose."""
        return 0.5 * math.hypot(self.length_px, self.width_px * math.sqrt(2))


def outline(centre: tuple[float, float], axis_deg: float, length: float, width: float) -> np.ndarray:
    """Rectangle corners (4, 2) px: ``axis_deg`` is the body axis from image-up towards +x."""
    a = math.radians(axis_deg)
    u = np.array([math.sin(a), -math.cos(a)])  # along the axis (image up at 0 deg)
    v = np.array([math.cos(a), math.sin(a)])  # across
    c = np.asarray(centre, float)
    hl, hw = length / 2, width / 2
    return np.array([c + hl * u + hw * v, c + hl * u - hw * v, c - hl * u - hw * v, c - hl * u + hw * v])


def coverage(corners: np.ndarray, roi: tuple[int, int, int, int]) -> np.ndarray:
    """Fraction of each pixel of ``roi`` (x0, y0, w, h) covered by the rectangle with ``corners``
    as :func:`outline` gives them (float32). OpenCV's fill includes the pixels its edges touch,
    which on the finer grid grows the area by about half a fine pixel all round; the edges are
    moved in by that much first (measured: area within 0.5 %). Edges snap to the finer grid, so
    the centroid is within ``0.5 / SUPERSAMPLE`` px."""
    x0, y0, w, h = roi
    s = SUPERSAMPLE
    along, across = corners[0] - corners[3], corners[0] - corners[1]
    inset = EDGE_INSET / s
    along = along / max(np.linalg.norm(along), 1e-12) * inset
    across = across / max(np.linalg.norm(across), 1e-12) * inset
    signs = np.array([[1, 1], [1, -1], [-1, -1], [-1, 1]], float)
    inner = corners - signs[:, :1] * along - signs[:, 1:] * across
    big = np.zeros((h * s, w * s), np.uint8)
    # pixel centres at integer coordinates, here and in OpenCV's fill on the finer grid
    pts = np.round((((inner - [x0, y0]) + 0.5) * s - 0.5) * 16).astype(np.int32)
    cv2.fillPoly(big, [pts], 255, cv2.LINE_8, 4)
    return cv2.resize(big.astype(np.float32) / 255.0, (w, h), interpolation=cv2.INTER_AREA)
