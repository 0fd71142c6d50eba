"""Second readings of a laser trace whose first fit is not ``ok`` (docs/vision.md, steps 4-5).

The first fit takes all the light of the whole clip at once. Two things mislead it by design
rather than by degree, and each has a second reading that the analysis tries only when the
first is not ``ok``, keeping it only if its verdict is better:

* light away from the pattern (a burnt-in timestamp, a stray reflection):
  :func:`without_stray_light` sets it apart (:mod:`labkit.vision.clusters`);
* a camera that wanders by many line widths: the accumulated trace is a blurred band that no
  curve fits, while each time chunk on its own is sharp. :func:`one_chunk_start` classifies the
  chunk with the most light alone; the fit then starts from it and follows the wander chunk by
  chunk (:mod:`labkit.vision.wander`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from labkit.vision.clusters import LINK_WIDTHS, separate_pattern
from labkit.vision.fit import MIN_POINTS, Classification, classify
from labkit.vision.nearest import PointTree


def without_stray_light(points: np.ndarray, weights: np.ndarray, times: np.ndarray, band: tuple | None,
                        width: float) -> tuple:
    """The trace without light away from the pattern: points, weights, times, band (its pixels
    near a kept point), and ``(share, rival)``: the share of points left out (0: nothing was) and
    the largest left-out group's size against the pattern's (:class:`labkit.vision.clusters.Separation`)."""
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
