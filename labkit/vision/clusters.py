"""Light that is not the pattern: a timestamp burnt into the corner of every frame, a static stray
reflection beside the pattern, a bright screw in the frame. Trace extraction keeps any light
that stands out of the background; this module sets apart the light that lies away from the
pattern before the fit sees it.

The trace points are grouped by closeness (points within one and a half line widths belong
together: a pattern is one connected curve, or a few arcs broken by the screen's hole or by
short exposures that lie inside one region). The pattern is the group that is both long and wide
(largest number of points x diagonal of its bounding box: text is long but small, a reflection
small and short). Other groups most of whose points lie inside the pattern's convex hull (grown
by a few line widths) are kept as parts of it; the rest is left out and reported. Pure
functions.

The link distance and the hull were chosen from what the light looks like, in line widths: a
timestamp burnt in below a pattern lies 2-3 line widths from it on the suite's 320x240 clips
(its characters a fraction of a width apart), so a link of 3 widths joined it to the pattern;
and a pattern's bounding box grown by a quarter took in a timestamp along the frame's bottom
edge whenever the pattern came near it (up to 20 % of the trace points, which pulled the fit
hundreds of px off).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

LINK_WIDTHS = 1.5  # points closer than this many line widths belong to one group
HULL_MARGIN_WIDTHS = 3.0  # other groups count as pattern if they lie in its hull grown by this


@dataclass
class Separation:
    """``keep``: mask of the points that belong to the pattern; ``left_out_share``: share of the
    points left out; ``groups``: how many groups were left out; ``rival``: the largest left-out
    group's size (points x box diagonal) against the pattern's (1: as large)."""

    keep: np.ndarray
    left_out_share: float
    groups: int
    rival: float = 0.0


def separate_pattern(points: np.ndarray, line_width_px: float) -> Separation:
    """Split ``points`` (N, 2) into the pattern and light away from it (see module docstring)."""
    n = len(points)
    if n == 0:
        return Separation(np.zeros(0, bool), 0.0, 0, 0.0)
    link = max(2.0, LINK_WIDTHS * (line_width_px if math.isfinite(line_width_px) else 2.0))
    label, count = _linked_groups(points, link)
    if count <= 2:
        return Separation(np.ones(n, bool), 0.0, 0, 0.0)
    groups = [np.flatnonzero(label == j) for j in range(1, count)]
    groups = [g for g in groups if len(g)]

    def size(g: np.ndarray) -> float:
        span = points[g].max(axis=0) - points[g].min(axis=0)
        return len(g) * float(np.hypot(*span))

    main = max(groups, key=size)
    inside = _inside_grown_hull(points, points[main], HULL_MARGIN_WIDTHS * max(line_width_px, 2.0)
                                if math.isfinite(line_width_px) else 2 * HULL_MARGIN_WIDTHS)
    keep = np.zeros(n, bool)
    left, rival = 0, 0.0
    for g in groups:
        if g is main or float(np.mean(inside[g])) > 0.5:
            keep[g] = True
        else:
            left += 1
            rival = max(rival, size(g) / max(size(main), 1e-9))
    return Separation(keep, float(1.0 - keep.mean()), left, rival)


def _linked_groups(points: np.ndarray, link_px: float) -> tuple[np.ndarray, int]:
    """Label per point (1..) and the number of labels + 1: points closer than about ``link_px``
    share a label (each point's disc of radius ``link_px / 2`` is drawn on a raster of about
    1 px, coarser for a very large extent, and touching discs connect)."""
    origin = points.min(axis=0) - link_px
    step = max(1.0, float(max(points.max(axis=0) - origin)) / 4000)
    idx = np.round((points - origin) / step).astype(int)
    w, h = idx.max(axis=0) + int(math.ceil(link_px / step)) + 2
    grid = np.zeros((h, w), np.uint8)
    grid[idx[:, 1], idx[:, 0]] = 1
    r = max(1, int(round(0.5 * link_px / step)))
    grid = cv2.dilate(grid, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
    count, labels = cv2.connectedComponents(grid, connectivity=8)
    return labels[idx[:, 1], idx[:, 0]], count


def _inside_grown_hull(points: np.ndarray, hull_of: np.ndarray, margin_px: float) -> np.ndarray:
    """Mask of ``points`` that lie inside the convex hull of ``hull_of`` or within ``margin_px``
    of it (on a raster of about 1 px, or coarser for a very large extent)."""
    lo = np.minimum(points.min(axis=0), hull_of.min(axis=0)) - margin_px - 2
    hi = np.maximum(points.max(axis=0), hull_of.max(axis=0)) + margin_px + 2
    step = max(1.0, float(max(hi - lo)) / 4000)
    w, h = (np.ceil((hi - lo) / step).astype(int) + 1)
    mask = np.zeros((h, w), np.uint8)
    hull = cv2.convexHull(np.round((hull_of - lo) / step).astype(np.int32))
    cv2.fillConvexPoly(mask, hull, 1)
    r = max(1, int(round(margin_px / step)))
    mask = cv2.dilate(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1)))
    idx = np.clip(np.round((points - lo) / step).astype(int), 0, [w - 1, h - 1])
    return mask[idx[:, 1], idx[:, 0]].astype(bool)
