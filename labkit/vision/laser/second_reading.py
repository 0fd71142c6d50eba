"""Second readings of a laser trace whose first fit is not ``ok`` (docs/explanation/laser-analysis.md, steps
4-5).

The first fit takes all the light of the whole clip at once. Three things mislead it by design
rather than by degree, and each has a second reading that the analysis tries only when the
first is not ``ok``, keeping it only if its verdict is better:

* light away from the pattern (a burnt-in timestamp, a stray reflection):
  :func:`without_stray_light` sets it apart (:mod:`labkit.vision.laser.stray_light`);
* light fixed in the frame while the pattern moves: a camera that moves against the screen
  moves everything on the screen in its frames, so light that stays at the same pixels all
  through the clip (a burnt-in timestamp, a mark on the sensor) is not on the screen.
  :func:`without_fixed_light` leaves it out; the reading counts only if the pattern fitted to
  the rest did move, by more than a line width (:func:`pattern_moved_px`). The stray-light
  reading cannot do this when the pattern is seen only as separate arcs and the timestamp is
  larger than every arc: it then takes the timestamp for the pattern;
* a camera that wanders by many line widths: the accumulated trace is a blurred band that no
  curve fits, while each time chunk on its own is sharp. :func:`one_chunk_start` classifies the
  chunk with the most light alone; the fit then starts from it and follows the wander chunk by
  chunk (:mod:`labkit.vision.laser.wander`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from labkit.vision.laser.nearest import PointTree
from labkit.vision.laser.pattern_fit import MIN_POINTS, Classification, classify
from labkit.vision.laser.stray_light import LINK_WIDTHS, linked_groups, separate_pattern


def without_stray_light(points: np.ndarray, weights: np.ndarray, times: np.ndarray, band: tuple | None,
                        width: float) -> tuple:
    """The trace without light away from the pattern: points, weights, times, band (its pixels
    near a kept point), and ``(share, rival)``: the share of points left out (0: nothing was) and
    the largest left-out group's size against the pattern's
    (:class:`labkit.vision.laser.stray_light.Separation`)."""
    sep = separate_pattern(points, width, weights, times)
    if sep.groups == 0:
        return points, weights, times, band, (0.0, 0.0)
    kept = points[sep.keep]
    if band is not None:
        near, _ = PointTree(kept).query(band[0], distance_upper_bound=LINK_WIDTHS * max(width, 2.0))
        inside = np.isfinite(near)
        band = tuple(None if part is None else np.asarray(part)[inside] for part in band)
    return kept, weights[sep.keep], times[sep.keep], band, (sep.left_out_share, sep.rival)


def one_chunk_start(points: np.ndarray, weights: np.ndarray,
                    times: np.ndarray | None) -> Classification | None:
    """The classification of the time chunk with the most trace points, alone (no drift within
    it), referred to that chunk's time; None for fewer than 3 chunks."""
    if times is None:
        return None
    mids, counts = np.unique(times, return_counts=True)
    if len(mids) < 3 or counts.max() < 10 * MIN_POINTS:
        return None
    chunk = mids[int(np.argmax(counts))]
    sel = times == chunk
    return replace(classify(points[sel], weights[sel], None), t_ref=float(chunk))


# light at the same place in every time chunk, to within the pixel grid, is fixed in the frame
FIXED_PX = 1.0


def fixed_in_frame(points: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Mask of the points with light of every time chunk within ``FIXED_PX``: light at the same
    place in the frame all through the clip (all False for fewer than 3 chunks)."""
    mids = np.unique(times)
    fixed = np.full(len(points), len(mids) >= 3)
    for mid in mids if fixed.any() else ():
        near, _ = PointTree(points[times == mid]).query(points, distance_upper_bound=2 * FIXED_PX)
        fixed &= near <= FIXED_PX
    return fixed


def without_fixed_light(points: np.ndarray, weights: np.ndarray, times: np.ndarray, band: tuple | None,
                        width: float) -> tuple | None:
    """The trace without the light fixed in the frame: points, weights, times, band (its pixels
    near a kept point) and the share of points left out; None when there is none, or too little
    light is left. Light is taken in groups linked as :mod:`labkit.vision.laser.stray_light` links them,
    and a group most of whose points are :func:`fixed_in_frame` is left out whole: a timestamp's
    changing digits sit among its fixed characters."""
    fixed = fixed_in_frame(points, times)
    if not fixed.any():
        return None
    label, count = linked_groups(points, LINK_WIDTHS * max(width, 2.0))
    fixed_share = np.bincount(label, weights=fixed, minlength=count) / np.maximum(
        np.bincount(label, minlength=count), 1)
    keep = fixed_share[label] <= 0.5
    if keep.all() or keep.sum() < 10 * MIN_POINTS:
        return None
    kept = points[keep]
    if band is not None:
        near, _ = PointTree(kept).query(band[0], distance_upper_bound=LINK_WIDTHS * max(width, 2.0))
        inside = np.isfinite(near)
        band = tuple(None if part is None else np.asarray(part)[inside] for part in band)
    return kept, weights[keep], times[keep], band, float(1.0 - keep.mean())


def pattern_moved_px(diag: dict, times: np.ndarray) -> float:
    """How far the fitted pattern's centre moved over the clip (px): the largest distance between
    its positions at the chunks' mid times, from the fitted drift and wander of ``diag``."""
    mids = np.unique(times)
    drift = complex(*diag["drift_px_s"])
    offsets = (diag.get("wander_px") or {}).get("chunk_offsets") or []
    extra = np.array([complex(*o) for o in offsets]) if len(offsets) == len(mids) else 0j
    where = drift * mids + extra
    return float(np.abs(where[:, None] - where[None, :]).max()) if len(mids) else 0.0
