"""Light that is not the pattern: a timestamp burnt into the corner of every frame, a static stray
reflection beside the pattern, a bright screw in the frame. Trace extraction keeps any light
that stands out of the background; this module sets apart the light that lies away from the
pattern before the fit sees it.

The trace points are grouped by closeness: points within one and a half line widths belong
together (a pattern is one connected curve, or a few arcs broken by the screen's hole or by
short exposures). The pattern is the group that is both long and wide (largest number of points
x diagonal of its bounding box: text is long but small, a reflection small and short). Other
groups most of whose points lie inside the pattern's convex hull, grown by 1.5 line widths,
are kept as parts of it. With the points' weights given, groups left out are then checked
against the curve fitted to the light kept, and those lying on it are taken back (an arc on the
pattern's outer edge can stick out of the hull). The rest is left out and reported. Pure
functions.

The link distance and the hull were chosen from what the light looks like, in line widths: a
timestamp burnt in below a pattern lies 2-3 line widths from it on the suite's 320x240 clips
(its characters a fraction of a width apart), so the former link of 3 widths joined it to the
pattern; and the former rule, keeping groups whose centre lay in the largest group's bounding box
grown by a quarter, took in a timestamp along the frame's bottom edge whenever the pattern came
near it (up to 20 % of the trace points, which pulled the fit hundreds of px off).

What it cannot do: when a pattern is seen only as arcs that do not touch (very short exposures
at a frame rate commensurate with the pattern) and a timestamp is larger than every arc, the
timestamp is taken for the pattern. If the camera moved, the timestamp is the light that stayed
at the same pixels, and :func:`labkit.vision.laser.second_reading.without_fixed_light` leaves it out; with a
still camera the fit fails its checks and says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from labkit.vision.laser.nearest import PointTree

LINK_WIDTHS = 1.5  # points closer than this many line widths belong to one group
# a group inside the pattern's hull grown by this many line widths is kept, or within this many
# of the curve fitted to the rest: as far as the link (a stray reflection 2.5 widths beside a
# pattern was kept with 3 and read as the pattern's extent)
HULL_MARGIN_WIDTHS = LINK_WIDTHS
ON_CURVE_WIDTHS = LINK_WIDTHS


@dataclass
class Separation:
    """``keep``: mask of the points that belong to the pattern; ``left_out_share``: share of the
    points left out; ``groups``: how many groups were left out; ``rival``: the largest left-out
    group's size (points x box diagonal) against the largest kept group's (1: as large)."""

    keep: np.ndarray
    left_out_share: float
    groups: int
    rival: float = 0.0


def separate_pattern(points: np.ndarray, line_width_px: float, weights: np.ndarray | None = None,
                     times: np.ndarray | None = None) -> Separation:
    """Split ``points`` (N, 2) into the pattern and light away from it (see module docstring).
    With ``weights`` (and the points' ``times``, for a drifting centre), groups left out are
    then checked against the curve fitted to the groups kept (:func:`_on_the_curve`)."""
    n = len(points)
    if n == 0:
        return Separation(np.zeros(0, bool), 0.0, 0, 0.0)
    width = max(2.0, line_width_px if math.isfinite(line_width_px) else 2.0)
    label, count = linked_groups(points, LINK_WIDTHS * width)
    if count <= 2:
        return Separation(np.ones(n, bool), 0.0, 0, 0.0)
    groups = [g for g in (np.flatnonzero(label == j) for j in range(1, count)) if len(g)]
    sizes = [_size(points[g]) for g in groups]
    kept = _around_largest(points, groups, sizes, HULL_MARGIN_WIDTHS * width)
    keep = np.zeros(n, bool)
    for j in kept:
        keep[groups[j]] = True
    if weights is not None and not keep.all():
        on = _on_the_curve(points, weights, times, keep, width)
        for j, g in enumerate(groups):
            if j not in kept and float(np.mean(on[g])) > 0.5:
                keep[g] = True
                kept.add(j)
    out = [j for j in range(len(groups)) if j not in kept]
    largest = max(sizes[j] for j in kept)
    rival = max((sizes[j] / max(largest, 1e-9) for j in out), default=0.0)
    return Separation(keep, float(1.0 - keep.mean()), len(out), rival)


def _size(p: np.ndarray) -> float:
    """Number of points x diagonal of their bounding box."""
    return len(p) * float(np.hypot(*(p.max(axis=0) - p.min(axis=0))))


def _around_largest(points: np.ndarray, groups: list[np.ndarray], sizes: list[float],
                    margin_px: float) -> set[int]:
    """Indices of the groups kept: the largest group, and every group most of whose points lie
    inside its convex hull grown by ``margin_px``."""
    main = int(np.argmax(sizes))
    distance = _distance_outside(points[groups[main]])
    return {j for j, g in enumerate(groups)
            if j == main or float(np.mean(distance(points[g]) <= margin_px)) > 0.5}


def _distance_outside(hull_of: np.ndarray):
    """A function giving, for points ``p``, about how far each lies outside the convex hull of
    ``hull_of``: the largest signed distance to the hull's edge lines (<= 0 inside; exact along
    the edges, a little short beyond its corners). Points on a line: the distance from their
    segment."""
    corners = _hull(hull_of)
    if corners is not None:
        normal, offset = _edge_lines(corners)
        return lambda p: (p @ normal.T + offset).max(axis=1)
    centre = hull_of.mean(axis=0)
    d = hull_of - centre
    axis = np.linalg.svd(d, full_matrices=False)[2][0] if len(hull_of) > 1 else np.array([1.0, 0.0])
    lo, hi = (d @ axis).min(), (d @ axis).max()
    return lambda p: np.hypot(*(p - centre - np.clip((p - centre) @ axis, lo, hi)[:, None] * axis).T)


def _hull(p: np.ndarray) -> np.ndarray | None:
    """The corners of the convex hull of ``p`` in order (``cv2.convexHull``); None for fewer than
    3 corners or a hull of no area (points on a line)."""
    if len(p) < 3:
        return None
    corners = p[cv2.convexHull(p.astype(np.float32), returnPoints=False).ravel()]
    if len(corners) < 3:
        return None
    x, y = corners[:, 0], corners[:, 1]
    area = 0.5 * abs(float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)))
    extent = float(np.ptp(corners, axis=0).max())
    return corners if area > 1e-9 * max(extent, 1e-9) ** 2 else None


def _edge_lines(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Outward unit normals (m, 2) and offsets (m) of a convex polygon's edges: a point ``x`` is
    inside when ``normal . x + offset <= 0`` for every edge, and that largest value is its signed
    distance from the nearest edge line."""
    edge = np.roll(corners, -1, axis=0) - corners
    normal = np.column_stack([edge[:, 1], -edge[:, 0]])
    normal /= np.maximum(np.hypot(normal[:, 0], normal[:, 1]), 1e-300)[:, None]
    inward = np.sum(normal * (corners.mean(axis=0) - corners), axis=1) > 0
    normal[inward] *= -1.0
    return normal, -np.sum(normal * corners, axis=1)


def linked_groups(points: np.ndarray, link_px: float) -> tuple[np.ndarray, int]:
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


def _on_the_curve(points: np.ndarray, weights: np.ndarray, times: np.ndarray | None, keep: np.ndarray,
                  width: float) -> np.ndarray:
    """Mask of the points within ``ON_CURVE_WIDTHS`` line widths of the curve fitted to the points
    ``keep`` (with its drift at each point's time): arcs of the pattern that the hull missed lie
    on it, a timestamp or a reflection does not."""
    from labkit.vision.laser.pattern_fit import MIN_POINTS, classify
    from labkit.vision.laser.wander import dense_curve

    if keep.sum() < MIN_POINTS:
        return np.zeros(len(points), bool)
    cls = classify(points[keep], weights[keep], None if times is None else times[keep])
    fit = cls.best
    z = points[:, 0] + 1j * points[:, 1]
    if times is not None:
        z = z - fit.drift * (np.asarray(times, float) - cls.t_ref)
    curve, _ = dense_curve(fit, 0.5)
    d, _ = PointTree(curve).query(z)
    return d <= ON_CURVE_WIDTHS * width
