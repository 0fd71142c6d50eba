"""Light that is not the pattern: a timestamp burnt into the corner of every frame, a static stray
reflection beside the pattern, a bright screw in the frame. Trace extraction keeps any light
that stands out of the background; this module sets apart the light that lies away from the
pattern before the fit sees it.

The trace points are grouped by closeness (points within a few line widths belong together: a
pattern is one connected curve, or a few arcs broken by the screen's hole or by short exposures
that lie inside one region). The pattern is the group that is both long and wide (largest
number of points x diagonal of its bounding box: text is long but small, a reflection small
and short). Other groups whose centre lies inside the pattern's box (grown by a quarter of its
size) are kept as parts of it; the rest is left out and reported. Pure functions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

LINK_WIDTHS = 3.0  # points closer than this many line widths belong to one group
GROW = 0.25  # other groups count as pattern if their centre lies in its box grown by this share


@dataclass
class Separation:
    """``keep``: mask of the points that belong to the pattern; ``left_out_share``: share of the
    points left out; ``groups``: how many groups were left out; ``rival``: the largest left-out
    group's size (points x box diagonal) against the pattern's (1: as large)."""

    keep: np.ndarray
    left_out_share: float
    groups: int
    rival: float = 0.0


def separate_pattern(points: np.ndarray, line_width_px: float, grow: float = GROW) -> Separation:
    """Split ``points`` (N, 2) into the pattern and light away from it (see module docstring;
    ``grow``: the share by which the pattern's box is grown, ``GROW`` unless given)."""
    n = len(points)
    if n == 0:
        return Separation(np.zeros(0, bool), 0.0, 0, 0.0)
    cell = max(2.0, LINK_WIDTHS * (line_width_px if math.isfinite(line_width_px) else 2.0)) / 2
    origin = points.min(axis=0)
    idx = np.floor((points - origin) / cell).astype(int)
    w, h = idx.max(axis=0) + 3
    grid = np.zeros((h, w), np.uint8)
    grid[idx[:, 1] + 1, idx[:, 0] + 1] = 1
    grid = cv2.dilate(grid, np.ones((3, 3), np.uint8))
    count, labels = cv2.connectedComponents(grid, connectivity=8)
    label = labels[idx[:, 1] + 1, idx[:, 0] + 1]
    if count <= 2:
        return Separation(np.ones(n, bool), 0.0, 0, 0.0)
    groups = [np.flatnonzero(label == j) for j in range(1, count)]
    groups = [g for g in groups if len(g)]

    def size(g: np.ndarray) -> float:
        span = points[g].max(axis=0) - points[g].min(axis=0)
        return len(g) * float(np.hypot(*span))

    main = max(groups, key=size)
    lo, hi = points[main].min(axis=0), points[main].max(axis=0)
    margin = grow * (hi - lo)
    keep = np.zeros(n, bool)
    left, rival = 0, 0.0
    for g in groups:
        centre = points[g].mean(axis=0)
        if g is main or bool(np.all((centre >= lo - margin) & (centre <= hi + margin))):
            keep[g] = True
        else:
            left += 1
            rival = max(rival, size(g) / max(size(main), 1e-9))
    return Separation(keep, float(1.0 - keep.mean()), left, rival)
